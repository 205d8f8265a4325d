// 'Build/Rebalance above imbalance' (doc/builds.md, "Rebalancing at a layer
// start") on the two-layer 2D build of tests/checkpoint_handover.prm (heat
// and solid) with the zone and margin of partition_resume_handover: its FE
// zone set to the plate's two lowest rows (8 um) and a hand-over margin of
// 32 um, so that the second layer's start (141 us) raises the zone to
// 52 um and leaves the plate's top rows and the first layer's metal as MPM
// points, most of them on one rank of the scene's partition. On 2 ranks to
// 170 us:
//   1. 'rebalance': with the rebalance above 1.2. After the step of the
//      second layer's start (its recoat and hand-over) the busiest rank
//      holds about 1.3 times the mean of the MPM points: the run writes a
//      checkpoint there and goes on from it on a grid cut by its state. One
//      rebalance (the count of run_to_end() must be 1), and layer 2's
//      mpm_share_max (layer_cost.csv, counted after it) must lie within 5 %
//      of an even split, [0.5, 0.55].
//   2. 'straight': without the rebalance, with a checkpoint at the step of
//      1.'s (Checkpoint/Every steps): layer 2's share stays at least 0.6,
//      and 1. must undercut it by a tenth.
//   3. 'explicit': 2.'s checkpoint resumed with 'Checkpoint/Partition on
//      resume = checkpoint', the route 1. takes inside one run. 1. and 3.
//      must agree: T and sigma_xx on the probe line AB at the end, sigma_xx
//      at the solid's probes (every row) and the counts of layer_cost.csv
//      (points, MPM points, elements, shares, kept cells and points at each
//      layer's start), within 1e-12 of their peaks (no iterative solver in
//      this scene: equal, printed rounded up to 1e-12). 1.'s layer 2 row
//      goes on over the rebalance: its window (start, steps) is 2.'s, and
//      it has a wall_rebalance > 0 (3.'s counts from the resume).
// The shares depend on the partition: 2 ranks only.
#include <algorithm>
#include <fstream>
#include <memory>
#include <regex>

#include "resume_tools.h"
#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

namespace
{
  /// Run @p file with @p overrides through femp::run_to_end() (std::cout
  /// silenced); returns the number of rebalances.
  unsigned int
  run_with_rebalances(const std::string           &file,
                      MPI_Comm                     comm,
                      const std::vector<Override> &overrides)
  {
    dealii::ParameterHandler prm;
    parse_scene(prm, file, overrides);
    std::streambuf *old = std::cout.rdbuf();
    std::ofstream   log("scene.log");
    std::cout.rdbuf(log.rdbuf());
    auto problem         = std::make_unique<femp::FempProblem<2>>(prm, comm);
    const unsigned int n = femp::run_to_end(problem, prm, comm);
    std::cout.rdbuf(old);
    return n;
  }

  /// Layer 2's row of @p dir's layer_cost.csv: column @p col.
  double
  layer_2(const std::string &dir, const std::string &col)
  {
    const auto c = read_csv_columns(dir + "/layer_cost.csv");
    AssertThrow(c.count("layer") && c.count(col),
                ExcMessage("no " + col + " in " + dir + "/layer_cost.csv"));
    const auto &layer = c.at("layer");
    for (std::size_t i = 0; i < layer.size(); ++i)
      if (layer[i] == 2)
        return c.at(col)[i];
    AssertThrow(false, ExcMessage("no layer 2 in " + dir + "/layer_cost.csv"));
    return 0;
  }

  /// Largest difference of the columns @p cols of the CSV files @p a and
  /// @p b, each relative to its column's peak in @p a, rounded up to 1e-12.
  double
  largest_relative(const std::string              &a,
                   const std::string              &b,
                   const std::vector<std::string> &cols)
  {
    double largest = 0;
    for (const auto &c : cols)
      {
        const auto [diff, peak] = columns_difference(a, b, {c});
        if (diff > 0)
          largest = std::max(largest, diff / std::max(peak, 1e-300));
      }
    return std::ceil(1e12 * largest) / 1e12;
  }

  /// The columns of layer_cost.csv but the walls.
  std::vector<std::string>
  count_columns(const std::string &dir)
  {
    std::ifstream in(dir + "/layer_cost.csv");
    std::string   header;
    std::getline(in, header);
    std::vector<std::string> cols;
    for (const auto &c : Utilities::split_string_list(header, ','))
      if (c.find("wall") == std::string::npos)
        cols.push_back(c);
    return cols;
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
      // The powder top's line alone, as in partition_resume_handover.
      const std::vector<Override> common = {
        {"Solid FEM", "Zone upper corner", "200e-6, 8e-6"},
        {"Build", "Hand-over margin", "3.2e-5"},
        {"Build", "Hand-over surface limit", "false"},
        {"Time stepping", "End time", "1.7e-4"}};
      auto with = [&](std::vector<Override> o) {
        o.insert(o.end(), common.begin(), common.end());
        return o;
      };
      // 1.
      const unsigned int n =
        run_with_rebalances(scene,
                            comm,
                            with({{"Build", "Rebalance above imbalance", "1.2"},
                                  {"Output", "Directory", "rebalance"}}));
      checks.in_range("rebalances", double(n), 1, 1);
      // The step of its checkpoint: the newest of the index.
      std::string step;
      {
        std::ifstream index("rebalance/checkpoint/index");
        index >> step;
      }
      AssertThrow(step.rfind("step_", 0) == 0,
                  ExcMessage("no rebalance checkpoint in rebalance/"));
      const std::string n_step = std::to_string(std::stoul(step.substr(5)));
      // 2.
      run_scene<2>(scene,
                   comm,
                   with({{"Checkpoint", "Every steps", n_step},
                         {"Output", "Directory", "straight"}}));
      // 3.
      const std::string from = "explicit/checkpoint/" + step;
      copy_for_resume("straight", "explicit", comm);
      run_scene<2>(scene,
                   comm,
                   with({{"Checkpoint", "Partition on resume", "checkpoint"},
                         {"Checkpoint", "Resume from", from},
                         {"Output", "Directory", "explicit"}}));

      const double share_rebalance = layer_2("rebalance", "mpm_share_max");
      const double share_straight  = layer_2("straight", "mpm_share_max");
      checks.in_range("layer 2: MPM points on the busiest rank, rebalanced",
                      std::round(100 * share_rebalance) / 100,
                      0.5,
                      0.55);
      checks.in_range("layer 2: MPM points on the busiest rank, straight",
                      std::round(100 * share_straight) / 100,
                      0.6,
                      1.);
      checks.in_range("layer 2: wall_rebalance > 0",
                      layer_2("rebalance", "wall_rebalance") > 0 ? 1. : 0.,
                      1,
                      1);
      checks.at_most("layer 2: busiest share, rebalanced / straight",
                     std::round(100 * share_rebalance / share_straight) / 100,
                     0.9);

      // layer_cost.csv: the windows (layer 2's from its start: the run
      // carries its row over the rebalance) against 2., the counts at the
      // layers' starts (layer 2's after the rebalance) against 3.
      const std::vector<std::string> window = {
        "layer", "t_start", "t_end", "temperature_steps", "solid_steps"};
      std::vector<std::string> counts;
      for (const auto &c : count_columns("rebalance"))
        if (std::find(window.begin(), window.end(), c) == window.end() &&
            c != "flow_steps" && c.rfind("fluid_", 0) != 0)
          counts.push_back(c);
      checks.in_range("layer_cost.csv: count columns compared",
                      double(counts.size()),
                      8,
                      100);
      checks.at_most("layer_cost.csv windows: rebalanced against straight, "
                     "/ column's peak",
                     largest_relative("rebalance/layer_cost.csv",
                                      "straight/layer_cost.csv",
                                      window),
                     1e-12);
      checks.at_most("layer_cost.csv counts: rebalanced against explicit, "
                     "/ column's peak",
                     largest_relative("rebalance/layer_cost.csv",
                                      "explicit/layer_cost.csv",
                                      counts),
                     1e-12);

      // 1. against 3.
      check_same_build_end(checks,
                           "rebalance",
                           "explicit",
                           "rebalanced against explicit",
                           1,
                           1e-12);
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
