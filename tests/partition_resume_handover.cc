// 'Checkpoint/Partition on resume' (doc/performance.md, "Balancing the
// ranks") on the two-layer 2D build of tests/checkpoint_handover.prm (heat
// and solid) with its FE zone set to the plate's two lowest rows (8 um)
// and a hand-over margin of 32 um: at the second layer's start (141 us)
// the hand-over raises the zone to 52 um, and the plate's top three rows
// and the first layer's metal stay MPM points. On 2 ranks the run is
// checkpointed at 150 us and resumed to 200 us twice:
//   1. 'checkpoint': the cells weighed by the checkpoint's zone and points.
//      The share of the MPM points on the busiest rank at the resume
//      (layer_cost.csv, mpm_share_max, counted after the restore) must lie
//      within 5 % of an even split, [0.5, 0.55] (0.52 measured): the MPM
//      points carry about three quarters of the cost here (42 against 2
//      per other point and 1 per cell), so that a partition of equal cost
//      splits them evenly up to the rest's uneven share.
//   2. 'scene': the scene's geometry at the start, which weighs the plate
//      above 8 um as MPM points; the rows the hand-over took are
//      elements, and the busiest rank holds 0.66 of the MPM points left
//      (at least 0.6 required; 1. must undercut it by a tenth). A resume
//      that ignores the checkpoint's state gives 1. this share too.
//   3. The same answer either way: T and sigma_xx on the probe line AB
//      (up the middle of the track, through the zone and the layers) and
//      sigma_xx at the solid's probes at 200 us agree within 1e-9 of their
//      peaks (the partitions differ in the order of sums only: no
//      iterative solver in this scene; printed rounded up to 1e-12).
// The shares depend on the partition: 2 ranks only.
#include <regex>

#include "resume_tools.h"
#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

namespace
{
  /// Share of the MPM points on the busiest rank at the resume: the last
  /// row of @p dir's layer_cost.csv (the layer resumed, counted after the
  /// restore).
  double
  busiest_share(const std::string &dir)
  {
    const auto c = read_csv_columns(dir + "/layer_cost.csv");
    AssertThrow(c.count("mpm_share_max") && !c.at("mpm_share_max").empty(),
                ExcMessage("no mpm_share_max in " + dir + "/layer_cost.csv"));
    return c.at("mpm_share_max").back();
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
      // The zone of the scene: the plate's two lowest rows; the hand-over
      // raises it to 52 um (a margin of 32 um below the new layer's top
      // less the fusion depth) and leaves the plate's top rows as points.
      // The powder top's line alone ('Hand-over surface limit = false'):
      // the surface line would hold the zone at 32 um, the margin below
      // the plate's top (the metal surface under the first layer's porous
      // bead), and the test reads the partition of a zone at 52 um.
      const std::vector<Override> zone = {
        {"Solid FEM", "Zone upper corner", "200e-6, 8e-6"},
        {"Build", "Hand-over margin", "3.2e-5"},
        {"Build", "Hand-over surface limit", "false"}};
      auto with = [&](std::vector<Override> o) {
        o.insert(o.end(), zone.begin(), zone.end());
        return o;
      };
      // To the checkpoint at 150 us, after the zone rose.
      run_scene<2>(scene,
                   comm,
                   with({{"Time stepping", "End time", "1.5e-4"},
                         {"Checkpoint", "Every simulated time", "1.5e-4"},
                         {"Output", "Directory", "straight"}}));
      auto resume = [&](const std::string &how) {
        const std::string from = copy_for_resume("straight", how, comm, true);
        run_scene<2>(scene,
                     comm,
                     with({{"Time stepping", "End time", "2e-4"},
                           {"Checkpoint", "Partition on resume", how},
                           {"Output", "Directory", how},
                           {"Checkpoint", "Resume from", from}}));
        return busiest_share(how);
      };
      const double share_state = resume("checkpoint");
      const double share_scene = resume("scene");

      // 1. and 2.
      checks.in_range("MPM points on the busiest rank, 'checkpoint'",
                      std::round(100 * share_state) / 100,
                      0.5,
                      0.55);
      checks.in_range("MPM points on the busiest rank, 'scene'",
                      std::round(100 * share_scene) / 100,
                      0.6,
                      1.);
      checks.at_most("busiest share, 'checkpoint' / 'scene'",
                     std::round(100 * share_state / share_scene) / 100,
                     0.9);

      // 3. The ends of both resumed runs.
      check_same_build_end(
        checks, "checkpoint", "scene", "'checkpoint' against 'scene'", 2, 1e-9);
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
