// Light grid nodes (doc/solid.md "Small node masses"): a fragment left by
// the flow with its point near a cell face gives the opposite nodes a tiny
// mass but a full shape-function gradient.
//
// A 2D block (1.6 m x 0.8 m, cells of 0.1 m, 2 x 2 points per cell,
// E = 100 Pa, rho = 1, elastic; bottom fixed, sides on rollers) with its
// top at y = 0.3 m, and one solid point on it in the cell [0.8, 0.9] x
// [0.3, 0.4] at local coordinates (xi, xi). The fragment starts at 0.2 m/s
// in x and y; ten temperature steps of 0.02 s.
// - 'no force' ('Small mass cutoff' 0.5, xi = 1/4: the top nodes at 3/16
//   and 1/16 of a full cell's node are light): the light nodes take no
//   force, the work the withheld force would have done is booked. Checked:
//   the withheld work is many times the initial kinetic energy K0 and the
//   balance a small fraction of it. Printed: the stress work over that of
//   the run without a cutoff, the straining that this update allows (a
//   fragment anchored by its heavy nodes and moving at its light ones is
//   strained at a constant rate).
// - 'mass floor': at xi = 1/4 and C = 0.5 no node lies below its floor,
//   and the run is that without a cutoff to round-off. At xi = 0.02 and
//   C = 0.8 (the paper-scale fast scene's C) the run without protection
//   collapses the point (checked: the instability is detected), while
//   with the floor it is stable, the balance with the withheld work booked
//   closes to a few per cent of K0, and the stress work stays within a
//   small factor of that of the fragment at xi = 1/4.
// Runs on 1 and 2 ranks against one output.
#include <femp/grid/material_points.h>
#include <femp/solid/solid_sub_cycle.h>

#include <cmath>

#include "solid_tools.h"

using namespace femp_test;

namespace
{
  constexpr int dim = 2;
  using P           = MaterialPoints<dim>::PropertyIndex;

  /// The solid's energies after the run with the small-mass cutoff
  /// @p cutoff or (@p floor) the mass floor, the fragment's point at local
  /// coordinates (@p xi, @p xi) of its cell, safety factor @p C.
  SolidSubCycle<dim>::Energies
  run(const double cutoff,
      const bool   floor,
      const double xi,
      const double C,
      MPI_Comm     comm,
      Checks      &checks)
  {
    const double     h = 0.1;
    const Point<dim> size(1.6, 0.8);
    SolidBlock<dim>  block(size, h, 0.3, unit_material(), comm);
    auto            &grid = block.grid;
    add_solid_box(block, h, 0.3, Point<dim>(0.8, 0.3), Point<dim>(0.85, 0.35));
    auto  &points     = *block.points;
    double n_fragment = 0;
    for (auto &p : points.particle_handler_for_update())
      if (p.get_location()[1] > 0.3)
        {
          p.get_properties()[P::velocity]     = 0.2;
          p.get_properties()[P::velocity + 1] = 0.2;
          p.set_location(Point<dim>(0.8 + xi * h, 0.3 + xi * h));
          ++n_fragment;
        }
    checks.in_range("points of the fragment",
                    Utilities::MPI::sum(n_fragment, comm),
                    1,
                    1);

    const SolidMaterial sm = elastic_block_material(block.material);
    auto                sp = block_supports<dim>();
    sp.safety_factor       = C;
    SolidSubCycle<dim> solid(
      sp, fe_block<dim>(false, size, 0.), sm, grid, points);
    const std::vector<double> T = grid.make_field(300.);
    solid.initialize(T, "");
    solid.set_small_mass_cutoff(cutoff);
    solid.set_mass_floor(floor);
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

  const auto   e0 = run(0, false, 0.25, 0.5, comm, checks);
  const auto   e  = run(0.5, false, 0.25, 0.5, comm, checks);
  const double K0 = 0.5 * 0.05 * 0.05 * 2 * 0.2 * 0.2;
  checks.in_range("initial kinetic energy / the fragment's",
                  e.initial_kinetic / K0,
                  1 - 1e-12,
                  1 + 1e-12);
  checks.at_most("no cutoff: |energy balance| / K0",
                 std::abs(e0.balance()) / K0,
                 0.03);
  checks.in_range("no force, cutoff 0.5: |withheld work| / K0",
                  std::abs(e.withheld) / K0,
                  10,
                  1e6);
  checks.at_most("no force, cutoff 0.5: |energy balance| / |withheld work|",
                 std::abs(e.balance()) / std::abs(e.withheld),
                 0.03);
  checks.print("no force, cutoff 0.5: stress work / no cutoff (hundreds)",
               std::round(e.internal / e0.internal / 100),
               2);

  // The floor where no node needs it: the same run.
  const auto f0 = run(0, true, 0.25, 0.5, comm, checks);
  checks.at_most("mass floor, xi 1/4: |stress work / no cutoff - 1|",
                 std::abs(f0.internal / e0.internal - 1),
                 1e-12);
  checks.at_most("mass floor, xi 1/4: |withheld work| / K0",
                 std::abs(f0.withheld) / K0,
                 1e-12);

  // A point 0.02 h from the lower and left faces, C = 0.8.
  bool collapsed = false;
  try
    {
      run(0, false, 0.02, 0.8, comm, checks);
    }
  catch (const std::exception &x)
    {
      collapsed = std::string(x.what()).find("collapsed") != std::string::npos;
    }
  checks.in_range("no protection, xi 0.02, C 0.8: collapse detected",
                  collapsed ? 1 : 0,
                  1,
                  1);
  const auto f = run(0, true, 0.02, 0.8, comm, checks);
  checks.in_range("mass floor, xi 0.02, C 0.8: |withheld work| / K0",
                  std::abs(f.withheld) / K0,
                  0.01,
                  10);
  checks.at_most("mass floor, xi 0.02, C 0.8: |energy balance| / K0",
                 std::abs(f.balance()) / K0,
                 0.04);
  checks.in_range("mass floor, xi 0.02, C 0.8: stress work / xi 1/4's",
                  f.internal / e0.internal,
                  0.5,
                  3);
  return checks.exit_code();
}
