// The metal fraction follows the points that the solid moves, in a run
// without the melt flow (tests/solid_moves_alpha.prm: a solid block falls
// freely by about three cells under gravity, temperature frozen). Only the
// solid moves points across cells there, so alpha is renewed only if the
// keeper of alpha (PointHeatExchange::follow_points()) sees the solid's
// moves. Checks at the end of the run: the block's points fell by
// g t^2 / 2 (so they crossed cells), and the metal fraction the run holds
// (the heat module's, which the output and the heat equation read) equals
// the one computed afresh from the points where they are now. Runs on 1
// and 2 ranks with the same output.
#include <femp/app/femp_problem.h>

#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  try
    {
      constexpr int    dim = 2;
      ParameterHandler prm;
      parse_scene(prm, argv[1], {});
      // The run's log to scene.log (std::cout back on every exit).
      std::ofstream log("scene.log");
      struct Redirect
      {
        std::streambuf *old;
        ~Redirect()
        {
          std::cout.rdbuf(old);
        }
      } redirect{std::cout.rdbuf(log.rdbuf())};
      femp::FempProblem<dim> problem(prm, comm);
      problem.run();
      std::cout.rdbuf(redirect.old);

      // The block's points (above the substrate top, 12 um): their mean
      // height against the free fall from 46 um.
      const auto &points = problem.material_points();
      double      sum[2] = {0, 0};
      for (const auto &p : points.particle_handler())
        if (p.get_location()[dim - 1] > 16e-6)
          sum[0] += p.get_location()[dim - 1], sum[1] += 1;
      Utilities::MPI::sum(ArrayView<const double>(sum, 2),
                          comm,
                          ArrayView<double>(sum, 2));
      const double t    = problem.summary().time;
      const double fall = 0.5 * 1e5 * t * t;
      checks.print("block points", sum[1], 4);
      checks.print("free fall (cells of 4 um)", std::round(fall / 4e-6), 3);
      checks.at_most("error of the block's fall / free fall",
                     std::abs(46e-6 - sum[0] / sum[1] - fall) / fall,
                     0.01);

      // The run's alpha against alpha from the points where they are.
      const auto &alpha = problem.heat_transfer().metal_fraction();
      const auto  fresh = points.metal_fraction();
      double      diff  = 0;
      for (std::size_t i = 0; i < alpha.size(); ++i)
        diff = std::max(diff, std::abs(alpha[i] - fresh[i]));
      diff = Utilities::MPI::max(diff, comm);
      checks.at_most("max |alpha of the run - alpha of the points|",
                     diff,
                     1e-12);
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
