// Light grid nodes ('Solid/Small mass cutoff', doc/solid.md "Small node
// masses"): a node lighter than the cutoff takes no force and keeps its
// velocity, while the stress rate of the points around it sees that
// velocity; the work the withheld force would have done is booked in the
// solid's energy balance (Energies::withheld).
//
// A 2D block (1.6 m x 0.8 m, cells of 0.1 m, 2 x 2 points per cell,
// E = 100 Pa, rho = 1, elastic; bottom fixed, sides on rollers) with its
// top at y = 0.3 m, and one solid point on it, at (0.825, 0.325) m, as a
// fragment left by the flow would be: the top nodes of its cell get 3/16
// and 1/16 of a full cell's node mass. The fragment starts at 0.2 m/s in x
// and y; ten temperature steps of 0.02 s, once without a cutoff and once
// with the cutoff 0.5 (both top nodes light). Checked: the cutoff acted
// (the withheld work is many times the initial kinetic energy K0), and
// the balance with it booked is a small fraction of it (without the
// booking the balance would be the withheld work itself). Printed: the
// stress work with the cutoff over that without, the size of the
// straining that the light nodes allow (a fragment anchored by its heavy
// nodes and moving at its light ones is strained at a constant rate).
// Runs on 1 and 2 ranks against one output.
#include <femp/grid/material_points.h>
#include <femp/solid/solid_stress.h>

#include "solid_tools.h"

#include <cmath>

using namespace femp_test;

namespace
{
  constexpr int dim = 2;
  using P           = MaterialPoints<dim>::PropertyIndex;

  /// The solid's energies after the run with the small-mass cutoff
  /// @p cutoff.
  SolidStress<dim>::Energies
  run(const double cutoff, MPI_Comm comm, Checks &checks)
  {
    const double     h = 0.1;
    const Point<dim> size(1.6, 0.8);
    SolidBlock<dim>  block(size, h, 0.3, unit_material(), comm);
    auto &           grid = block.grid;
    add_solid_box(block, h, 0.3, Point<dim>(0.8, 0.3), Point<dim>(0.85, 0.35));
    auto & points     = *block.points;
    double n_fragment = 0;
    for (auto &p : points.particle_handler_for_update())
      if (p.get_location()[1] > 0.3)
        {
          p.get_properties()[P::velocity]     = 0.2;
          p.get_properties()[P::velocity + 1] = 0.2;
          ++n_fragment;
        }
    checks.in_range("points of the fragment",
                    Utilities::MPI::sum(n_fragment, comm), 1, 1);

    const SolidMaterial sm = elastic_block_material(block.material);
    SolidStress<dim>    solid(block_supports<dim>(),
                           fe_block<dim>(false, size, 0.), sm, grid, points);
    const std::vector<double> T = grid.make_field(300.);
    solid.initialize(T, "");
    solid.set_small_mass_cutoff(cutoff);
    for (int s = 1; s <= 10; ++s)
      solid.advance(0.02 * s, T, s == 10);
    return solid.energies();
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);

  const auto   e0 = run(0, comm, checks);
  const auto   e  = run(0.5, comm, checks);
  const double K0 = 0.5 * 0.05 * 0.05 * 2 * 0.2 * 0.2;
  checks.in_range("initial kinetic energy / the fragment's",
                  e.initial_kinetic / K0, 1 - 1e-12, 1 + 1e-12);
  checks.at_most("no cutoff: |energy balance| / K0",
                 std::abs(e0.balance()) / K0, 0.03);
  checks.in_range("cutoff 0.5: |withheld work| / K0",
                  std::abs(e.withheld) / K0, 10, 1e6);
  checks.at_most("cutoff 0.5: |energy balance| / |withheld work|",
                 std::abs(e.balance()) / std::abs(e.withheld), 0.03);
  checks.print("stress work, cutoff 0.5 / no cutoff (hundreds)",
               std::round(e.internal / e0.internal / 100), 2);
  return checks.exit_code();
}
