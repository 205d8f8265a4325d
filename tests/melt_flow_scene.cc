// Melt flow through FempProblem (step 3 of the macro step): the 2D powder
// bed of mpi_consistency.prm melted by a line scan, with gravity, viscosity,
// Darcy damping, surface tension and Marangoni stress. Checks that the
// coupled run completes, that the melt moves (Marangoni-driven speeds of the
// order of 0.1-10 m/s) and prints rounded global results; ctest compares the
// 1-rank and the 2-rank output with the same expected file.
#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  const auto                       s = run_scene<2>(argv[1], comm);
  checks.print("temperature steps", s.steps, 8);
  checks.print("material points", s.n_points, 10);
  checks.print("melt pool length (um)",
               std::round(s.pool.length * 1e7) / 10,
               4);
  checks.print("melt pool depth (um)", std::round(s.pool.depth * 1e7) / 10, 4);
  checks.print("peak temperature (K)", std::round(s.T_max), 5);
  checks.in_range("max fluid speed at the end (m/s)",
                  std::round(s.max_fluid_speed * 100) / 100,
                  0.1,
                  10);
  checks.in_range("fluid steps", s.flow_steps, s.steps, 100 * s.steps);
  return checks.exit_code();
}
