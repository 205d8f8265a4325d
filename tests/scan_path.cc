// Scan path from a file: segments with the laser on and off. A 2D scene
// (tests/scan_path.prm, path tests/scan_path.txt): 60 um on at 1 m/s, a
// 120 um jump at 12 m/s with the laser off, 60 um on at 1 m/s, then off.
// Checks the beam position and on/off state along the path, and that the
// absorbed energy equals eta P times the time the laser is on (1 %).
#include <femp/heat/laser.h>

#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);

  Laser<2>::Parameters lp;
  lp.scan_path_file = std::string(argv[2]);
  lp.start_time     = 1e-5;
  Laser<2> laser(lp);
  Point<2> x;
  double   power;
  // t = 1e-5 + 30 us: on, at x = 50 + 30 um.
  const bool on1 = laser.position(1e-5 + 30e-6, x, power);
  checks.at_most("first segment: |x - 80 um| (m)",
                 on1 ? std::abs(x[0] - 80e-6) : 1.,
                 1e-12);
  // t = 1e-5 + 60 us + 5 us: jump, off, at x = 110 + 60 um.
  const bool on2 = laser.position(1e-5 + 65e-6, x, power);
  checks.at_most("jump: laser on", on2, 0);
  checks.at_most("jump: |x - 170 um| (m)", std::abs(x[0] - 170e-6), 1e-12);
  // after the path: off
  checks.at_most("after the path: laser on", laser.position(1e-3, x, power), 0);
  checks.print("path end time (s)", laser.end_time(), 6);

  const auto s =
    run_scene<2>(argv[1], comm, {{"Laser", "Scan path file", argv[2]}});
  // On for 2 x 60 us at 1e5 W/m, eta = 0.35.
  const double expected = 0.35 * 1e5 * 120e-6;
  checks.print("laser energy (J/m)", s.laser, 4);
  checks.at_most("|laser energy - eta P t_on| / (eta P t_on)",
                 std::abs(s.laser - expected) / expected,
                 0.01);
  checks.at_most("energy imbalance / laser energy",
                 std::abs(s.laser + s.boundary - s.losses - s.stored) / s.laser,
                 0.01);
  return checks.exit_code();
}
