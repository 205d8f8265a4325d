// The same scene on 1 and 2 MPI ranks must give the same answer to
// round-off: this program runs tests/mpi_consistency.prm (2D powder bed,
// melting, all losses) and prints rounded global results; ctest compares the
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
  checks.print("steps", s.steps, 8);
  checks.print("material points", s.n_points, 10);
  checks.print("peak temperature (K)", s.T_max, 8);
  checks.print("melt pool length (m)", s.pool.length, 8);
  checks.print("melt pool depth (m)", s.pool.depth, 8);
  checks.print("laser energy (J/m)", s.laser, 8);
  checks.print("stored enthalpy change (J/m)", s.stored, 8);
  checks.print("surface losses (J/m)", s.losses, 8);
  checks.print("mean point temperature (K)", s.point_T_mean, 8);
  // Also read back the probe line file written by rank 0.
  std::ifstream line("output/probe_line_AB_00001.csv");
  std::string   row, last;
  while (std::getline(line, row))
    last = row;
  if (Utilities::MPI::this_mpi_process(comm) == 0)
    std::cout << "last probe row: " << last << std::endl;
  return checks.exit_code();
}
