// Scan paths in adamantine's 'segment' and 'event_series' formats and in
// AdditiveFOAM's format (tests/scan_path_*.txt): the same path written
// three ways, on a 2D scene (tests/scan_path_formats.prm, 'Laser/Power' =
// 1e5 W/m, start time 10 us). By hand, from the files:
//   10 us  beam placed at x = 50 um, off
//   60 um at 1 m/s to x = 110 um, 1e5 W/m          60 us   6 J/m
//   dwell at x = 110 um, 5e4 W/m                   20 us   1 J/m
//   to x = 230 um and 30 um up (next layer), off   30 us   0
//   60 um at 1.2 m/s to x = 290 um, 8e4 W/m        50 us   4 J/m
// so 11 J/m emitted over 170 us, and eta = 0.35 of it absorbed. Checks the
// emitted energy of each reader's segments, the beam at three times, the
// energy the scene absorbs (1 %), and that a 2D scene refuses a path whose
// y varies.
//
// With '--generated DIR': the files contrib/scan_path_generator.py wrote
// in DIR for two 400 um square layers (border contour at 40 um inset, two
// 160 um hatches 80 um apart, 200 W at 1 m/s): by hand 2 x (4 x 320 um +
// 2 x 160 um) x 200 W / (1 m/s) = 0.64 J in every format, and the three
// formats must give the same beam at all times.
#include <femp/heat/scan_path.h>

#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

namespace
{
  /// The format of the input name @p name.
  ScanPathFormat
  format_named(const std::string &name)
  {
    for (const auto &c : scan_path_format_choices())
      if (c.second == name)
        return c.first;
    throw std::logic_error("no scan path format " + name);
  }

  int
  check_generated(const std::string &dir, Checks &checks)
  {
    std::vector<std::unique_ptr<Laser<3>>> lasers;
    for (const std::string format :
         {"adamantine_segment", "adamantine_event_series", "additivefoam"})
      {
        Laser<3>::Parameters lp;
        lp.scan_path_file   = dir + "/gen_" + format + ".txt";
        lp.scan_path_format = format_named(format);
        lp.power            = 200;
        lasers.push_back(std::make_unique<Laser<3>>(lp));
        checks.at_most(format + ": |emitted - 0.64 J| (J)",
                       std::abs(emitted_energy<3>(lasers.back()->segments()) -
                                0.64),
                       1e-9);
      }
    checks.print("path end time (s)", lasers[0]->end_time(), 6);
    double difference = 0;
    for (unsigned int i = 0; i <= 1000; ++i)
      {
        const double t = 0.999 * i * lasers[0]->end_time() / 1000;
        Point<3>     x0, x;
        double       p0 = 0, p = 0;
        const bool   on0 = lasers[0]->position(t, x0, p0);
        for (unsigned int k = 1; k < 3; ++k)
          {
            const bool on = lasers[k]->position(t, x, p);
            difference =
              std::max(difference,
                       (on != on0) + std::abs(p - p0) + x.distance(x0) / 1e-6);
          }
      }
    checks.at_most("largest difference between the formats", difference, 1e-6);
    return checks.exit_code();
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  const std::string                dir = argv[2];
  if (std::string(argv[1]) == "--generated")
    return check_generated(dir, checks);

  const double emitted_by_hand = 1e5 * 60e-6 + 5e4 * 20e-6 + 8e4 * 50e-6;
  const double t0              = 1e-5;
  struct Probe
  {
    double t, x, z, power;
  };
  const std::vector<Probe> probes = {{t0 + 40e-6, 80e-6, 92e-6, 1e5},
                                     {t0 + 80e-6, 110e-6, 92e-6, 5e4},
                                     {t0 + 140e-6, 254e-6, 122e-6, 8e4}};

  for (const std::string format :
       {"adamantine_segment", "adamantine_event_series", "additivefoam"})
    {
      const std::string    file = dir + "/scan_path_" + format + ".txt";
      Laser<2>::Parameters lp;
      lp.scan_path_file   = file;
      lp.scan_path_format = format_named(format);
      lp.power            = 1e5;
      lp.start_time       = t0;
      Laser<2> laser(lp);
      checks.at_most(format + ": |emitted - 11 J/m| (J/m)",
                     std::abs(emitted_energy<2>(laser.segments()) -
                              emitted_by_hand),
                     1e-12);
      checks.at_most(format + ": |end time - 180 us| (s)",
                     std::abs(laser.end_time() - (t0 + 170e-6)),
                     1e-15);
      double position_error = 0, power_error = 0;
      for (const auto &p : probes)
        {
          Point<2>   axis;
          double     power = 0;
          const bool on    = laser.position(p.t, axis, power);
          position_error =
            std::max(position_error,
                     std::abs(axis[0] - p.x) + std::abs(axis[1] - p.z));
          power_error =
            std::max(power_error, on ? std::abs(power - p.power) : p.power);
        }
      checks.at_most(format + ": beam position error (m)",
                     position_error,
                     1e-12);
      checks.at_most(format + ": beam power error (W/m)", power_error, 1e-9);

      const auto   s        = run_scene<2>(argv[1],
                                  comm,
                                  {{"Laser", "Scan path file", file},
                                            {"Laser", "Scan path format", format}});
      const double expected = 0.35 * emitted_by_hand;
      checks.print(format + ": absorbed laser energy (J/m)", s.laser, 4);
      checks.at_most(format + ": |absorbed - eta E| / (eta E)",
                     std::abs(s.laser - expected) / expected,
                     0.01);
    }

  // A 3D hatch (two tracks 40 um apart in y) does not fit a 2D scene.
  std::string message;
  try
    {
      Laser<2>::Parameters lp;
      lp.scan_path_file   = dir + "/scan_path_3d_hatch.txt";
      lp.scan_path_format = ScanPathFormat::additivefoam;
      Laser<2> laser(lp);
    }
  catch (const InputError &e)
    {
      message = e.what();
    }
  checks.at_most("3D hatch on a 2D scene refused",
                 message.find("Laser/Scan path file") == std::string::npos ||
                   message.find("same y") == std::string::npos,
                 0);
  // ... and reads in 3D: 2 x 240 um at 1 m/s and 200 W, 40 um jump at 2 m/s.
  {
    Laser<3>::Parameters lp;
    lp.scan_path_file   = dir + "/scan_path_3d_hatch.txt";
    lp.scan_path_format = ScanPathFormat::additivefoam;
    Laser<3> laser(lp);
    checks.at_most("3D hatch: |emitted - 0.096 J| (J)",
                   std::abs(emitted_energy<3>(laser.segments()) - 0.096),
                   1e-15);
    checks.at_most("3D hatch: |end time - 500 us| (s)",
                   std::abs(laser.end_time() - 500e-6),
                   1e-15);
  }
  return checks.exit_code();
}
