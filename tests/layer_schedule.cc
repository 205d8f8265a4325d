// The layer schedule from the scan path (builds/recoater.h, doc/builds.md
// "Recoating", 'Build/Layer schedule = scan path'), read from small
// adamantine_segment files (heat/scan_path.h) in 3D and printed layer by
// layer (number, start time, top of its powder, thickness):
//   1. a path at one height (two tracks and a dwell at z = 100 um): one
//      layer, no layer after the first;
//   2. the same with a jump, laser off, up to z = 140 um and a track
//      there: layer 2 starts at the jump's start (10 us placing + 200 us
//      track + 50 us dwell = 260 us), its powder reaches the first layer's
//      top + 40 um;
//   3. path 2 then a move, laser off, down to z = 0 (the beam parked
//      below): still two layers (a move down with the laser off is a
//      move);
//   4. path 2 then a track, laser on, back down to z = 100 um: refused,
//      the message naming 'Build/Layer schedule', the segment's times and
//      heights and the layer it falls below (printed).
#include <femp/base/input_checks.h>
#include <femp/builds/recoater.h>
#include <femp/heat/scan_path.h>

#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "test_tools.h"

using namespace femp_test;

namespace
{
  constexpr int dim = 3;

  /// Write an adamantine_segment file @p name with the segment @p lines
  /// ('mode x y z power_factor parameter').
  void
  write_path(const std::string &name, const std::vector<std::string> &lines)
  {
    std::ofstream f(name);
    f << "Number of path segments\n"
      << lines.size() << "\nMode x y z pmod param\n";
    for (const auto &l : lines)
      f << l << '\n';
  }

  /// Layer 1: placed at (0, 0, 100 um) for 10 us, laser off; a track to
  /// x = 200 um at 1 m/s, 200 W; a dwell of 50 us, laser off.
  const std::vector<std::string> layer_1 = {"1 0 0 100e-6 0 1e-5",
                                            "0 200e-6 0 100e-6 1 1",
                                            "1 200e-6 0 100e-6 0 5e-5"};
  /// The jump up, laser off, at 5 m/s, and the track of layer 2.
  const std::vector<std::string> layer_2 = {"0 0 0 140e-6 0 5",
                                            "0 200e-6 0 140e-6 1 1"};

  std::vector<std::string>
  join(std::vector<std::string> a, const std::vector<std::string> &b)
  {
    a.insert(a.end(), b.begin(), b.end());
    return a;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  Checks                           checks(MPI_COMM_WORLD);

  // Substrate top 100 um + a 30 um powder layer; a domain 300 um tall with
  // cells of 8 um.
  const double first_top = 130e-6, domain_top = 300e-6, h = 8e-6;
  typename LayerSchedule<dim>::Parameters prm;
  prm.source = LayerSource::scan_path;

  const auto schedule_of = [&](const std::string              &name,
                               const std::vector<std::string> &lines) {
    write_path(name, lines);
    const auto segments =
      read_scan_path<dim>(name, ScanPathFormat::adamantine_segment, 200., 0.);
    return LayerSchedule<dim>(prm, segments, first_top, domain_top, h);
  };
  const auto print_layers = [&](const std::string        &what,
                                const LayerSchedule<dim> &s) {
    for (const auto &l : s.layers())
      {
        const std::string k = what + ": layer " + std::to_string(l.number);
        checks.print(k + " start (us)", l.start_time * 1e6, 6);
        checks.print(k + " top (um)", l.top * 1e6, 6);
        checks.print(k + " thickness (um)", l.thickness * 1e6, 6);
      }
  };

  // 1. One height: one layer.
  {
    const auto s = schedule_of("flat.txt", join(layer_1, {"0 0 0 100e-6 1 1"}));
    print_layers("flat", s);
    checks.at_most("flat: layers after the first", s.layers().size(), 0);
  }
  // 2. Two layers.
  {
    const auto s = schedule_of("two_layers.txt", join(layer_1, layer_2));
    print_layers("two layers", s);
    checks.in_range("two layers: layers after the first",
                    s.layers().size(),
                    1,
                    1);
    if (s.layers().size() == 1)
      {
        const auto &l = s.layers()[0];
        checks.in_range("two layers: start (us)",
                        l.start_time * 1e6,
                        260 - 1e-6,
                        260 + 1e-6);
        checks.in_range("two layers: top (um)",
                        l.top * 1e6,
                        170 - 1e-6,
                        170 + 1e-6);
      }
  }
  // 3. A move down with the laser off after the last layer: no layer more.
  {
    const auto s =
      schedule_of("parked.txt", join(join(layer_1, layer_2), {"0 0 0 0 0 5"}));
    print_layers("parked below", s);
    checks.in_range("parked below: layers after the first",
                    s.layers().size(),
                    1,
                    1);
  }
  // 4. A track with the laser on back down at layer 1's height: refused.
  {
    bool refused = false;
    try
      {
        schedule_of("down.txt",
                    join(join(layer_1, layer_2), {"0 0 0 100e-6 1 1"}));
      }
    catch (const InputError &e)
      {
        std::cout << "down: " << e.what() << std::endl;
        refused = std::strstr(e.what(), "Build/Layer schedule") &&
                  std::strstr(e.what(), "goes down");
      }
    checks.at_most("down: refused (0 = yes)", refused ? 0 : 1, 0);
  }
  return checks.exit_code();
}
