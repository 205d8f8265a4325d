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
//    stale temperature (stale_gas_cell below);
//  - the points of fixed cells (the FE zone) get the temperatures and
//    peaks passed to their cells when flushed (fixed_cells below);
//  - bunched points (bunched_points below): a cell over-full with points
//    passes its excess volume to the half-full cells of the top row, the
//    top row is heated (as the laser heats the surface), the points take
//    the cells' temperatures and move again: with 'Metal of melt cells =
//    points' the stored enthalpy must stay what the heating made it (to
//    round-off); with 'alpha' the heat given to the excess volume of the
//    top row is lost (printed, and it must be large enough that the check
//    above could fail).

#include <femp/coupling/point_heat_exchange.h>

#include "test_tools.h"

using namespace femp_test;

constexpr int dim = 2;

// The strip of all three tests: 1 x 2h with h = 1/20, a unit material
// melting over [1.4, 1.6], points at h/2 with 2 x 2 sub-cells.
struct Strip
{
  const double                    h = 1. / 20;
  BackgroundGrid<dim>             grid;
  Material                        mat = unit_material();
  MaterialPoints<dim>::Parameters pp;

  explicit Strip(MPI_Comm comm)
      : grid(box<dim>(Point<dim>(0, 0), Point<dim>(1, 2 * h), h), comm)
  {
    grid.create();
    mat.solidus        = 1.4;
    mat.liquidus       = 1.6;
    pp.point_spacing   = h / 2;
    pp.subcells        = 2;
    pp.layer_thickness = 0;
  }
};

// Moves every point by dx along x and tells the points that they moved.
void
shift_points(MaterialPoints<dim> &points, const double dx)
{
  for (auto &particle : points.particle_handler())
    {
      Point<dim> x = particle.get_location();
      x[0] += dx;
      particle.set_location(x);
    }
  points.points_moved();
}

void
run(const bool carried_by_points, Checks &checks, MPI_Comm comm)
{
  Strip        strip(comm);
  const double h         = strip.h;
  auto        &grid      = strip.grid;
  auto        &mat       = strip.mat;
  mat.latent_heat_fusion = 0.5;
  Laser<dim>        laser(laser_off<dim>());
  auto              hp = heat_parameters<dim>(1., {});
  HeatTransfer<dim> heat(hp, mat, laser, grid);
  heat.initialize();

  MaterialPoints<dim> points(strip.pp, mat, grid);
  points.create_region(
    [](const Point<dim> &x) { return x[0] > 0.2 && x[0] < 0.8; },
    2.,
    MaterialPoints<dim>::fluid);
  heat.set_metal_fraction(points.metal_fraction());
  // Temperatures from 1 to 2 along x: solid, mushy and liquid cells.
  for (const auto idx : grid.owned_cells())
    heat.set_cell_temperature(idx, 1 + grid.cell_center(idx)[0]);
  heat.update_ghosts();
  points.cells_to_points(heat.temperature());

  PointHeatExchange<dim> exchange(points, heat, grid, carried_by_points);
  const double           H0 = heat.stored_enthalpy();
  shift_points(points, h / 3);
  exchange.points_changed_cells();
  const double dH = heat.stored_enthalpy() - H0;
  // Scale: the enthalpy of the metal, 0.6 x 2h x (c T + L) ~ 0.2.
  const double      scale = std::abs(H0);
  const std::string mode  = carried_by_points ? "points: " : "upwind: ";
  const double      account_error =
    std::abs(exchange.moved_points_energy() - dH) / scale;
  checks.at_most(mode + "|moved_points account - change of stored enthalpy| / "
                        "enthalpy, next power of ten",
                 account_error > 0 ?
                   std::pow(10., std::ceil(std::log10(account_error))) :
                   0.,
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
                      std::round(T_new * 1e6) / 1e6,
                      1.775 - 1e-6,
                      1.775 + 1e-6);
      checks.print("upwind: change of stored enthalpy / enthalpy",
                   std::round(dH / scale * 1e4) / 1e4,
                   3);
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
  Strip             strip(comm);
  const double      h    = strip.h;
  const auto       &grid = strip.grid;
  const auto       &mat  = strip.mat;
  const auto       &pp   = strip.pp;
  Laser<dim>        laser(laser_off<dim>());
  HeatTransfer<dim> heat(heat_parameters<dim>(1., {}), mat, laser, grid);
  heat.initialize();
  for (const bool with_metal : {true, false})
    {
      MaterialPoints<dim> points(pp, mat, grid);
      points.create_region(
        [](const Point<dim> &x) { return x[0] > 0.2 && x[0] < 0.8; },
        2.,
        MaterialPoints<dim>::solid);
      heat.set_metal_fraction(points.metal_fraction());
      for (const auto idx : grid.owned_cells())
        heat.set_cell_temperature(idx, 1 + grid.cell_center(idx)[0]);
      heat.update_ghosts();
      points.cells_to_points(heat.temperature());
      // Move the points by a third of a cell: the cells at x in [0.8,
      // 0.85] gain the points of the cell at 0.775; give them a stale
      // temperature.
      shift_points(points, h / 3);
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
        T_max = std::max(
          T_max,
          particle
            .get_properties()[MaterialPoints<dim>::PropertyIndex::temperature]);
      T_max = Utilities::MPI::max(T_max, comm);
      if (with_metal)
        checks.in_range("stale gas cell: hottest point after cells_to_points "
                        "with the metal fraction",
                        std::round(T_max * 1e6) / 1e6,
                        1.775 - 1e-6,
                        1.775 + 1e-6);
      else
        checks.print("stale gas cell: hottest point after cells_to_points "
                     "without it (the stale value)",
                     T_max);
    }
}

// Fixed cells (the FE zone): cells_to_points() only records their
// temperature and peak, flush_point_temperatures() writes them. Two equal
// sets of points, one with the left half of the strip fixed, take the
// same sequence of cell temperatures (a hot one, then cooler ones, and one
// fixed cell above the solidus, written at once); after the flush every
// point's temperature, peak and state must equal the unfixed set's, and so
// must the volume means over the points after the cells' temperatures
// changed without a push. Without the flush the fixed points would hold
// their first temperature (printed as the contrast).
void
fixed_cells(Checks &checks, MPI_Comm comm)
{
  Strip       strip(comm);
  const auto &grid = strip.grid;
  const auto &mat  = strip.mat;
  const auto &pp   = strip.pp;
  auto        make = [&]() {
    auto p = std::make_unique<MaterialPoints<dim>>(pp, mat, grid);
    p->create_region(
      [](const Point<dim> &x) { return x[0] > 0.2 && x[0] < 0.8; },
      1.,
      MaterialPoints<dim>::solid);
    return p;
  };
  auto                      eager = make(), lazy = make();
  std::vector<std::uint8_t> fixed(grid.n_local(), 0);
  for (const auto idx : grid.owned_cells())
    fixed[idx] = grid.cell_center(idx)[0] < 0.5;
  lazy->set_fixed_cells(fixed);
  (void) lazy->metal_fraction();
  // Cell temperatures: a + b x; the cell at x = 0.475 (fixed) goes above
  // the solidus at the third push.
  auto field = [&](const double a, const double b, const bool hot_cell) {
    std::vector<double> T(grid.n_local(), 0.);
    for (const auto idx : grid.owned_cells())
      {
        const double x = grid.cell_center(idx)[0];
        T[idx]         = a + b * x;
        if (hot_cell && std::abs(x - 0.475) < 0.01)
          T[idx] = 1.5;
      }
    grid.update_ghosts(T);
    return T;
  };
  const std::vector<std::vector<double>> pushes = {field(1.3, 0.1, false),
                                                   field(1.1, 0.2, false),
                                                   field(1.0, 0.1, true),
                                                   field(0.9, 0.1, false)};
  using P                 = MaterialPoints<dim>::PropertyIndex;
  auto largest_difference = [&](const unsigned int property) {
    double d = 0;
    AssertDimension(eager->occupied_cells().size(),
                    lazy->occupied_cells().size());
    for (std::size_t c = 0; c < eager->occupied_cells().size(); ++c)
      {
        const auto a = eager->cell_point_properties(c);
        const auto b = lazy->cell_point_properties(c);
        AssertDimension(a.size(), b.size());
        for (std::size_t k = 0; k < a.size(); ++k)
          d = std::max(d, std::abs(a[k][property] - b[k][property]));
      }
    return Utilities::MPI::max(d, comm);
  };
  for (const auto &T : pushes)
    {
      eager->cells_to_points(T);
      lazy->cells_to_points(T);
    }
  checks.print("fixed cells: largest temperature difference before the flush "
               "(the contrast)",
               std::round(largest_difference(P::temperature) * 1e6) / 1e6);
  lazy->flush_point_temperatures();
  checks.at_most("fixed cells: largest temperature difference after the flush",
                 largest_difference(P::temperature),
                 0.);
  checks.at_most("fixed cells: largest peak temperature difference",
                 largest_difference(P::peak_temperature),
                 0.);
  checks.at_most("fixed cells: largest state difference",
                 largest_difference(P::state),
                 0.);
  // Pushed again, then the cells' temperatures change without a push: the
  // volume means over the points (the cells with points at another
  // temperature) must be the same.
  eager->cells_to_points(pushes[1]);
  lazy->cells_to_points(pushes[1]);
  const auto e  = [](const double T) { return 2 * T; };
  const auto me = eager->volume_mean_over_points(pushes[0], e);
  const auto ml = lazy->volume_mean_over_points(pushes[0], e);
  double     d  = me.size() == ml.size() ? 0. : 1.;
  for (std::size_t i = 0; i < std::min(me.size(), ml.size()); ++i)
    d = std::max({d,
                  std::abs(me[i].second - ml[i].second),
                  me[i].first == ml[i].first ? 0. : 1.});
  checks.at_most("fixed cells: largest difference of the volume means",
                 Utilities::MPI::max(d, comm),
                 0.);
  checks.print("fixed cells: cells with a volume mean (all ranks)",
               Utilities::MPI::sum(me.size(), comm));
}

// Stored enthalpy after a heating of the top row and a move of all points,
// relative to that after the heating (see the header): the strip's lower
// row full of melt, its top row half full; the points of one full cell are
// first moved into its right neighbour, which holds twice its volume.
double
bunched_points(const bool metal_from_points, MPI_Comm comm)
{
  Strip        strip(comm);
  const double h         = strip.h;
  auto        &grid      = strip.grid;
  auto        &mat       = strip.mat;
  mat.latent_heat_fusion = 0.5;
  Laser<dim>        laser(laser_off<dim>());
  HeatTransfer<dim> heat(heat_parameters<dim>(1., {}), mat, laser, grid);
  heat.initialize();
  MaterialPoints<dim> points(strip.pp, mat, grid);
  points.create_region(
    [h](const Point<dim> &x) {
      return x[0] > 0.2 && x[0] < 0.8 && x[1] < 1.5 * h;
    },
    2.,
    MaterialPoints<dim>::fluid);
  heat.set_metal_fraction(points.metal_fraction());
  for (const auto idx : grid.owned_cells())
    heat.set_cell_temperature(idx, 1 + grid.cell_center(idx)[0]);
  heat.update_ghosts();
  points.cells_to_points(heat.temperature());
  PointHeatExchange<dim> exchange(points, heat, grid, true, metal_from_points);
  // The lower cell at x in [0.5, 0.55) gives its points to its right
  // neighbour.
  for (auto &particle : points.particle_handler())
    {
      Point<dim> x = particle.get_location();
      if (x[0] > 0.5 && x[0] < 0.55 && x[1] < h)
        x[0] += h;
      particle.set_location(x);
    }
  points.points_moved();
  exchange.points_changed_cells();
  // The heating of the top row (0.4 in T, across the melting range).
  for (const auto idx : grid.owned_cells())
    if (grid.cell_center(idx)[1] > h && heat.metal_fraction()[idx] > 0)
      heat.set_cell_temperature(idx, heat.temperature()[idx] + 0.4);
  heat.update_ghosts();
  const double H1 = heat.stored_enthalpy();
  points.cells_to_points(heat.temperature(), &heat.metal_fraction());
  shift_points(points, h / 3);
  exchange.points_changed_cells();
  return (heat.stored_enthalpy() - H1) / std::abs(H1);
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
  fixed_cells(checks, comm);
  {
    const double e = std::abs(bunched_points(true, comm));
    checks.at_most("bunched points, metal of melt cells = points: |change of "
                   "stored enthalpy| / enthalpy, next power of ten",
                   e > 0 ? std::pow(10., std::ceil(std::log10(e))) : 0.,
                   1e-13);
    // The contrast: large enough that the check above could fail.
    const double a = bunched_points(false, comm);
    checks.print("bunched points, metal of melt cells = alpha: change of "
                 "stored enthalpy / enthalpy",
                 std::round(a * 1e4) / 1e4);
    checks.in_range("bunched points, metal of melt cells = alpha: |change| "
                    "/ enthalpy",
                    std::round(std::abs(a) * 1e4) / 1e4,
                    1e-3,
                    1.);
  }
  return checks.exit_code();
}
