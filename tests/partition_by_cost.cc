// 'Background grid/Partition' (doc/performance.md, "Balancing the ranks")
// on the short coupled track of tests/cooling_step.prm (melt flow, solid by
// MPM above an FE zone), on 2 ranks:
//   1. The share of the MPM points on the busiest rank, printed by the scene
//      at its start: with 'cost' within 5 % of an even split, and below the
//      share that 'cells' (equal numbers of cells) leaves.
//   2. The same answer either way: T and sigma_xx on the probe lines CD
//      (material points) and EF (finite elements) after 12 us agree within
//      1e-6 of their peaks (the partitions differ in the order of sums and
//      in the flow's pressure solve, converged to its tolerance; below
//      1e-6 the regression output's absolute tolerance takes the printed
//      values as equal).
//   3. A checkpoint written with 'cells' resumed with 'cost' (every point
//      on another rank than the one that wrote it may be met): the run
//      goes on (it used to stop with "material point(s) lost in the gather
//      of the solid points") and ends with the straight 'cost' run's lines
//      within the same 1e-6.
#include <regex>

#include "resume_tools.h"
#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

namespace
{
  /// Share of the MPM points on the busiest rank, from the scene's log
  /// (rank 0 writes it; broadcast by a maximum).
  double
  busiest_share(MPI_Comm comm)
  {
    double           share = 0;
    std::ifstream    log("scene.log");
    const std::regex at_most("solid: [0-9]+ material points \\(at most "
                             "([0-9.]+) % on one rank\\)");
    std::smatch      m;
    for (std::string line; std::getline(log, line);)
      if (std::regex_search(line, m, at_most))
        share = std::stod(m[1]) / 100;
    return Utilities::MPI::max(share, comm);
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  try
    {
      const std::string           scene  = argv[1];
      const std::vector<Override> common = {
        {"Time stepping", "End time", "1.2e-5"},
        {"Checkpoint", "Every simulated time", "8e-6"}};
      auto with = [&](const std::string &partition, const std::string &dir) {
        auto o = common;
        o.push_back({"Background grid", "Partition", partition});
        o.push_back({"Output", "Directory", dir});
        return o;
      };

      // 1. and 2.
      run_scene<3>(scene, comm, with("cost", "cost"));
      const double share_cost = busiest_share(comm);
      run_scene<3>(scene, comm, with("cells", "cells"));
      const double share_cells = busiest_share(comm);
      checks.in_range("MPM points on the busiest rank, 'cost'",
                      std::round(100 * share_cost) / 100,
                      0.5,
                      0.55);
      checks.at_most("busiest share, 'cost' / 'cells'",
                     std::round(100 * share_cost / share_cells) / 100,
                     0.99);
      for (const auto &[col, offset] :
           std::vector<std::pair<std::string, double>>{{"T", 300.},
                                                       {"sigma_xx", 0.}})
        checks.at_most(
          col + ": 'cost' against 'cells', / peak",
          probe_line_relative_difference("cost", "cells", col, offset),
          1e-6);

      // 3. The 'cells' checkpoint at 8 us, resumed with 'cost'.
      const std::string from = copy_for_resume("cells", "resumed", comm);
      auto              o    = with("cost", "resumed");
      o.push_back({"Checkpoint", "Resume from", from});
      run_scene<3>(scene, comm, o);
      for (const auto &[col, offset] :
           std::vector<std::pair<std::string, double>>{{"T", 300.},
                                                       {"sigma_xx", 0.}})
        checks.at_most(
          col + ": resumed with 'cost' against 'cost', / peak",
          probe_line_relative_difference("cost", "resumed", col, offset),
          1e-6);
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
