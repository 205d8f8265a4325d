// A drop that solidifies while detached and still moving with the melt
// flow's velocity is stopped by the next gather, and a re-sort after that
// does not count it as a member that the solid carried into the drop
// (SolidPointStore::exchange_since_gather(), Exchange::n_stopped;
// doc/solid.md "Detached drops").
//
// A 2D block (1.6 m x 0.8 m, cells of 0.1 m, 2 x 2 points per cell,
// E = 100 Pa, rho = 1, elastic; bottom fixed, sides on rollers, solidus
// 1000 K) with its top at y = 0.3 m, and two drops of one cell each in the
// gas:
//   D1 at (0.8 .. 0.9, 0.5 .. 0.6), fluid at 1500 K, its cell detached
//      from the start (out of the solid); the solid runs beside a melt
//      flow, so the fluid points keep their velocity;
//   D2 in the top row (y 0.7 .. 0.8), solid, moving at 1 m/s along x from
//      the cell left of a boundary between two ranks (on one rank: of the
//      cell at x = 0.3 .. 0.4); it crosses that boundary in the second
//      step (0.02 m in the first, 0.04 m after two, its right points
//      start 0.025 m from it), so on two ranks the solid re-sorts its
//      points in the second step.
// After the first temperature step (0.02 s) D1's points are given 0.2 m/s
// along x (as the flow would leave them) and solidify in place (their
// cell below the solidus, MaterialPoints::cells_to_points()); the cell
// stays detached. The second step's gather must stop them (at rest,
// stress-free, out of the solid); the re-sort in that step on two ranks
// must then find the solid's points unchanged. Without the stop, one rank
// finds D1 still moving after the gather, and two ranks stop with
// "material point(s) lost in re-sorting" (196 found, 192 expected). Runs
// on 1 and 2 ranks against one output.
#include <femp/grid/material_points.h>
#include <femp/solid/solid_sub_cycle.h>

#include "solid_tools.h"

using namespace femp_test;

namespace
{
  constexpr int dim = 2;
  using P           = MaterialPoints<dim>::PropertyIndex;

  /// Number, largest speed and largest |stress| of the points in the box
  /// [a, b], all ranks.
  std::array<double, 3>
  points_in(const MaterialPoints<dim> &points,
            const Point<dim>          &a,
            const Point<dim>          &b,
            MPI_Comm                   comm)
  {
    double n = 0, m[2] = {0, 0};
    for (const auto &p : points.particle_handler())
      {
        const auto &x = p.get_location();
        if (x[0] < a[0] || x[0] > b[0] || x[1] < a[1] || x[1] > b[1])
          continue;
        const auto q = p.get_properties();
        n += 1;
        m[0] = std::max(m[0], std::hypot(q[P::velocity], q[P::velocity + 1]));
        for (unsigned int k = P::stress; k < P::stress + 3; ++k)
          m[1] = std::max(m[1], std::abs(q[k]));
      }
    n = Utilities::MPI::sum(n, comm);
    Utilities::MPI::max(ArrayView<const double>(m, 2),
                        comm,
                        ArrayView<double>(m, 2));
    return {{n, m[0], m[1]}};
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
  Material         material = unit_material();
  material.solidus          = 1000;
  material.liquidus         = 1100;
  SolidBlock<dim> block(size, h, 0.3, material, comm);
  auto           &grid = block.grid;

  // The first cell of the top row whose right neighbour another rank
  // owns (the lowest such on every rank); on one rank the fourth cell.
  const int j_top = 7;
  int       i_b   = 3;
  {
    const unsigned int        n_x = 16;
    std::vector<unsigned int> owner(n_x, 0);
    const unsigned int        rank = Utilities::MPI::this_mpi_process(comm);
    for (unsigned int i = 0; i < n_x; ++i)
      {
        const auto ijk = grid.cell_of(Point<dim>((i + 0.5) * h, 0.75));
        if (grid.in_box(ijk) && grid.cell_status()[grid.local_index(ijk)] ==
                                  BackgroundGrid<dim>::owned)
          owner[i] = rank;
      }
    Utilities::MPI::max(owner, comm, owner);
    for (unsigned int i = 0; i + 1 < n_x; ++i)
      if (owner[i] != owner[i + 1])
        {
          i_b = int(i);
          break;
        }
  }
  const Point<dim> d1_a(0.8, 0.5), d1_b(0.9, 0.6);
  const Point<dim> d2_a(i_b * h, j_top * h), d2_b((i_b + 1) * h, 0.8);
  {
    typename MaterialPoints<dim>::Parameters pp;
    pp.point_spacing   = h / 2;
    pp.substrate_top   = 0.3;
    pp.layer_thickness = 0;
    pp.subcells        = 2;
    typename MaterialPoints<dim>::Parameters::Body d1, d2;
    d1.state  = MaterialPoints<dim>::fluid;
    d1.a      = d1_a;
    d1.b      = d1_b;
    d1.T      = 1500;
    d2.state  = MaterialPoints<dim>::solid;
    d2.a      = d2_a;
    d2.b      = d2_b;
    d2.T      = 300;
    pp.bodies = {d1, d2};
    block.points =
      std::make_unique<MaterialPoints<dim>>(pp, block.material, grid);
    block.points->create(300.);
  }
  auto &points = *block.points;
  for (auto &p : points.particle_handler_for_update())
    if (p.get_location()[1] > j_top * h)
      p.get_properties()[P::velocity] = 1.0;

  const SolidMaterial sm = elastic_block_material(block.material);
  auto                sp = block_supports<dim>();
  SolidSubCycle<dim>  solid(
    sp, fe_block<dim>(false, size, 0.), sm, grid, points);
  solid.set_flow_owns_fluid_points(true);
  // D1's cell hot in the first step, everything at 300 K after.
  std::vector<double>        T_hot = grid.make_field(300.);
  const auto                 T     = grid.make_field(300.);
  std::vector<std::uint32_t> d1_cell;
  {
    const auto ijk = grid.cell_of(Point<dim>(0.85, 0.55));
    if (grid.in_box(ijk))
      {
        const auto idx = grid.local_index(ijk);
        T_hot[idx]     = 1500;
        if (grid.cell_status()[idx] == BackgroundGrid<dim>::owned)
          d1_cell.push_back(idx);
      }
  }
  solid.initialize(T_hot, "");
  const double n_solid0 = solid.sizes()[0];

  checks.in_range("points in D1", points_in(points, d1_a, d1_b, comm)[0], 4, 4);
  // As the problem does: the detached cells before every step.
  solid.set_detached_cells(d1_cell);
  solid.advance(0.02, T_hot, false);

  // D1 solidifies in place with the flow's velocity, still detached.
  for (auto &p : points.particle_handler_for_update())
    {
      const auto &x = p.get_location();
      if (x[0] > d1_a[0] && x[0] < d1_b[0] && x[1] > d1_a[1] && x[1] < d1_b[1])
        p.get_properties()[P::velocity] = 0.2;
    }
  points.cells_to_points(T);
  const auto before = points_in(points, d1_a, d1_b, comm);
  checks.in_range("D1 solid and moving: largest speed (m/s)",
                  before[1],
                  0.2,
                  0.2);

  for (int s = 2; s <= 3; ++s)
    {
      solid.set_detached_cells(d1_cell);
      solid.advance(0.02 * s, T, s == 3);
    }

  const auto after = points_in(points, d1_a, d1_b, comm);
  checks.in_range("D1: points in its cell", after[0], 4, 4);
  checks.at_most("D1: largest speed after the next gather (m/s)", after[1], 0);
  checks.at_most("D1: largest |stress| (Pa)", after[2], 0);
  checks.in_range("points in the solid / at the start",
                  solid.sizes()[0] / n_solid0,
                  1,
                  1);
  checks.in_range("times a point was set aside",
                  solid.n_points_set_aside(),
                  0,
                  0);
  // D2 crossed into the next cell (on two ranks: the other rank's).
  checks.in_range("D2: points past the cell boundary",
                  points_in(points,
                            Point<dim>(d2_b[0], d2_a[1]),
                            Point<dim>(d2_b[0] + h, d2_b[1]),
                            comm)[0],
                  2,
                  2);
  return checks.exit_code();
}
