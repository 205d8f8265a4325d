// A rebalance's checkpoint ('Build/Rebalance above imbalance') beside the
// user's interval checkpoints (doc/checkpoint.md, "Which checkpoints are
// kept"), on the two-layer build of rebalance_at_layer_start (its zone,
// margin and ratio 1.2: one rebalance, at the second layer's start, 141 us)
// on 2 ranks, with 'Checkpoint/Every simulated time = 5e-5':
//   1. to 145 us: user checkpoints at 50 and 100 us, then the rebalance's.
//      All three must be kept: the index names 3, the newest first, and
//      step directories exist for exactly these 3, one of them marked as
//      the rebalance's (the newest). The two user checkpoints must resume
//      (a FempProblem made with 'Checkpoint/Resume from' reads and
//      verifies each: its files, checksums and scene).
//   2. 'femp --resume' of 1.'s checkpoint directory (its newest, the
//      rebalance's) to 170 us: the user checkpoint at 150 us removes the
//      rebalance's and keeps 100 us: the index names 2, the older of them
//      1.'s second, and no rebalance's checkpoint is left.
// Then the ratio where it cannot act, each run to 2 us: the scene's printout
// must say it is inert and why ("rebalance: inert, <why>"):
//   3. on one rank (rank 0 alone), 4. without the solid (and so without the
//   hand-over), 5. with one layer (Build/Layer schedule = none).
#include <filesystem>
#include <fstream>
#include <memory>
#include <regex>

#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

namespace
{
  /// The lines of @p dir's checkpoint index, the newest first.
  std::vector<std::string>
  index_of(const std::string &dir)
  {
    std::ifstream            in(dir + "/checkpoint/index");
    std::vector<std::string> names;
    for (std::string line; std::getline(in, line);)
      if (!line.empty())
        names.push_back(line);
    return names;
  }

  /// The step directories in @p dir's checkpoint directory, and how many
  /// of them are marked as a rebalance's.
  std::pair<unsigned int, unsigned int>
  step_directories(const std::string &dir)
  {
    namespace fs       = std::filesystem;
    unsigned int steps = 0, marked = 0;
    for (const auto &e : fs::directory_iterator(dir + "/checkpoint"))
      if (e.is_directory() &&
          e.path().filename().string().rfind("step_", 0) == 0)
        {
          ++steps;
          marked += fs::exists(e.path() / "rebalance");
        }
    return {steps, marked};
  }

  /// Whether every name of @p names is a step directory in @p dir.
  bool
  all_exist(const std::string &dir, const std::vector<std::string> &names)
  {
    for (const auto &n : names)
      if (!std::filesystem::is_directory(dir + "/checkpoint/" + n))
        return false;
    return true;
  }

  /// Whether the scene's log holds the line "rebalance: inert, @p why"
  /// (rank 0 writes it; broadcast by a maximum over @p comm).
  bool
  says_inert(const std::string &why, MPI_Comm comm)
  {
    bool          found = false;
    std::ifstream log("scene.log");
    for (std::string line; std::getline(log, line);)
      found = found || line.find("  rebalance: inert, " + why) == 0;
    return Utilities::MPI::max(int(found), comm) > 0;
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
      const std::string scene = argv[1];
      // The powder top's line alone, as in rebalance_at_layer_start: the
      // zone rises to 52 um and the layer start's rebalance fires.
      const std::vector<Override> common = {
        {"Solid FEM", "Zone upper corner", "200e-6, 8e-6"},
        {"Build", "Hand-over margin", "3.2e-5"},
        {"Build", "Hand-over surface limit", "false"},
        {"Build", "Rebalance above imbalance", "1.2"},
        {"Checkpoint", "Every simulated time", "5e-5"},
        {"Output", "Directory", "kept"}};
      // The later of two overrides of one entry wins: @p o's.
      auto with = [&](const std::vector<Override> &o) {
        auto all = common;
        all.insert(all.end(), o.begin(), o.end());
        return all;
      };
      // The index of 'kept' names @p n checkpoints, as many step
      // directories are left, @p n_rebalance of them a rebalance's, and
      // every name of the index exists; returns the index.
      auto check_kept = [&](const std::string &part,
                            const unsigned int n,
                            const unsigned int n_rebalance) {
        const auto index              = index_of("kept");
        const auto [steps, rebalance] = step_directories("kept");
        checks.in_range(part + ": checkpoints in the index",
                        index.size(),
                        n,
                        n);
        checks.in_range(part + ": step directories", steps, n, n);
        checks.in_range(part + ": of them a rebalance's",
                        rebalance,
                        n_rebalance,
                        n_rebalance);
        checks.in_range(part + ": the index's checkpoints exist",
                        all_exist("kept", index),
                        1,
                        1);
        return index;
      };
      // 1.
      run_scene<2>(scene,
                   comm,
                   with({{"Time stepping", "End time", "1.45e-4"}}));
      MPI_Barrier(comm);
      const auto first = check_kept("1.", 3, 1);
      const bool newest_marked =
        !first.empty() &&
        std::filesystem::exists("kept/checkpoint/" + first[0] + "/rebalance");
      checks.in_range("1.: the newest is the rebalance's", newest_marked, 1, 1);
      // The user checkpoints resume: read and verified by the constructor.
      unsigned int resumable = 0;
      for (std::size_t i = 1; i < first.size(); ++i)
        {
          dealii::ParameterHandler prm;
          parse_scene(
            prm,
            scene,
            with({{"Checkpoint", "Resume from", "kept/checkpoint/" + first[i]},
                  {"Output", "Directory", "resumable"}}));
          femp::FempProblem<2> problem(prm, comm);
          ++resumable;
        }
      checks.in_range("1.: user checkpoints that resume", resumable, 2, 2);

      // 2.
      run_scene<2>(scene,
                   comm,
                   with({{"Time stepping", "End time", "1.7e-4"},
                         {"Checkpoint", "Resume from", "kept/checkpoint"}}));
      MPI_Barrier(comm);
      const auto second = check_kept("2.", 2, 0);
      checks.in_range("2.: the older is 1.'s newest user checkpoint",
                      second.size() == 2 && first.size() > 1 &&
                        second[1] == first[1],
                      1,
                      1);

      // 3.-5.
      const std::vector<Override> short_run = {
        {"Time stepping", "End time", "2e-6"},
        {"Checkpoint", "Every simulated time", "0"}};
      auto with_short = [&](std::vector<Override> o) {
        o.insert(o.end(), short_run.begin(), short_run.end());
        return with(o);
      };
      bool one_rank = false;
      if (Utilities::MPI::this_mpi_process(comm) == 0)
        {
          run_scene<2>(scene,
                       MPI_COMM_SELF,
                       with_short({{"Output", "Directory", "one_rank"}}));
          one_rank = says_inert("one MPI rank", MPI_COMM_SELF);
        }
      checks.in_range("3.: inert on one rank",
                      Utilities::MPI::max(int(one_rank), comm),
                      1,
                      1);
      run_scene<2>(scene,
                   comm,
                   with_short({{"Physics", "Solid stress", "false"},
                               {"Build", "Hand over cooled metal", "false"},
                               {"Output", "Directory", "no_solid"}}));
      checks.in_range("4.: inert without the solid",
                      says_inert("no solid", comm),
                      1,
                      1);
      run_scene<2>(scene,
                   comm,
                   with_short({{"Build", "Layer schedule", "none"},
                               {"Build", "Hand over cooled metal", "false"},
                               {"Output", "Directory", "one_layer"}}));
      checks.in_range("5.: inert with one layer",
                      says_inert("one layer", comm),
                      1,
                      1);
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
