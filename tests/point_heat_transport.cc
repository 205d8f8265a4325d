// Verification of heat carried by the material points (Heat transfer/
// Advection by melt flow = points, doc/equations.md): a temperature pulse
// on a strip of metal whose points all move at u = 1 along x, with
// diffusivity 0.01 (Peclet u L / kappa = 100). The heat equation does the
// conduction only; after each step the points take their cell's
// temperature, move, and each cell takes the mean enthalpy of the points
// now in it (MaterialPoints::volume_mean_over_points, HeatTransfer::
// take_point_enthalpy), as FempProblem does after the flow sub-steps.
// The metal fills [0, 2] of a box [0, 2.5] at the start and ends in
// [0.48, 2.48]: no point leaves the box, cells at the left end empty and
// cells at the right end fill (cells that gain metal take their points'
// enthalpy).
// Exact on the infinite line for a pulse on [a, b]:
//   T = 1 + 0.5 [erf((x - a - u t)/(2 sqrt(kappa t)))
//              - erf((x - b - u t)/(2 sqrt(kappa t)))],
// here from t0 = 0.02 (smooth start) to t = 0.5, far from the ends. The
// transport is first order (a cell mixes with its upwind neighbour each
// time a column of points crosses, a numerical diffusion of about u h / 4):
// the observed order must be about 1, and the error at the finest grid is
// gated. A second run with a melting range and latent heat inside the pulse
// (mushy cells mixed by enthalpy, not by temperature) checks that the
// stored enthalpy is conserved to round-off; a mean of temperatures there
// would create or destroy latent heat.

#include <femp/grid/material_points.h>
#include <femp/heat/heat_transfer.h>

#include "test_tools.h"

using namespace femp_test;

const double kappa = 0.01, u = 1., a = 0.5, b = 1., t0 = 0.02;

double
exact(const double x, const double t)
{
  const double s = 2 * std::sqrt(kappa * t);
  return 1 +
         0.5 * (std::erf((x - a - u * t) / s) - std::erf((x - b - u * t) / s));
}

struct Result
{
  double error;          // max |T - exact| at the end
  double enthalpy_error; // |H_end - H_start| / (pulse enthalpy)
};

Result
run(const double h, const bool latent, MPI_Comm comm)
{
  const int  dim = 2;
  const auto gp  = box<dim>(Point<dim>(0, 0), Point<dim>(2.5, 2 * h), h);
  BackgroundGrid<dim> grid(gp, comm);
  grid.create();
  Material mat     = unit_material();
  mat.conductivity = PiecewiseLinear(kappa);
  // The moving metal is melt, as in a scene: its points are (or have been)
  // above the solidus, so alpha is the points' volume (doc/equations.md,
  // "Background grid and material points"); sub-cell occupancy would read half
  // a cell when round-off puts two points of a row into one sub-cell.
  mat.solidus            = latent ? 1.4 : 0.5;
  mat.liquidus           = latent ? 1.6 : 0.6;
  mat.latent_heat_fusion = latent ? 0.5 : 0.;
  Laser<dim>        laser(laser_off<dim>());
  auto              p = heat_parameters<dim>(1., {});
  HeatTransfer<dim> heat(p, mat, laser, grid);
  heat.initialize();

  MaterialPoints<dim>::Parameters pp;
  pp.point_spacing   = h / 2;
  pp.subcells        = 2;
  pp.layer_thickness = 0;
  MaterialPoints<dim> points(pp, mat, grid);
  // Created at T = 2 (melted once: peak temperature above the solidus),
  // then given the cell temperatures below.
  points.create_region([](const Point<dim> &x) { return x[0] < 2; },
                       2.,
                       MaterialPoints<dim>::fluid);
  heat.set_metal_fraction(points.metal_fraction());
  const auto &T = heat.temperature();
  for (const auto idx : grid.owned_cells())
    heat.set_cell_temperature(idx, exact(grid.cell_center(idx)[0], t0));
  heat.update_ghosts();
  const double H0 = heat.stored_enthalpy();

  const double t_end = 0.5;
  const double dt0   = 0.5 * heat.stable_time_step();
  // An odd number of steps: u dt is then never an odd multiple of a
  // quarter cell, so the point columns (a quarter cell off the faces at
  // the start) never sit exactly on a cell face, where round-off could put
  // a whole column into either cell.
  const unsigned int n  = 2 * unsigned(std::ceil((t_end - t0) / dt0 / 2)) + 1;
  const double       dt = (t_end - t0) / n;
  double             t  = t0;
  for (unsigned int i = 0; i < n; ++i, t += dt)
    {
      heat.advance(dt, t);
      points.cells_to_points(T);
      for (auto &particle : points.particle_handler())
        {
          Point<dim> x = particle.get_location();
          x[0] += u * dt;
          particle.set_location(x);
        }
      points.points_moved();
      const auto mean =
        points.volume_mean_over_points(T, [&heat](const double Tc) {
          return heat.specific_enthalpy(Tc);
        });
      heat.set_metal_fraction(points.metal_fraction());
      heat.take_point_enthalpy(mean);
    }

  double err = 0;
  for (const auto idx : grid.owned_cells())
    if (grid.cell_center(idx)[0] > 0.5 && grid.cell_center(idx)[0] < 2)
      err = std::max(err,
                     std::abs(T[idx] - exact(grid.cell_center(idx)[0], t_end)));
  // (Round-off over ~1500 steps: tolerance 1e-9 of the pulse enthalpy.)
  // Enthalpy of the pulse above T = 1: its width times the height 1
  // (sensible part, rho c = 1) plus the latent heat, per unit depth.
  const double H_pulse = (b - a) * 2 * h * (1 + mat.latent_heat_fusion);
  return {Utilities::MPI::max(err, comm),
          std::abs(heat.stored_enthalpy() - H0) / H_pulse};
}

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  const auto                       r1 = run(1. / 50, false, comm);
  const auto                       r2 = run(1. / 100, false, comm);
  const auto                       r3 = run(1. / 200, false, comm);
  auto round2 = [](const double x) { return std::round(x * 1000) / 1000; };
  checks.print("max error h=1/50", round2(r1.error), 3);
  checks.print("max error h=1/100", round2(r2.error), 3);
  checks.print("max error h=1/200", round2(r3.error), 3);
  checks.in_range("observed order (1/100 -> 1/200)",
                  std::round(std::log2(r2.error / r3.error) * 10) / 10,
                  0.8,
                  1.3);
  // (The grid upwind scheme gives 0.024 at h = 1/200: tests/convection_upwind.)
  checks.at_most("max error h=1/200", round2(r3.error), 0.02);
  const double e_max =
    std::max({r1.enthalpy_error, r2.enthalpy_error, r3.enthalpy_error});
  checks.at_most(
    "enthalpy change / pulse enthalpy, no latent heat, next power of ten",
    e_max > 0 ? std::pow(10., std::ceil(std::log10(e_max))) : 0.,
    1e-9);
  const auto rl = run(1. / 100, true, comm);
  checks.at_most("enthalpy change / pulse enthalpy, melting range in the "
                 "pulse, next power of ten",
                 rl.enthalpy_error > 0 ?
                   std::pow(10., std::ceil(std::log10(rl.enthalpy_error))) :
                   0.,
                 1e-9);
  return checks.exit_code();
}
