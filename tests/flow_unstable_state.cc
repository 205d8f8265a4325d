// Melt flow, run-time detection of a state that has gone wrong (doc/
// stability.md, "Limits and detection"): in a small 2D drop (R = 0.25 m,
// h = R/8, sigma = 1 N/m, mu = 0.5 Pa s) one material point's velocity is
// set to
//   nan:  NaN, which must stop the next step with "non-finite velocity"
//         and the position of the grid node;
//   fast: 1e30 m/s, which no halving of the step can keep within a cell,
//         so the step rejection must give up after 20 halvings and stop.
// Both are errors that every rank meets (CollectiveError): on 2 ranks the
// point is changed on rank 0 only and both ranks must stop together.
#include <femp/base/collective_error.h>

#include "flow_tools.h"

using namespace femp_test;

namespace
{
  constexpr int dim = 2;

  void
  run(const std::string &what,
      const double       value,
      const std::string &expect,
      Checks            &checks,
      MPI_Comm           comm)
  {
    typename IncompressibleFlow<dim>::Parameters prm;
    prm.viscosity       = 0.5;
    prm.gravity         = Tensor<1, dim>();
    prm.surface_tension = 1;
    const double     R = 0.25, h = R / 8;
    const Point<dim> centre(0.5, 0.5);
    FlowScene<dim>   scene(
      Point<dim>(1, 1),
      h,
      1000,
      [&](const Point<dim> &x) { return x.distance(centre) < R; },
      prm,
      comm);
    const double dt = scene.flow->stable_time_step().min();
    for (int n = 0; n < 3; ++n)
      scene.flow->step(dt);
    if (Utilities::MPI::this_mpi_process(comm) == 0)
      {
        auto p = scene.points->particle_handler().begin();
        if (p != scene.points->particle_handler().end())
          p->get_properties()[MaterialPoints<dim>::PropertyIndex::velocity] =
            value;
      }
    bool        collective = false, stopped = false;
    std::string message;
    try
      {
        for (int n = 0; n < 3; ++n)
          scene.flow->step(dt);
      }
    catch (const CollectiveError &e)
      {
        stopped = collective = true;
        message              = e.what();
      }
    catch (const std::exception &e)
      {
        stopped = true;
        message = e.what();
      }
    checks.print("case " + what + ", one point's velocity changed", 1);
    checks.in_range("stopped by an error every rank meets", collective, 1, 1);
    checks.in_range("message says '" + expect + "'",
                    stopped && message.find(expect) != std::string::npos,
                    1,
                    1);
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  run("nan",
      std::numeric_limits<double>::quiet_NaN(),
      "non-finite velocity",
      checks,
      comm);
  run("fast", 1e30, "after halving the step 20 times", checks, comm);
  return checks.exit_code();
}
