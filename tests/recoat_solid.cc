// The recoater's blade sweeps a detached body that the solid owns, and the
// solid accounts for it (builds/recoater.h, SolidSubCycle::
// before_points_removed() and points_removed(); doc/builds.md "Recoating").
//
// A 2D block (1.6 m x 0.8 m, cells of 0.1 m, 2 x 2 points per cell,
// E = 100 Pa, rho = 1, elastic; bottom fixed, sides on rollers; finite
// elements below y = 0.2 m) with its top at y = 0.3 m, and a body of two
// cells of solid points in the gas, (0.8 .. 1.0, 0.5 .. 0.6), eight
// points moving at 0.2 m/s along x. Nothing is set aside: the body is a
// member of the solid. Three temperature steps of 0.02 s; then layer 2
// (top 0.45 m) is recoated: the blade sweeps the body (it reaches above
// the top and no metal joins it to the block), grains (0.1-0.2 m) fill
// the 0.15 m above the block; then three more steps.
//   1. told of the sweep (the hooks): the solid removes exactly the
//      body's eight points (the count it reports and its size before and
//      after), the kinetic energy it books with the melted points is the
//      body's, 8 x m v^2 / 2 (nothing else moves), the next steps run (the
//      gather's point count holds) and the energy balance stays zero;
//   2. not told (the same scene, no hooks): the next step stops with the
//      solid's "lost in the gather" message: the count check is what
//      catches a point deleted behind the solid's back.
// Runs on 1 and 2 ranks against one output.
#include <femp/builds/recoater.h>
#include <femp/grid/material_points.h>
#include <femp/grid/metal_bodies.h>
#include <femp/solid/solid_sub_cycle.h>

#include <cstring>

#include "solid_tools.h"

using namespace femp_test;

namespace
{
  constexpr int dim = 2;
  using P           = MaterialPoints<dim>::PropertyIndex;

  struct Result
  {
    double n_start = 0, n_before = 0, n_after = 0, n_end = 0;
    double removed = 0, swept_points = 0, swept_bodies = 0, grains = 0;
    double melted = 0, balance = 0;
    bool   stopped = false;
  };

  Result
  run(const bool tell_solid, MPI_Comm comm)
  {
    const double     h = 0.1;
    const Point<dim> size(1.6, 0.8);
    SolidBlock<dim>  block(size, h, 0.3, unit_material(), comm);
    auto            &grid = block.grid;
    add_solid_box(block, h, 0.3, Point<dim>(0.8, 0.5), Point<dim>(1.0, 0.6));
    auto &points = *block.points;
    for (auto &p : points.particle_handler_for_update())
      if (p.get_location()[1] > 0.45)
        p.get_properties()[P::velocity] = 0.2;

    const SolidMaterial       sm = elastic_block_material(block.material);
    SolidSubCycle<dim>        solid(block_supports<dim>(),
                             fe_zone(Point<dim>(0, 0), Point<dim>(1.6, 0.2)),
                             sm,
                             grid,
                             points);
    const std::vector<double> T = grid.make_field(300.);
    solid.initialize(T, "");
    Result res;
    res.n_start = solid.sizes()[0];

    int s = 0;
    for (; s < 3; ++s)
      solid.advance(0.02 * (s + 1), T, false);
    res.n_before        = solid.sizes()[0];
    const double melted = solid.energies().melted;

    // Layer 2: the powder of grains 0.1-0.2 m across on the point lattice.
    typename MaterialPoints<dim>::Parameters pp;
    pp.point_spacing    = h / 2;
    pp.subcells         = 2;
    pp.substrate_top    = 0.3;
    pp.layer_thickness  = 0;
    pp.mean_diameter    = 0.15;
    pp.std_diameter     = 0.02;
    pp.min_diameter     = 0.1;
    pp.max_diameter     = 0.2;
    pp.packing_fraction = 0.35;
    pp.seed             = 3;
    const Recoater<dim>                recoater(pp, 1., grid);
    typename LayerSchedule<dim>::Layer layer;
    layer.number        = 2;
    layer.start_time    = 0.06;
    layer.top           = 0.45;
    layer.thickness     = 0.15;
    const auto alpha    = points.metal_fraction();
    const auto attached = attached_metal_cells(grid, alpha);
    typename Recoater<dim>::RemovalHook hook;
    if (tell_solid)
      hook = [&](const std::vector<types::particle_index> &ids) {
        solid.before_points_removed(ids);
      };
    const auto r =
      recoater.recoat(points, layer, 300., alpha, attached, {}, hook);
    res.removed      = solid.points_removed();
    res.swept_points = r.swept_points;
    res.swept_bodies = r.swept_bodies;
    res.grains       = r.grains;
    res.n_after      = solid.sizes()[0];
    res.melted       = solid.energies().melted - melted;

    try
      {
        for (; s < 6; ++s)
          solid.advance(0.02 * (s + 1), T, s == 5);
      }
    catch (const std::exception &e)
      {
        res.stopped = std::strstr(e.what(), "lost in the gather") != nullptr;
        if (!res.stopped)
          throw;
        return res;
      }
    res.n_end   = solid.sizes()[0];
    res.balance = solid.energies().balance();
    return res;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);

  // The body: 8 points of mass rho (h/2)^2 at 0.2 m/s.
  const double n_body = 8;
  const double K_body = n_body * 0.5 * 0.05 * 0.05 * 0.2 * 0.2;

  const Result a = run(true, comm);
  checks.print("told: points in the solid at the start", a.n_start);
  checks.print("told: grains of the new layer", a.grains);
  checks.at_most("told: |bodies swept - 1|", std::abs(a.swept_bodies - 1), 0);
  checks.at_most("told: |points swept - the body's 8|",
                 std::abs(a.swept_points - n_body),
                 0);
  checks.at_most("told: |solid points removed - 8|",
                 std::abs(a.removed - n_body),
                 0);
  checks.at_most("told: |points in the solid before - after - 8|",
                 std::abs(a.n_before - a.n_after - n_body),
                 0);
  checks.at_most("told: |points in the solid at the end - after the sweep|",
                 std::abs(a.n_end - a.n_after),
                 0);
  checks.at_most("told: the steps after the sweep stopped (0 = no)",
                 a.stopped ? 1 : 0,
                 0);
  checks.at_most("told: |kinetic energy booked - the body's| / the body's",
                 std::abs(a.melted - K_body) / K_body,
                 1e-12);
  checks.at_most("told: |energy balance of the solid| / the body's kinetic "
                 "energy",
                 std::abs(a.balance) / K_body,
                 1e-10);

  const Result b = run(false, comm);
  checks.at_most("not told: |points swept - the body's 8|",
                 std::abs(b.swept_points - n_body),
                 0);
  checks.at_most("not told: the next step stops with a lost-points count "
                 "(0 = yes)",
                 b.stopped ? 0 : 1,
                 0);
  return checks.exit_code();
}
