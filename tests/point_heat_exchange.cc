// Unit test of PointHeatExchange (heat between points and cells when the
// points change cells): a 2D strip of melt whose cells hold different
// temperatures across the melting range (latent heat in play) and whose
// points are then moved along x by a third of a cell, so that every cell
// exchanges points with its neighbour and the cells at the ends gain or
// lose metal.
//  - 'points' (the points carry the heat): the stored enthalpy of the grid
//    must not change (to round-off), and the exchange's own account
//    (moved_points) must hold that change;
//  - 'upwind': cells that gained metal take the mean temperature of their
//    points; the account holds the change of the stored enthalpy;
//  - a cell that was gas at the last alpha pass gives its new points no
//    stale temperature (stale_gas_cell below).

#include <femp/coupling/point_heat_exchange.h>

#include "test_tools.h"

using namespace femp_test;

void
run(const bool carried_by_points, Checks &checks, MPI_Comm comm)
{
  const int  dim = 2;
  const double h = 1. / 20;
  BackgroundGrid<dim> grid(box<dim>(Point<dim>(0, 0), Point<dim>(1, 2 * h), h),
                           comm);
  grid.create();
  Material mat           = unit_material();
  mat.solidus            = 1.4;
  mat.liquidus           = 1.6;
  mat.latent_heat_fusion = 0.5;
  Laser<dim>        laser(laser_off<dim>());
  auto              hp = heat_parameters<dim>(1., {});
  HeatTransfer<dim> heat(hp, mat, laser, grid);
  heat.initialize();

  MaterialPoints<dim>::Parameters pp;
  pp.point_spacing   = h / 2;
  pp.subcells        = 2;
  pp.layer_thickness = 0;
  MaterialPoints<dim> points(pp, mat, grid);
  points.create_region([](const Point<dim> &x) { return x[0] > 0.2 && x[0] < 0.8; },
                       2., MaterialPoints<dim>::fluid);
  heat.set_metal_fraction(points.metal_fraction());
  // Temperatures from 1 to 2 along x: solid, mushy and liquid cells.
  for (const auto idx : grid.owned_cells())
    heat.set_cell_temperature(idx, 1 + grid.cell_center(idx)[0]);
  heat.update_ghosts();
  points.cells_to_points(heat.temperature());

  PointHeatExchange<dim> exchange(points, heat, carried_by_points);
  const double           H0 = heat.stored_enthalpy();
  for (auto &particle : points.particle_handler())
    {
      Point<dim> x = particle.get_location();
      x[0] += h / 3;
      particle.set_location(x);
    }
  points.points_moved();
  exchange.points_changed_cells();
  const double dH = heat.stored_enthalpy() - H0;
  // Scale: the enthalpy of the metal, 0.6 x 2h x (c T + L) ~ 0.2.
  const double scale = std::abs(H0);
  const std::string mode = carried_by_points ? "points: " : "upwind: ";
  const double account_error = std::abs(exchange.moved_points_energy() - dH) / scale;
  checks.at_most(mode + "|moved_points account - change of stored enthalpy| / "
                        "enthalpy, next power of ten",
                 account_error > 0 ?
                   std::pow(10., std::ceil(std::log10(account_error))) : 0.,
                 1e-14);
  if (carried_by_points)
    {
      const double e = std::abs(dH) / scale;
      checks.at_most("points: |change of stored enthalpy| / enthalpy, next "
                     "power of ten",
                     e > 0 ? std::pow(10., std::ceil(std::log10(e))) : 0.,
                     1e-13);
    }
  else
    {
      // Cells that gained metal (the right end, x in [0.8, 0.85]) hold
      // the mean temperature of their points, all from the cell at
      // centre 0.775: 1.775.
      double T_new = 0;
      for (const auto idx : grid.owned_cells())
        {
          const double xc = grid.cell_center(idx)[0];
          if (xc > 0.8 && xc < 0.85)
            T_new = std::max(T_new, heat.temperature()[idx]);
        }
      T_new = Utilities::MPI::max(T_new, comm);
      checks.in_range("upwind: temperature of a cell that gained metal",
                      std::round(T_new * 1e6) / 1e6, 1.775 - 1e-6, 1.775 + 1e-6);
      checks.print("upwind: change of stored enthalpy / enthalpy",
                   std::round(dH / scale * 1e4) / 1e4, 3);
    }
}

// Points that enter a cell which was gas at the last alpha pass (as the
// solid moves its points, with no alpha pass after it): that cell's
// temperature is stale (here set to 9), and cells_to_points() with the
// heat equation's metal fraction must leave those points at their own
// temperature (1.775, from the cell they came from); the next alpha pass
// then gives the cell their enthalpy. Without the metal fraction they
// would take the stale 9 (printed as the contrast).
void
stale_gas_cell(Checks &checks, MPI_Comm comm)
{
  const int  dim = 2;
  const double h = 1. / 20;
  BackgroundGrid<dim> grid(box<dim>(Point<dim>(0, 0), Point<dim>(1, 2 * h), h),
                           comm);
  grid.create();
  Material mat = unit_material();
  mat.solidus  = 1.4;
  mat.liquidus = 1.6;
  Laser<dim>        laser(laser_off<dim>());
  HeatTransfer<dim> heat(heat_parameters<dim>(1., {}), mat, laser, grid);
  heat.initialize();
  MaterialPoints<dim>::Parameters pp;
  pp.point_spacing   = h / 2;
  pp.subcells        = 2;
  pp.layer_thickness = 0;
  for (const bool with_metal : {true, false})
    {
      MaterialPoints<dim> points(pp, mat, grid);
      points.create_region(
        [](const Point<dim> &x) { return x[0] > 0.2 && x[0] < 0.8; }, 2.,
        MaterialPoints<dim>::solid);
      heat.set_metal_fraction(points.metal_fraction());
      for (const auto idx : grid.owned_cells())
        heat.set_cell_temperature(idx, 1 + grid.cell_center(idx)[0]);
      heat.update_ghosts();
      points.cells_to_points(heat.temperature());
      // Move the points by a third of a cell: the cells at x in [0.8,
      // 0.85] gain the points of the cell at 0.775; give them a stale
      // temperature.
      for (auto &particle : points.particle_handler())
        {
          Point<dim> x = particle.get_location();
          x[0] += h / 3;
          particle.set_location(x);
        }
      points.points_moved();
      for (const auto idx : grid.owned_cells())
        {
          const double xc = grid.cell_center(idx)[0];
          if (xc > 0.8 && xc < 0.85)
            heat.set_cell_temperature(idx, 9.);
        }
      heat.update_ghosts();
      points.cells_to_points(heat.temperature(),
                             with_metal ? &heat.metal_fraction() : nullptr);
      double T_max = 0;
      for (const auto &particle : points.particle_handler())
        T_max = std::max(T_max, particle.get_properties()[MaterialPoints<dim>::PropertyIndex::temperature]);
      T_max = Utilities::MPI::max(T_max, comm);
      if (with_metal)
        checks.in_range("stale gas cell: hottest point after cells_to_points "
                        "with the metal fraction",
                        std::round(T_max * 1e6) / 1e6, 1.775 - 1e-6,
                        1.775 + 1e-6);
      else
        checks.print("stale gas cell: hottest point after cells_to_points "
                     "without it (the stale value)",
                     T_max);
    }
}

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  run(true, checks, comm);
  run(false, checks, comm);
  stale_gas_cell(checks, comm);
  return checks.exit_code();
}
