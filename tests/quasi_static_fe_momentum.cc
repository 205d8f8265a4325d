// 'Solid/Adaptive mass scaling/Finite-element nodes at a raise after
// solidification = momentum kept' (doc/solid.md, "Quasi-static cooling")
// on the short coupled track of tests/cooling_step.prm (as
// tests/quasi_static_fe_damping.cc: no hourglass control, 1 us temperature
// steps after solidification, the controller taking over at 141 us).
//   1. A common run to 140 us writes a checkpoint; the runs below resume
//      from copies of it and cool to 300 us with the controller.
//   2. Velocities kept and momentum kept at the raises: at each raise of
//      the factor from s to s_new the finite-element nodes lose the
//      kinetic energy K_FE (1 - (s / s_new)^2) at the old masses, booked
//      with transfer_dissipation (the transfer dissipation grows by more
//      than with kept velocities), so that the energy balance moves by at
//      most 2 % of that energy against the other run's (unbooked it
//      would move by all of it); the stresses on the probe lines CD
//      (points) and EF (elements) stay within 3 % of the other run's
//      peak.
//   3. The run with the option resumed from its checkpoint at 250 us
//      (after the switch) ends with the same solid energy rows.
// Runs on 1 and 2 ranks with the same output.
#include "cooling_step_runs.h"
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
      const CoolingStepRuns runs{argv[1], comm};
      runs.check_option(checks,
                        {"Solid/Adaptive mass scaling",
                         "Finite-element nodes at a raise after solidification",
                         "momentum kept"},
                        "momentum",
                        "keeping the momentum",
                        "momentum kept",
                        "velocities kept");
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
