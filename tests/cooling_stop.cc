// 'Time stepping/Stop when peak temperature below' (doc/cases.md, "Residual
// stress after cooling") on a heat-only track (tests/cooling_stop.prm):
// the laser runs 32 us and is off after its path; the run must stop at the
// first step after which the hottest metal cell is below 600 K: before the
// end time (1 ms), after the laser's path, with T_max < 600 K; and the same
// scene run without the stop for one step less ('Maximum number of steps')
// must still be at or above 600 K there. Runs on 1 and 2 ranks
// with the same output.
#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  try
    {
      const auto stop =
        run_scene<3>(argv[1], comm, {{"Output", "Directory", "stop"}});
      const double laser_end = 64e-6 / 2;
      checks.print("stopped at (us)", std::round(stop.time * 1e6), 3);
      checks.in_range("stop time (s)", stop.time, laser_end, 1e-3 * (1 - 1e-9));
      checks.at_most("peak temperature at the stop (K) / 600",
                     stop.T_max / 600,
                     1);
      // The same steps, one fewer.
      std::ostringstream end;
      end.precision(15);
      end << stop.time;
      const auto before = run_scene<3>(
        argv[1],
        comm,
        {{"Output", "Directory", "before"},
         {"Time stepping", "Stop when peak temperature below", "0"},
         {"Time stepping", "End time", end.str()},
         {"Time stepping",
          "Maximum number of steps",
          std::to_string(stop.steps - 1)}});
      checks.print("steps to the stop", stop.steps, 4);
      checks.in_range("peak temperature one step before the stop (K) / 600",
                      before.T_max / 600,
                      1,
                      2);
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
