// Verification: laser energy accounting in a full thermal scene (powder
// layer on a substrate, 316L tables for c(T) and lambda(T), latent heat,
// evaporation, convection and radiation, bottom face held at 300 K):
//   absorbed laser energy + heat in through fixed faces
//     = change of stored enthalpy + surface losses
//       + heat carried away by the evaporated mass     (within 1 %),
// and the absorbed energy equals eta P t_on for the first-surface
// deposition (within 1 %). Scene: tests/energy_balance.prm.
#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  const auto                       s = run_scene<3>(argv[1], comm);

  checks.print("steps", s.steps);
  checks.print("laser energy (J)", s.laser, 4);
  checks.print("surface losses (J)", s.losses, 3);
  checks.print("stored enthalpy change (J)", s.stored, 3);
  checks.print("peak temperature (K)", s.T_max, 3);
  const double imbalance =
    std::abs(s.laser + s.boundary - s.losses - s.removed_enthalpy - s.stored) /
    s.laser;
  checks.at_most("energy imbalance / laser energy", imbalance, 0.01);
  // eta P t_on: 200 W * 0.35 * (laser on for 2e-4 s).
  const double expected = 200 * 0.35 * 2e-4;
  checks.at_most("|laser energy - eta P t| / (eta P t)",
                 std::abs(s.laser - expected) / expected,
                 0.01);
  return checks.exit_code();
}
