// Melt flow through a scene file: prm/hydrostatic_pool.prm (a liquid pool
// placed by 'Material points/Initial bodies', gravity, isothermal heat
// transfer) run by FempProblem for 1 ms instead of 5 ms. The pool must stay
// at rest: max point speed / (g t) at round-off (tolerance 1e-9, as in
// tests/hydrostatic_pool.cc); prints the fluid steps and the step report.
// 1 and 2 ranks give the same output.
#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  const double                     end_time = 1e-3, g = 9.81;
  const auto                       s = run_scene<2>(argv[1],
                              comm,
                              {{"Time stepping", "End time", "1e-3"},
                                                     {"Output", "Directory", "output"},
                                                     {"Output", "Write material points", "never"}});
  checks.print("temperature steps", s.steps, 8);
  checks.print("material points", s.n_points, 10);
  checks.print("fluid steps", s.flow_steps, 8);
  const auto &l = s.flow_limits;
  checks.print("convective limit (s)", l.convective, 4);
  checks.print("sub-steps governed by the convective limit", l.governed[0], 8);
  checks.print("sub-steps per temperature step, max", l.max_substeps, 4);
  // Round-off level, printed as the next power of ten (stable in numdiff).
  const double v = s.max_fluid_speed / (g * end_time);
  checks.at_most("max point speed / (g t), next power of ten",
                 v > 0 ? std::pow(10., std::ceil(std::log10(v))) : 0.,
                 1e-9);
  return checks.exit_code();
}
