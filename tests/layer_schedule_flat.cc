// A flat scan path through femp (doc/builds.md, "Recoating"): the 2D scene
// argv[1] (tests/layer_schedule_flat.prm: a plate with a 24 um powder
// layer, heat only, 'Build/Layer schedule = scan path') run with the path
// of the folder argv[2]'s layer_schedule_flat_path.txt (AdditiveFOAM: two
// tracks of 80 um at 3e5 W/m, 10 us apart, both at z = 96 um). One layer:
// layer_cost.csv holds one row, layer 1 from t = 0 to the end time;
// tracks.csv puts both tracks in layer 1 and layers.csv holds one layer of
// two tracks. Against it the same scene with layer_schedule_rise_path.txt
// (the second track 32 um higher, after a jump with the laser off at
// t = 91 us): two rows, layer 2's from the step holding 91 us, and the
// second track in layer 2 (the counts come from the path's heights).
#include <deal.II/base/mpi.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  const std::string                scene = argv[1], dir = argv[2];
  const double                     t_end = 1.8e-4;

  const auto run = [&](const std::string &path) {
    run_scene<2>(scene,
                 comm,
                 {{"Laser",
                   "Scan path file",
                   dir + "/layer_schedule_" + path + "_path.txt"},
                  {"Output", "Directory", path}});
    // Rank 0 writes the files: read them once it is done.
    MPI_Barrier(comm);
  };
  const auto rows = [](const std::map<std::string, std::vector<double>> &c) {
    const auto it = c.find("layer");
    return it == c.end() ? 0. : static_cast<double>(it->second.size());
  };

  // The flat path: one layer.
  run("flat");
  {
    const auto cost   = read_csv_columns("flat/layer_cost.csv");
    const auto tracks = read_csv_columns("flat/tracks.csv");
    const auto layers = read_csv_columns("flat/layers.csv");
    checks.in_range("flat: rows of layer_cost.csv", rows(cost), 1, 1);
    if (rows(cost) == 1)
      {
        checks.in_range("flat: its layer", cost.at("layer")[0], 1, 1);
        checks.at_most("flat: its t_start (s)", cost.at("t_start")[0], 0);
        checks.at_most("flat: |t_end - end time| / end time",
                       std::abs(cost.at("t_end")[0] - t_end) / t_end,
                       1e-9);
      }
    checks.in_range("flat: rows of tracks.csv", rows(tracks), 2, 2);
    if (rows(tracks) > 0)
      checks.in_range("flat: highest layer of a track",
                      *std::max_element(tracks.at("layer").begin(),
                                        tracks.at("layer").end()),
                      1,
                      1);
    checks.in_range("flat: rows of layers.csv", rows(layers), 1, 1);
    if (rows(layers) == 1)
      checks.in_range("flat: tracks of layer 1", layers.at("tracks")[0], 2, 2);
  }

  // The path with a jump up: two layers.
  run("rise");
  {
    const auto cost   = read_csv_columns("rise/layer_cost.csv");
    const auto tracks = read_csv_columns("rise/tracks.csv");
    checks.in_range("rise: rows of layer_cost.csv", rows(cost), 2, 2);
    if (rows(cost) == 2)
      {
        checks.in_range("rise: layer of row 2", cost.at("layer")[1], 2, 2);
        // The step that holds the layer's start, 91 us (steps under 1 us).
        checks.in_range("rise: t_start of layer 2 (us)",
                        cost.at("t_start")[1] * 1e6,
                        90,
                        91);
        checks.at_most("rise: |t_end - end time| / end time",
                       std::abs(cost.at("t_end")[1] - t_end) / t_end,
                       1e-9);
      }
    checks.in_range("rise: rows of tracks.csv", rows(tracks), 2, 2);
    if (rows(tracks) == 2)
      checks.in_range("rise: layer of track 2", tracks.at("layer")[1], 2, 2);
  }
  return checks.exit_code();
}
