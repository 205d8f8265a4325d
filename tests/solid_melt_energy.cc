// Energy balance of the solid with melting and re-solidification
// (doc/verification.md, "Energy balances of the solid"; doc/solid.md
// "Energies"). A 2D block, 1.6 m x 0.8 m, cells of 0.1 m: finite elements below
// y = 0.3 m, material points above (2 x 2 per cell); bottom fixed, sides on
// rollers. A hot spot on the top (prescribed cell temperatures, no heat solver)
// heats the block fast enough (peak in 0.3 s, about 4 wave transits of the
// block) that the block rings: the points that melt (cells above the solidus,
// 450 K) leave the solid with kinetic energy (booked, and dropped: without the
// melt flow a melted point is at rest), and when the spot cools they come back
// (solidify) at rest and stress-free. The balance
//   W_ext + W_remap - (K - K_0) - W_int - E_HG - D_transfer - K_melted
//     + K_solidified
// (W_remap: the MUSL re-map work, doc/solid.md "Energies") must vanish up
// to the time-discretization error of the stress work; the test prints it
// relative to the stress work |W_int| and fails above 0.05, the tolerance
// of the coupling test and of case 3.1 (whose balance is 1-2 % of the
// scale). Also printed: the same balance without the melt terms and
// without the transfer term (to show what they carry), the number of
// points that melted. Gated for APIC, the default transfer; with FLIP the
// balance is printed only (0.07 since the re-map work is booked; before,
// the booked transfer term counted the kinetic energy dt^2 f^2 / 2m that
// the grid update gives nodes with little point mass and the balance was
// 3.0).
// Runs on 1 and 2 ranks against one output. Optional argument: a directory
// for the energy files of both runs.
#include <femp/grid/material_points.h>
#include <femp/solid/solid_sub_cycle.h>

#include "solid_tools.h"

using namespace femp_test;

namespace
{
  constexpr int dim = 2;

  void
  run(const SolidMaterial::VelocityTransfer transfer,
      const std::string                    &name,
      Checks                               &checks,
      MPI_Comm                              comm,
      const std::string                    &directory)
  {
    const double h   = 0.1;
    Material     mat = unit_material();
    mat.solidus      = 450;
    mat.liquidus     = 460;
    SolidBlock<dim> block(Point<dim>(1.6, 0.8), h, 0.8, mat, comm);
    auto           &grid   = block.grid;
    auto           &points = *block.points;

    SolidMaterial sm     = block_material("300:0.05, 450:0.01", block.material);
    sm.poisson_ratio     = 0.3;
    sm.velocity_transfer = transfer;
    auto       sp        = block_supports<dim>();
    const auto fp        = fe_zone(Point<dim>(0, 0), Point<dim>(1.6, 0.3));
    if (!directory.empty())
      sp.energy_file = "solid_melt_energy_" + name + ".csv";
    SolidSubCycle<dim>  solid(sp, fp, sm, grid, points);
    std::vector<double> T = grid.make_field(300.);
    solid.initialize(T, directory);
    const double n0 = solid.sizes()[0];

    // Temperature steps of 0.02 s; amplitude up to 300 K at t = 0.3 s
    // (peak 600 K: the top cells melt), down to 100 K at t = 0.6 s (all
    // solid again), then held to t = 0.8 s.
    const int n            = 40;
    double    n_melted_max = 0;
    for (int s = 1; s <= n; ++s)
      {
        const double t = 0.02 * s;
        const double A =
          t < 0.3 ? 1000 * t : (t < 0.6 ? 300 - 200 * (t - 0.3) / 0.3 : 100);
        hot_spot(grid, Point<dim>(0.8, 0.8), A, 0.04, T);
        points.cells_to_points(T);
        solid.advance(t, T, s == n);
        n_melted_max = std::max(n_melted_max, n0 - solid.sizes()[0]);
      }

    const auto   e     = solid.energies();
    const double scale = std::abs(e.internal);
    checks.print(name + ": solid steps", solid.n_steps(), 6);
    checks.print(name + ": most points melted at once", n_melted_max, 6);
    checks.print(name + ": points in the solid at the end / at the start",
                 solid.sizes()[0] / n0,
                 6);
    checks.print(name + ": stress work / 1e-6", e.internal / 1e-6, 3);
    checks.print(name + ": kinetic energy / stress work", e.kinetic / scale, 2);
    checks.print(name + ": melted / stress work", e.melted / scale, 2);
    checks.print(name + ": solidified / stress work", e.solidified / scale, 2);
    checks.print(name + ": transfer dissipation / stress work",
                 e.transfer / scale,
                 2);
    checks.print(name + ": re-map work / stress work", e.remap / scale, 2);
    const double without_melt = e.balance() + e.melted - e.solidified;
    checks.print(name + ": balance without the melt terms / stress work",
                 std::abs(without_melt) / scale,
                 1);
    checks.print(name + ": balance without the transfer term / stress work",
                 std::abs(e.balance() + e.transfer) / scale,
                 1);
    checks.in_range(name + ": points melted and came back (1 = yes)",
                    n_melted_max > 0 && solid.sizes()[0] == n0,
                    1,
                    1);
    if (transfer == SolidMaterial::VelocityTransfer::apic)
      checks.at_most(name + ": |energy balance| / |stress work|",
                     std::abs(e.balance()) / scale,
                     0.05);
    else // see the header comment
      checks.print(name + ": |energy balance| / |stress work| (printed)",
                   std::abs(e.balance()) / scale,
                   1);
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  // Optional argument: a directory for the energy files (CSV).
  const std::string dir = argc > 1 ? argv[1] : "";
  run(SolidMaterial::VelocityTransfer::apic, "APIC", checks, comm, dir);
  run(SolidMaterial::VelocityTransfer::flip, "FLIP", checks, comm, dir);
  return checks.exit_code();
}
