// Stability: an explicit temperature step above its stable limit must stop
// the run with a diagnostic, even when the latent heat keeps the unstable
// solution finite (doc/stability.md). The two-phase Stefan strip of
// stefan_two_phase.cc (h = 0.02, two cells wide, so that its own limit is
// twice the limit femp computes for the plane) is advanced to t = 1 with a
// step of C times femp's limit, C = 1, 2, 2.5, 3, 4, forced past femp's own
// refusal by calling HeatTransfer directly. Expected: C <= 2 run to the end
// undetected (they are stable); C = 2.5 is stopped by the maximum-principle
// check (without it the run ends normally with a bounded, wrong
// checkerboard); C >= 3 are stopped by the maximum-principle check before
// the temperature becomes non-finite.
#include <femp/base/collective_error.h>

#include <iostream>

#include "test_tools.h"

using namespace femp_test;

namespace
{
  /// Advance the strip with C x the stable step; "none" or the check that
  /// stopped it.
  std::string
  run_strip(const double C, MPI_Comm comm, double &t_stop)
  {
    const int    dim = 2;
    const double h = 0.02, Tm = 10;
    const auto   gp = box<dim>(Point<dim>(0, 0), Point<dim>(3, 2 * h), h);
    BackgroundGrid<dim> grid(gp, comm);
    grid.create();
    Material mat           = unit_material();
    mat.solidus            = Tm - 0.005;
    mat.liquidus           = Tm + 0.005;
    mat.latent_heat_fusion = 1;
    Laser<dim> laser(laser_off<dim>());
    auto p = heat_parameters<dim>(Tm - 1, {{"x-", Tm + 1}, {"x+", Tm - 1}});
    p.reference_temperature = Tm - 1;
    HeatTransfer<dim> heat(p, mat, laser, grid);
    heat.initialize();
    heat.set_metal_fraction(grid.make_field(1.));
    const double dt = C * heat.stable_time_step();
    double       t  = 0;
    try
      {
        while (t < 1 - 1e-12)
          {
            const double size = std::min(dt, 1 - t);
            heat.advance(size, t);
            t += size;
          }
      }
    catch (const femp::CollectiveError &e)
      {
        t_stop              = t;
        const std::string m = e.what();
        if (m.find("maximum principle") != std::string::npos &&
            m.find("cell at (") != std::string::npos &&
            m.find("Safety factor") != std::string::npos)
          return "maximum principle";
        if (m.find("non-finite") != std::string::npos)
          return "non-finite";
        return "other: " + m;
      }
    t_stop = t;
    return "none";
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  for (const double C : {1., 2., 2.5, 3., 4.})
    {
      double            t_stop   = 0;
      const std::string how      = run_strip(C, comm, t_stop);
      const std::string expected = C <= 2 ? "none" : "maximum principle";
      const bool        ok       = how == expected;
      if (Utilities::MPI::this_mpi_process(comm) == 0)
        std::cout << "step " << C << " x limit: stopped by " << how
                  << " (expected " << expected << ") " << (ok ? "ok" : "FAILED")
                  << std::endl;
      std::ostringstream label;
      label << "step " << C << " x limit:";
      checks.at_most(label.str() + " wrong detection", ok ? 0. : 1., 0.);
      if (C > 2)
        checks.at_most(label.str() + " stopped at t", t_stop, 0.25);
    }
  return checks.exit_code();
}
