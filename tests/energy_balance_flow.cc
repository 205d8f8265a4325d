// Energy bookkeeping of the heat equation with melt flow (doc/verification.md,
// Energy accounting): tests/melt_flow_scene.prm (2D powder bed melted by a
// line scan, melt flow with surface tension and Marangoni) through
// FempProblem. femp reports, besides laser, losses, fixed faces and stored
// enthalpy, the energy created by the upwind convection of T (not a
// conservative scheme) and by points moving between cells (change of the
// stored enthalpy when alpha and the cells that gained metal are updated).
// With these two counted as sources the balance must close to round-off
// (tolerance 1e-3 of the laser energy; it was 6.5e-3 before cells that gain
// metal took gamma(T) with their temperature: a stale gamma = 0 made the
// next step take the latent heat of hot arrivals out of their sensible
// heat). The plain balance error and the two terms are printed (not gated:
// 2.2 % against the 2 % target; it was 7.9 % while alpha of melt cells was
// sub-cell occupancy, which lost metal volume when fluid points bunch; see
// doc/verification.md, "With melt flow"). 1 and 2 ranks give the same output.
#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  const auto   s = run_scene<2>(argv[1], comm);
  const double in = s.laser + std::abs(s.boundary);
  auto r = [](const double x) { return std::round(x * 1000) / 1000; };
  checks.print("laser energy (J/m)", std::round(s.laser * 100) / 100, 4);
  checks.print("balance error (laser + faces - losses - stored) / laser",
               r((s.laser + s.boundary - s.losses - s.stored) / in), 2);
  checks.print("energy created by the upwind convection / laser",
               r(s.advection / in), 2);
  checks.print("energy created by points moving between cells / laser",
               r(s.moved_points / in), 2);
  const double closed = std::abs(s.laser + s.boundary + s.advection +
                                 s.moved_points - s.losses - s.stored) / in;
  checks.at_most("balance error with both counted as sources, next power of ten",
                 closed > 0 ? std::pow(10., std::ceil(std::log10(closed))) : 0.,
                 1e-3);
  return checks.exit_code();
}
