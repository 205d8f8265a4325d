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
//      heights and the layer it falls below (printed);
//   5. path 2, a move, laser off, down to z = 100 um, then a track, laser
//      on, from there up to z = 140 um: refused (it starts below layer 2,
//      the layer in progress when it starts);
//   6. layer 1 then the jump up with the laser on and the track of layer 2:
//      two layers, layer 2 starting at the jump's start (a jump up starts
//      at the height of the layer it leaves);
//   7. layer 1, a move, laser off, down to z = 60 um, then the jump up with
//      the laser on: refused (it starts below layer 1, the layer it leaves);
//   8. an AdditiveFOAM path (the beam starts at the origin) whose first
//      segment is a track, laser on, from z = 0 up to z = 100 um, then a
//      track at that height: one layer (the first segment with the laser on
//      begins layer 1, its start is not read).
#include <femp/base/input_checks.h>
#include <femp/builds/recoater.h>
#include <femp/heat/scan_path.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "test_tools.h"

using namespace femp_test;

namespace
{
  constexpr int dim = 3;

  /// Write a scan path file @p name with the segment @p lines ('mode x y z
  /// power parameter'; the power a factor in adamantine_segment, in W in
  /// AdditiveFOAM) and the header of @p format.
  void
  write_path(const std::string              &name,
             const std::vector<std::string> &lines,
             const ScanPathFormat            format)
  {
    std::ofstream f(name);
    if (format == ScanPathFormat::adamantine_segment)
      f << "Number of path segments\n"
        << lines.size() << "\nMode x y z pmod param\n";
    else
      f << "Mode X(m) Y(m) Z(m) Power(W) Parameter\n";
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
                               const std::vector<std::string> &lines,
                               const ScanPathFormat            format =
                                 ScanPathFormat::adamantine_segment) {
    write_path(name, lines, format);
    const auto segments = read_scan_path<dim>(name, format, 200., 0.);
    return LayerSchedule<dim>(prm, segments, first_top, domain_top, h);
  };
  // The message of a path refused for going down ("" if accepted), printed.
  const auto refusal = [&](const std::string              &what,
                           const std::vector<std::string> &lines) {
    try
      {
        std::string file = what + ".txt";
        std::replace(file.begin(), file.end(), ' ', '_');
        schedule_of(file, lines);
      }
    catch (const InputError &e)
      {
        std::cout << what << ": " << e.what() << std::endl;
        return std::string(e.what());
      }
    return std::string();
  };
  const auto has = [](const std::string &message, const char *part) {
    return message.find(part) != std::string::npos;
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
  // 5. A move down with the laser off, then a track with the laser on from
  //    there back up to layer 2's height: refused, naming its start.
  {
    const std::string m =
      refusal("starts below",
              join(join(layer_1, layer_2),
                   {"0 0 0 100e-6 0 5", "0 200e-6 0 140e-6 1 1"}));
    checks.at_most("starts below: refused at its start below layer 2 (0 = yes)",
                   has(m, "Build/Layer schedule") && has(m, "goes down") &&
                       has(m, "starts at the height 0.0001 m") &&
                       has(m, "below the height 0.00014 m of layer 2") ?
                     0 :
                     1,
                   0);
  }
  // 6. The jump up with the laser on: two layers.
  {
    const auto s =
      schedule_of("jump_on.txt",
                  join(layer_1, {"0 0 0 140e-6 1 5", "0 200e-6 0 140e-6 1 1"}));
    print_layers("jump on", s);
    checks.in_range("jump on: layers after the first", s.layers().size(), 1, 1);
    if (s.layers().size() == 1)
      checks.in_range("jump on: start (us)",
                      s.layers()[0].start_time * 1e6,
                      260 - 1e-6,
                      260 + 1e-6);
  }
  // 7. The jump up with the laser on from below the layer it leaves.
  {
    const std::string m =
      refusal("jump from below",
              join(layer_1, {"0 0 0 60e-6 0 5", "0 200e-6 0 140e-6 1 1"}));
    checks.at_most(
      "jump from below: refused at its start below layer 1 (0 = yes)",
      has(m, "goes down") && has(m, "starts at the height 6e-05 m") &&
          has(m, "below the height 0.0001 m of layer 1") ?
        0 :
        1,
      0);
  }
  // 8. AdditiveFOAM: the first track starts at the origin, z = 0.
  {
    const auto s =
      schedule_of("origin.txt",
                  {"0 200e-6 0 100e-6 200 1", "0 0 0 100e-6 200 1"},
                  ScanPathFormat::additivefoam);
    print_layers("from the origin", s);
    checks.at_most("from the origin: layers after the first",
                   s.layers().size(),
                   0);
  }
  return checks.exit_code();
}
