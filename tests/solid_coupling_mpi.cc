// FEMP coupling over MPI ranks (doc/solid.md, "MPI"): a 2D substrate block,
// 1.6 m x 0.8 m, cells of 0.1 m; finite elements below y = 0.4 m (the
// constant-solid zone), material points above (2 x 2 per cell), so that the
// horizontal FE-MPM interface crosses the rank boundaries of any partition
// along x. Bottom fixed, sides on rollers, gravity, and a hot spot on the
// top that rises linearly in time to 400 K (prescribed cell temperatures,
// no heat solver), with a yield stress that softens with temperature so
// that the top yields. The printed numbers (stresses at probes on both
// sides of the interface, energies, plastic state) must not depend on the
// number of ranks (the test runs on 1, 2 and 3 ranks against one output),
// and the stress must be continuous across the interface.
// Independent partitions: a second scene with an FE zone of 14 x 3 cells
// at the lower right (so that p4est partitions the FE triangulation
// row-wise, unlike the grid's blocks, and the interface has a vertical and
// a horizontal part) puts FE elements on ranks that do not own their grid
// cells; it is run on all ranks and again on one rank alone
// (MPI_COMM_SELF), and the results must agree to round-off.
#include <femp/grid/material_points.h>
#include <femp/solid/solid_sub_cycle.h>

#include "solid_tools.h"

using namespace femp_test;

namespace
{
  /// The second scene: probes (sigma_xx, T) and energies after 10 steps of
  /// heating; @p off_rank: FE elements whose grid cell another rank owns.
  std::vector<double>
  partition_scene(MPI_Comm comm, double &off_rank)
  {
    constexpr int dim = 2;
    const double  h   = 0.1;
    Material      mat = unit_material();
    mat.density       = 1;
    SolidBlock<dim>     block(Point<dim>(1.6, 0.8), h, 0.8, mat, comm);
    auto               &grid   = block.grid;
    auto               &points = *block.points;
    const SolidMaterial sm =
      block_material("300:0.02, 400:0.005", block.material);
    auto sp                = block_supports<dim>();
    sp.gravity[1]          = -0.01;
    const auto          fp = fe_zone(Point<dim>(0.2, 0), Point<dim>(1.6, 0.3));
    SolidSubCycle<dim>  solid(sp, fp, sm, grid, points);
    std::vector<double> T = grid.make_field(300.);
    solid.initialize(T, "");
    for (int s = 1; s <= 10; ++s)
      {
        const double t = 0.05 * s;
        hot_spot(grid, Point<dim>(0.3, 0.3), 200 * t, 0.05, T);
        solid.advance(t, T, s == 10);
      }
    off_rank = solid.fe_elements_off_rank();
    std::vector<Point<dim>> probes;
    for (const double x : {0.15, 0.25, 0.85, 1.55})
      for (const double y : {0.05, 0.25, 0.35, 0.75})
        probes.emplace_back(x, y);
    std::vector<double> r;
    for (const auto &v : solid.probe(probes))
      r.push_back(v[0]);
    const auto e = solid.energies();
    for (const double x : {e.internal, e.kinetic, e.hourglass, e.external})
      r.push_back(x);
    return r;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  constexpr int                    dim = 2;
  const double                     h   = 0.1;

  Material mat = unit_material();
  mat.density  = 1;
  SolidBlock<dim> block(Point<dim>(1.6, 0.8), h, 0.8, mat, comm);
  auto           &grid   = block.grid;
  auto           &points = *block.points;

  SolidMaterial sm = block_material("300:0.02, 400:0.005", block.material);
  sm.poisson_ratio = 0.3;
  auto sp          = block_supports<dim>();
  sp.gravity[1]    = -0.01;
  const auto          fp = fe_zone(Point<dim>(0, 0), Point<dim>(1.6, 0.4));
  SolidSubCycle<dim>  solid(sp, fp, sm, grid, points);
  std::vector<double> T = grid.make_field(300.);
  solid.initialize(T, "");

  // Hot spot on the top, rising linearly to 400 K at t = 1 s; the solid is
  // advanced after each of 20 "temperature steps".
  const int n = 20;
  for (int s = 1; s <= n; ++s)
    {
      const double t = double(s) / n;
      hot_spot(grid, Point<dim>(0.8, 0.8), 100 * t, 0.05, T);
      solid.advance(t, T, s == n);
    }

  const auto sizes = solid.sizes();
  checks.print("material points", sizes[0], 6);
  checks.print("finite elements", sizes[1], 6);
  checks.print("solid steps", solid.n_steps(), 6);
  // Probes: columns at x = 0.25, 0.85 and 1.35, cells just below (FE) and
  // above (MPM) the interface y = 0.4, and one near the top.
  std::vector<Point<dim>> probes;
  for (const double x : {0.25, 0.85, 1.35})
    for (const double y : {0.35, 0.45, 0.75})
      probes.emplace_back(x, y);
  const auto v    = solid.probe(probes);
  double     jump = 0, scale = 0;
  for (std::size_t i = 0; i < probes.size(); ++i)
    {
      std::ostringstream s;
      s << "sigma_xx at (" << probes[i][0] << ", " << probes[i][1]
        << ") / 1e-3";
      checks.print(s.str(), v[i][0] / 1e-3, 4);
      scale = std::max(scale, std::abs(v[i][0]));
    }
  for (int c = 0; c < 3; ++c)
    jump = std::max(jump, std::abs(v[3 * c][0] - v[3 * c + 1][0]));
  const auto e = solid.energies();
  checks.print("stress work / 1e-6", e.internal / 1e-6, 4);
  checks.print("kinetic energy / 1e-9", e.kinetic / 1e-9, 3);
  checks.print("hourglass energy / 1e-9", e.hourglass / 1e-9, 3);
  checks.print("external work / 1e-6", e.external / 1e-6, 4);
  checks.print("transfer dissipation / stress work",
               e.transfer / e.internal,
               2);
  checks.print("transfer dissipation / 1e-9", e.transfer / 1e-9, 3);
  // Continuity: the stress steps across the interface (one cell apart) by
  // much less than its size in the block.
  checks.at_most("max |sigma_xx(0.35) - sigma_xx(0.45)| / max |sigma_xx|",
                 jump / scale,
                 0.3);
  checks.at_most("energy balance (transfer dissipation booked) / stress work",
                 std::abs(e.balance() / e.internal),
                 0.05);

  // Melting and re-solidification of the points of one hot cell: lower the
  // solidus to 450 K, heat the cell at (0.85, 0.75) to 500 K (its points
  // turn fluid and leave the solid for one solid step), then cool it to
  // just below the solidus: the points come back stress-free, so after a
  // short step (1 % of a solid step) their stress is tiny, not the -0.06 Pa
  // they carried before. (After a full step it is the elastic response to
  // the strain rate with which the neighbours, relaxed into the molten
  // cell, compress it: 0.16 of the former stress with APIC, 0.015 with
  // FLIP, whose transfers smooth the nodal velocities; doc/solid.md.)
  {
    block.material.solidus = 450; // the material of the points and the solid
    const Point<dim> hot(0.85, 0.75);
    const auto       ijk = grid.cell_of(hot);
    const bool       mine =
      grid.in_box(ijk) &&
      grid.cell_status()[grid.local_index(ijk)] == BackgroundGrid<dim>::owned;
    const double before = solid.probe({hot})[0][0];
    double       t      = solid.time();
    for (const double T_hot : {500., 449.999})
      {
        if (mine)
          T[grid.local_index(ijk)] = T_hot;
        points.cells_to_points(T);
        t += (T_hot > 450 ? 1 : 0.01) * solid.time_step();
        solid.advance(t, T, true);
      }
    const double after = solid.probe({hot})[0][0];
    checks.print("re-solidified cell: sigma_xx before melting / 1e-3",
                 before / 1e-3,
                 4);
    checks.at_most("re-solidified cell: |sigma_xx after| / |sigma_xx before|",
                   std::abs(after / before),
                   0.05);
  }

  // Independent partitions of the FE triangulation and the grid.
  {
    double              off_rank = 0, off_self = 0;
    const auto          all = partition_scene(comm, off_rank);
    std::vector<double> self(all.size(), 0.);
    if (Utilities::MPI::this_mpi_process(comm) == 0)
      self = partition_scene(MPI_COMM_SELF, off_self);
    self        = Utilities::MPI::broadcast(comm, self, 0);
    double diff = 0, scale = 0;
    for (std::size_t i = 0; i < all.size(); ++i)
      {
        diff  = std::max(diff, std::abs(all[i] - self[i]));
        scale = std::max(scale, std::abs(self[i]));
      }
    const unsigned int n_ranks = Utilities::MPI::n_mpi_processes(comm);
    checks.print("partition scene: stress work / 1e-6", all[16] / 1e-6, 4);
    checks.print("partition scene: sigma_xx at (0.25, 0.25) / 1e-3",
                 all[5] / 1e-3,
                 4);
    checks.in_range("partition scene: FE elements on ranks that do not own "
                    "their grid cell (some with several ranks, none on one)",
                    n_ranks == 1 ? off_rank == 0 : off_rank > 0,
                    1,
                    1);
    checks.in_range("partition scene: max difference to a one-rank run / "
                    "max value below 1e-9",
                    diff <= 1e-9 * scale,
                    1,
                    1);
  }
  return checks.exit_code();
}
