// Energy bookkeeping of the heat equation with melt flow (doc/verification.md,
// "Energy balance"): tests/melt_flow_scene.prm (2D powder bed melted by a
// line scan, melt flow with surface tension and Marangoni) through
// FempProblem, once with each way heat moves with the flow (Heat transfer/
// Advection by melt flow). femp reports, besides laser, losses, fixed faces
// and stored enthalpy (and the heat carried away by the evaporated mass, a
// loss like the surface losses), the energy created by the upwind convection
// of T and by points moving between cells (change of the stored enthalpy
// when alpha and the temperatures of the cells whose points changed are
// updated).
// - 'points' (the default): the points carry the metal's enthalpy, so the
//   plain balance must close to 1 % of the laser energy (it was 1.9 % with
//   'upwind'; what is left is the difference between the grid's metal
//   volume and the points' volume).
// - 'points' with 'Heat transfer/Metal of melt cells = points' (the cells
//   holding melt keep the heat of their own points' volume): the exchange
//   conserves the heat the points carry, so the plain balance must close
//   to 1e-3 of the laser energy (the moved points' term keeps only the
//   gas's heat in the volume alpha gives or takes).
// - 'upwind': not conservative; its plain error is printed, not gated.
// In both, with the two terms counted as sources the balance must close to
// round-off (1e-3 of the laser energy). 1 and 2 ranks give the same output.

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
  auto r = [](const double x) { return std::round(x * 1000) / 1000; };
  for (const std::string mode : {"points", "points, metal of points", "upwind"})
    {
      const bool        by_points = mode == "points, metal of points";
      const auto        s         = run_scene<2>(argv[1],
                                  comm,
                                  {{"Heat transfer",
                                                   "Advection by melt flow",
                                    by_points ? "points" : mode},
                                                  {"Heat transfer",
                                                   "Metal of melt cells",
                                    by_points ? "points" : "alpha"}});
      const double      in        = s.laser + std::abs(s.boundary);
      const std::string m         = "[" + mode + "] ";
      checks.print(m + "laser energy (J/m)",
                   std::round(s.laser * 100) / 100,
                   4);
      // The heat carried away by the evaporated mass is a loss like the
      // surface losses.
      const double plain =
        (s.laser + s.boundary - s.losses - s.removed_enthalpy - s.stored) / in;
      if (mode == "points")
        checks.at_most(
          m + "|balance error| (laser + faces - losses - stored) / laser",
          r(std::abs(plain)),
          0.01);
      else if (by_points)
        checks.at_most(m + "|balance error| (laser + faces - losses - "
                           "stored) / laser, next power of ten",
                       std::abs(plain) > 0 ?
                         std::pow(10., std::ceil(std::log10(std::abs(plain)))) :
                         0.,
                       1e-3);
      else
        checks.print(m + "balance error (laser + faces - losses - stored) / "
                         "laser (not gated)",
                     r(plain),
                     2);
      checks.print(m + "energy created by the upwind convection / laser",
                   r(s.advection / in),
                   2);
      checks.print(m + "energy created by points moving between cells / laser",
                   r(s.moved_points / in),
                   2);
      const double closed =
        std::abs(s.laser + s.boundary + s.advection + s.moved_points -
                 s.losses - s.removed_enthalpy - s.stored) /
        in;
      checks.at_most(
        m + "balance error with both counted as sources, next power of ten",
        closed > 0 ? std::pow(10., std::ceil(std::log10(closed))) : 0.,
        1e-3);
    }
  return checks.exit_code();
}
