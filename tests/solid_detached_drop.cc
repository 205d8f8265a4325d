// Solid points of a detached drop are set aside, out of the solid, and
// come back when the drop is no longer detached (SolidSubCycle::
// set_detached_cells(), SolidMPM::set_aside_cells(); doc/solid.md
// "Detached drops").
//
// A 2D block (1.6 m x 0.8 m, cells of 0.1 m, 2 x 2 points per cell,
// E = 100 Pa, rho = 1, elastic; bottom fixed, sides on rollers) with its
// top at y = 0.3 m, and one cell of solid points above it in the gas, at
// (0.8 .. 0.9, 0.5 .. 0.6): a drop of four points, given a velocity of
// 0.2 m/s along x. Nine temperature steps of 0.02 s, in three phases:
//   A. steps 1-3, no detached cell: the drop is part of the solid and,
//      alone in its cell and unstressed, keeps its velocity (APIC moves a
//      uniform velocity exactly): it moves by 0.2 m/s times the time the solid
//      has stepped (it lags the temperature step by less than its step);
//   B. steps 4-6, the drop's cell detached: its points leave the solid
//      (the solid counts the substrate's points only), at rest and
//      stress-free; they do not move; their kinetic energy is booked with
//      what melting removes;
//   C. steps 7-9, detached no more: the points rejoin at rest (booked as
//      solidified, with no kinetic energy) and stay where they are.
// The energy balance of the solid stays zero (nothing else moves). Runs
// on 1 and 2 ranks against one output.
#include <femp/grid/material_points.h>
#include <femp/solid/solid_sub_cycle.h>

#include "solid_tools.h"

using namespace femp_test;

namespace
{
  constexpr int dim = 2;
  using P           = MaterialPoints<dim>::PropertyIndex;

  struct DropState
  {
    double n = 0, x = 0, vx = 0, speed = 0, stress = 0;
  };

  /// Number, mean x, mean and largest speed, largest |stress| of the
  /// points above y = 0.45 m (the drop), all ranks.
  DropState
  drop_state(const MaterialPoints<dim> &points, MPI_Comm comm)
  {
    double s[3] = {0, 0, 0}, m[2] = {0, 0};
    for (const auto &p : points.particle_handler())
      {
        if (p.get_location()[1] < 0.45)
          continue;
        const auto q = p.get_properties();
        s[0] += 1, s[1] += p.get_location()[0], s[2] += q[P::velocity];
        m[0] = std::max(m[0], std::hypot(q[P::velocity], q[P::velocity + 1]));
        for (unsigned int k = P::stress; k < P::stress + 3; ++k)
          m[1] = std::max(m[1], std::abs(q[k]));
      }
    Utilities::MPI::sum(ArrayView<const double>(s, 3),
                        comm,
                        ArrayView<double>(s, 3));
    Utilities::MPI::max(ArrayView<const double>(m, 2),
                        comm,
                        ArrayView<double>(m, 2));
    DropState d;
    d.n = s[0], d.x = s[0] > 0 ? s[1] / s[0] : 0,
    d.vx = s[0] > 0 ? s[2] / s[0] : 0, d.speed = m[0], d.stress = m[1];
    return d;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);

  const double     h = 0.1;
  const Point<dim> size(1.6, 0.8);
  SolidBlock<dim>  block(size, h, 0.3, unit_material(), comm);
  auto            &grid = block.grid;
  // The substrate and the drop (an initial body of solid points).
  add_solid_box(block, h, 0.3, Point<dim>(0.8, 0.5), Point<dim>(0.9, 0.6));
  auto &points = *block.points;
  for (auto &p : points.particle_handler_for_update())
    if (p.get_location()[1] > 0.45)
      p.get_properties()[P::velocity] = 0.2;

  const SolidMaterial sm = elastic_block_material(block.material);
  auto                sp = block_supports<dim>();
  SolidSubCycle<dim>  solid(
    sp, fe_block<dim>(false, size, 0.), sm, grid, points);
  const std::vector<double> T = grid.make_field(300.);
  solid.initialize(T, "");
  const double n_all = solid.sizes()[0];

  // The drop's cell, on the rank that owns it.
  std::vector<std::uint32_t> drop_cell;
  {
    const auto ijk = grid.cell_of(Point<dim>(0.85, 0.55));
    if (grid.in_box(ijk))
      {
        const auto idx = grid.local_index(ijk);
        if (grid.cell_status()[idx] == BackgroundGrid<dim>::owned)
          drop_cell.push_back(idx);
      }
  }

  const DropState d0 = drop_state(points, comm);
  checks.in_range("points in the drop", d0.n, 4, 4);
  DropState after[3];
  double    n_solid[3];
  double    energy_melted[3], energy_solidified[3], t_solid[3];
  int       s = 0;
  for (int phase = 0; phase < 3; ++phase)
    {
      for (int k = 0; k < 3; ++k)
        {
          ++s;
          solid.set_detached_cells(phase == 1 ? drop_cell :
                                                std::vector<std::uint32_t>());
          solid.advance(0.02 * s, T, s == 9);
        }
      after[phase]             = drop_state(points, comm);
      t_solid[phase]           = solid.time();
      n_solid[phase]           = solid.sizes()[0];
      const auto e             = solid.energies();
      energy_melted[phase]     = e.melted;
      energy_solidified[phase] = e.solidified;
    }

  const double K_drop = 4 * 0.5 * (h / 2) * (h / 2) * 0.2 * 0.2;
  // A: part of the solid, moving.
  checks.in_range("A: points in the solid / all points",
                  n_solid[0] / n_all,
                  1,
                  1);
  checks.at_most("A: |drop displacement - 0.2 m/s x solid time| (m)",
                 std::abs(after[0].x - d0.x - 0.2 * t_solid[0]),
                 1e-12);
  checks.at_most("A: |drop velocity - 0.2 m/s| (m/s)",
                 std::abs(after[0].vx - 0.2),
                 1e-12);
  // B: set aside.
  checks.in_range("B: points in the solid + 4 / all points",
                  (n_solid[1] + 4) / n_all,
                  1,
                  1);
  checks.in_range("B: times a point was set aside",
                  solid.n_points_set_aside(),
                  4,
                  4);
  checks.at_most("B: drop displacement in the phase (m)",
                 std::abs(after[1].x - after[0].x),
                 1e-15);
  checks.at_most("B: largest drop speed (m/s)", after[1].speed, 0);
  checks.at_most("B: largest drop |stress| (Pa)", after[1].stress, 0);
  checks.at_most("B: |booked kinetic energy - the drop's| / the drop's",
                 std::abs(energy_melted[1] - K_drop) / K_drop,
                 1e-12);
  // C: back, at rest.
  checks.in_range("C: points in the solid / all points",
                  n_solid[2] / n_all,
                  1,
                  1);
  checks.at_most("C: drop displacement in the phase (m)",
                 std::abs(after[2].x - after[1].x),
                 1e-15);
  checks.at_most("C: largest drop speed (m/s)", after[2].speed, 1e-15);
  checks.at_most("C: kinetic energy it brought back (J/m)",
                 energy_solidified[2],
                 0);
  const auto e = solid.energies();
  checks.at_most("|energy balance of the solid| / the drop's kinetic energy",
                 std::abs(e.balance()) / K_drop,
                 1e-10);
  return checks.exit_code();
}
