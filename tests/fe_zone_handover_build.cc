// The hand-over of cooled metal to the FE zone in a build (doc/builds.md,
// "Handing cooled metal to finite elements"): the two-layer 2D scene
// tests/fe_zone_handover_build.prm runs with 'Build/Hand over cooled metal'
// on and off. With it on, the zone's top must rise at the second layer's
// start (rows handed over, the same count of solid parts before it), and at
// the end σ_xx at the solid's probe points must stay within 0.1 of the
// largest |σ_xx| there of the run without the hand-over (the tolerance was
// set before the first measurement: the rows become elements at rest, so
// the runs differ by the discretisation of those rows and the mass-scaled
// dynamics, not by round-off). Prints the elements added, the points
// handed over, the new top and the largest probe difference rounded.
// A third run with 'Build/Hand-over checks per layer' = 3 must choose twice
// within the second layer (none within the first) and, since a layer's own
// melt only deepens the depth it keeps clear, each choice within the layer
// must keep its limit at or below the layer start's.
// One argument: the scene.
#include <regex>
#include <sstream>

#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

namespace
{
  /// The last row of the solid's probe file: sigma_xx at each probe.
  std::vector<double>
  last_probe_stresses(const std::string &file)
  {
    const auto          columns = read_csv_columns(file);
    std::vector<double> s;
    for (unsigned int i = 0;; ++i)
      {
        const auto c = columns.find("sigma_xx_" + std::to_string(i));
        if (c == columns.end())
          break;
        s.push_back(c->second.back());
      }
    return s;
  }

  /// The limits ("rows up to ... m") of the hand-over choices in scene.log:
  /// the layer starts' and those within a layer, in the order of the log.
  std::pair<std::vector<double>, std::vector<double>>
  handover_limits()
  {
    std::pair<std::vector<double>, std::vector<double>> limits;
    std::ifstream                                       log("scene.log");
    std::string                                         line;
    const std::regex re("FE zone hand-over at t = [-0-9.e+]+ s( \\(within "
                        "the layer\\))?: .* rows up to ([-0-9.e+]+) m");
    std::smatch      m;
    while (std::getline(log, line))
      if (std::regex_search(line, m, re))
        (m[1].matched ? limits.second : limits.first)
          .push_back(std::stod(m[2]));
    return limits;
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
      run_scene<2>(argv[1], comm, {{"Output", "Directory", "without"}});
      MPI_Barrier(comm);
      const auto without = last_probe_stresses("without/solid_probes.csv");
      run_scene<2>(argv[1],
                   comm,
                   {{"Output", "Directory", "with"},
                    {"Build", "Hand over cooled metal", "true"}});
      MPI_Barrier(comm);
      const auto with = last_probe_stresses("with/solid_probes.csv");

      // The hand-over's line in the log of the second run.
      double elements = 0, handed = 0, from = 0, to = 0;
      if (Utilities::MPI::this_mpi_process(comm) == 0)
        {
          std::ifstream    log("scene.log");
          std::string      line;
          const std::regex re("the zone's top rises from ([-0-9.e+]+) to "
                              "([-0-9.e+]+) m: ([0-9]+) elements, ([0-9]+) "
                              "points handed over");
          std::smatch      m;
          unsigned int     n = 0;
          while (std::getline(log, line))
            if (std::regex_search(line, m, re))
              {
                from     = std::stod(m[1]);
                to       = std::stod(m[2]);
                elements = std::stod(m[3]);
                handed   = std::stod(m[4]);
                ++n;
              }
          AssertThrow(n == 1,
                      ExcMessage("one hand-over expected in the log, found " +
                                 std::to_string(n)));
        }
      elements = Utilities::MPI::max(elements, comm);
      handed   = Utilities::MPI::max(handed, comm);
      from     = Utilities::MPI::max(from, comm);
      to       = Utilities::MPI::max(to, comm);
      checks.print("zone top before the hand-over (um)", from * 1e6, 3);
      checks.print("zone top after the hand-over (um)", to * 1e6, 3);
      checks.print("elements added", elements, 6);
      checks.print("points handed over", handed, 6);
      // 50 cells per row of 4 um, 4 points per cell in the plate.
      const double rows = std::round((to - from) / 4e-6);
      checks.in_range("rows handed over", rows, 1, 10);
      checks.at_most("|elements - 50 per row|",
                     std::abs(elements - 50 * rows),
                     0.);
      checks.at_most("|points - 4 per element|",
                     std::abs(handed - 4 * elements),
                     0.);

      AssertThrow(with.size() == without.size() && !with.empty(),
                  ExcMessage("the probe files differ in their columns"));
      double largest = 0, diff = 0;
      for (std::size_t i = 0; i < with.size(); ++i)
        {
          largest = std::max(largest, std::abs(without[i]));
          diff    = std::max(diff, std::abs(with[i] - without[i]));
        }
      checks.at_most("max |sigma_xx with - without| / max |sigma_xx| at "
                     "the probes at the end",
                     std::round(diff / largest * 1000) / 1000,
                     0.1);

      // The choices within a layer: 3 per layer, the start and two more.
      run_scene<2>(argv[1],
                   comm,
                   {{"Output", "Directory", "within"},
                    {"Build", "Hand over cooled metal", "true"},
                    {"Build", "Hand-over checks per layer", "3"}});
      MPI_Barrier(comm);
      double n_start = 0, n_within = 0, rise = 0;
      if (Utilities::MPI::this_mpi_process(comm) == 0)
        {
          const auto [starts, within] = handover_limits();
          n_start                     = starts.size();
          n_within                    = within.size();
          for (const double l : within)
            if (!starts.empty())
              rise = std::max(rise, l - starts.back());
        }
      n_start  = Utilities::MPI::max(n_start, comm);
      n_within = Utilities::MPI::max(n_within, comm);
      rise     = Utilities::MPI::max(rise, comm);
      checks.at_most("3 checks per layer: |choices at a layer start - 1|",
                     std::abs(n_start - 1),
                     0.);
      checks.at_most("3 checks per layer: |choices within the layers - 2|",
                     std::abs(n_within - 2),
                     0.);
      checks.at_most("3 checks per layer: largest rise of a limit within "
                     "the layer above the start's (um)",
                     std::round(rise * 1e7) / 10,
                     0.);
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
