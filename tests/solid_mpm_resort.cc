// Solid MPM with points that cross cells and ranks
// (doc/solid_implementation.md, "Cell crossing"): a 2D block of material points
// (2 x 2 per cell, no finite elements) given a uniform velocity (1, 0.4) m/s,
// no forces, free faces, moves rigidly by 2.5 cells in x and 1 cell in y (no
// point ends on a cell face) over 0.25 s, in 10 calls of advance() (as after 10
// temperature steps). Points that leave their cell are bound to the new cell,
// moved in the ParticleHandler when the state is written back, and re-sorted
// globally when they enter a cell of another rank (SolidMPM::resort()). Checks,
// for FLIP and APIC: no point lost, every point in the handler's cell that
// contains it, positions equal to the rigid translation, zero stress (a uniform
// velocity has no gradient), velocity unchanged. A third scene throws a block
// of points into the finite-element zone in one step, beyond what its rank sees
// on two ranks: the run must stop with a diagnostic (SolidSubCycle counts the
// solid points at every gather and re-sort). Runs on 1 and 2 ranks against one
// output.
#include <femp/grid/material_points.h>
#include <femp/solid/solid_sub_cycle.h>

#include <map>

#include "test_tools.h"

using namespace femp_test;

namespace
{
  constexpr int dim = 2;

  void
  run(const SolidMaterial::VelocityTransfer transfer,
      const std::string                    &name,
      Checks                               &checks,
      MPI_Comm                              comm)
  {
    const double h  = 0.1;
    const auto   gp = box<dim>(Point<dim>(0, 0), Point<dim>(1.0, 0.5), h);
    BackgroundGrid<dim> grid(gp, comm);
    grid.create();
    Material                                 mat = unit_material();
    typename MaterialPoints<dim>::Parameters pp;
    pp.point_spacing   = h / 2;
    pp.layer_thickness = 0;
    pp.subcells        = 2;
    MaterialPoints<dim> points(pp, mat, grid);
    points.create_region(
      [](const Point<dim> &x) { return x[0] < 0.3 && x[1] < 0.2; },
      300.,
      MaterialPoints<dim>::solid);
    using P = typename MaterialPoints<dim>::PropertyIndex;
    const Tensor<1, dim> u({1., 0.4});
    for (auto &p : points.particle_handler())
      {
        p.get_properties()[P::velocity + 0] = u[0];
        p.get_properties()[P::velocity + 1] = u[1];
      }
    const double n0 = points.n_global_points();

    SolidMaterial sm(mat); // density 1, solidus 1e6
    sm.youngs_modulus    = PiecewiseLinear(1.);
    sm.poisson_ratio     = 0.3;
    sm.velocity_transfer = transfer;
    typename SolidSubCycle<dim>::Parameters sp;
    sp.energy_file = "";
    typename SolidFEM<dim>::Parameters fp;
    fp.enabled = false;
    SolidSubCycle<dim>  solid(sp, fp, sm, grid, points);
    std::vector<double> T = grid.make_field(300.);
    // Initial positions by particle id (to compare with the translation).
    std::map<types::particle_index, Point<dim>> x0;
    for (const auto &p : points.particle_handler())
      x0[p.get_id()] = p.get_location();
    solid.initialize(T, "");
    const double t_end = 0.25;
    for (int s = 1; s <= 10; ++s)
      solid.advance(s * t_end / 10, T, s == 10);

    double err_x = 0, err_v = 0, max_s = 0, wrong_cell = 0;
    for (const auto &[idx, cell] : points.occupied_cells())
      for (const auto &p : points.particle_handler().particles_in_cell(cell))
        {
          const auto x = p.get_location();
          if (grid.cell_of(x) != grid.global_index(idx))
            wrong_cell += 1;
          const auto q = p.get_properties();
          for (int d = 0; d < dim; ++d)
            err_v = std::max(err_v, std::abs(q[P::velocity + d] - u[d]));
          for (unsigned int c = P::stress; c < P::plastic_strain; ++c)
            max_s = std::max(max_s, std::abs(q[c]));
        }
    // Positions against the translation; a point that changed rank has its
    // initial position on the other rank, so gather all of them first.
    {
      std::vector<std::pair<types::particle_index, Point<dim>>> all(x0.begin(),
                                                                    x0.end());
      const auto gathered = Utilities::MPI::all_gather(comm, all);
      std::map<types::particle_index, Point<dim>> global;
      for (const auto &g : gathered)
        for (const auto &e : g)
          global.insert(e);
      for (const auto &p : points.particle_handler())
        err_x = std::max(
          err_x,
          (global.at(p.get_id()) + t_end * u).distance(p.get_location()));
    }
    // Points that changed rank (stderr only: zero on one rank).
    {
      double changed = 0;
      for (const auto &p : points.particle_handler())
        changed += x0.count(p.get_id()) == 0;
      changed = Utilities::MPI::sum(changed, comm);
      if (Utilities::MPI::this_mpi_process(comm) == 0)
        std::cerr << name << ": points that changed rank: " << changed
                  << std::endl;
    }
    err_x      = Utilities::MPI::max(err_x, comm);
    err_v      = Utilities::MPI::max(err_v, comm);
    max_s      = Utilities::MPI::max(max_s, comm);
    wrong_cell = Utilities::MPI::sum(wrong_cell, comm);
    checks.print(name + ": solid steps", solid.n_steps(), 6);
    checks.print(name + ": displacement in cells", t_end * u.norm() / h, 3);
    checks.at_most(name + ": points lost", n0 - points.n_global_points(), 0);
    checks.at_most(name + ": points of the MPM", n0 - solid.sizes()[0], 0);
    checks.at_most(name + ": points outside their handler cell", wrong_cell, 0);
    checks.at_most(name + ": max |x - (x0 + u t)| / h", err_x / h, 1e-9);
    checks.at_most(name + ": max |v - u| / |u|", err_v / u.norm(), 1e-9);
    checks.at_most(name + ": max |sigma| / E",
                   max_s / sm.youngs_modulus.value(300.),
                   1e-12);
  }

  /// A block of points thrown in one solid step across 8 cells into the
  /// finite-element zone (far beyond the ghost and padding layers of its
  /// rank's box on two ranks, so that only the receiving rank sees where it
  /// lands): the run must stop with a diagnostic at solid step 1, never
  /// drop the points silently.
  void
  lost_points(Checks &checks, MPI_Comm comm)
  {
    const double h  = 0.1;
    const auto   gp = box<dim>(Point<dim>(0, 0), Point<dim>(1.6, 0.8), h);
    BackgroundGrid<dim> grid(gp, comm);
    grid.create();
    Material                                 mat = unit_material();
    typename MaterialPoints<dim>::Parameters pp;
    pp.point_spacing   = h / 2;
    pp.layer_thickness = 0;
    pp.subcells        = 2;
    MaterialPoints<dim> points(pp, mat, grid);
    points.create_region(
      [](const Point<dim> &x) {
        return x[0] > 0.3 && x[0] < 0.5 && x[1] > 0.5 && x[1] < 0.7;
      },
      300.,
      MaterialPoints<dim>::solid);
    using P         = typename MaterialPoints<dim>::PropertyIndex;
    const double dt = 0.01; // below the stable limit 0.03 s
    for (auto &p : points.particle_handler())
      {
        p.get_properties()[P::velocity + 0] = 0.8 / dt;
        p.get_properties()[P::velocity + 1] = -0.35 / dt;
      }
    SolidMaterial sm(mat); // density 1, solidus 1e6
    sm.youngs_modulus = PiecewiseLinear(1.);
    typename SolidSubCycle<dim>::Parameters sp;
    sp.energy_file = "";
    sp.time_step   = dt;
    typename SolidFEM<dim>::Parameters fp;
    fp.enabled      = true;
    fp.lower_corner = Point<dim>(1.0, 0);
    fp.upper_corner = Point<dim>(1.6, 0.4);
    SolidSubCycle<dim>  solid(sp, fp, sm, grid, points);
    std::vector<double> T = grid.make_field(300.);
    solid.initialize(T, "");
    bool stopped = false;
    try
      {
        solid.advance(dt, T, false);
        solid.advance(2 * dt, T, true);
      }
    catch (const std::exception &e)
      {
        const std::string what = e.what();
        stopped = what.find("at solid step 1,") != std::string::npos;
        if (Utilities::MPI::this_mpi_process(comm) == 0)
          std::cerr << what << std::endl;
      }
    checks.in_range("points thrown into the FE zone: run stopped with a "
                    "diagnostic at solid step 1 (1 = yes)",
                    stopped,
                    1,
                    1);
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  run(SolidMaterial::VelocityTransfer::flip, "FLIP", checks, comm);
  run(SolidMaterial::VelocityTransfer::apic, "APIC", checks, comm);
  lost_points(checks, comm);
  return checks.exit_code();
}
