// Recession of a melt surface by evaporation ('Heat transfer/Remove
// evaporated mass', doc/equations.md): a flat layer of melt (316L-like, 2D,
// 4 um cells, points 2 um apart, the top at 30 um, half way through a cell)
// held at T0 = 3500 and 4000 K, above the boiling point T_v = 3090 K,
// evaporation the only loss, laser off. The specific heat is raised to
// 1e9 J/(kg K) so that the evaporation does not cool the melt (the
// temperature falls by < 0.01 K over the run; the mass flux then stays
// m_dot(T0)); the other constants are the material's. Each step as in a
// run: the temperature step, the cell temperatures to the points, the
// evaporated mass taken from the points (PointHeatExchange::
// remove_evaporated_mass()), alpha renewed (follow_points()): the mass
// evaporated from the cells that straddle the surface leaves the outermost
// metal, so the surface stays sharp. Closed form (Hertz-Knudsen flux of the
// saturated vapour, the pressure from Clausius-Clapeyron):
//   m_dot(T) = zeta_q p0 exp[L_v M (T - T_v)/(R T T_v)] sqrt(M/(2 pi R T)),
// the mass lost over the width L in the time t is m_dot L t, the surface
// recedes by m_dot t / rho_m (the metal volume sum alpha h^2 over L).
// Checked:
//  - the evaporated mass the heat books (its evaporation loss over L_v)
//    against m_dot L t: within 1e-4 (the temperature drift and the gas's
//    heat capacity in the surface weight, a few 1e-5);
//  - the mass taken from the points against m_dot L t: exact but for the
//    rest of each deleted point (less than 1 % of a lattice point's mass
//    rho_m s^2 by the deletion rule): the tolerance is that bound, 0.01
//    rho_m s^2 per deleted point, relative to m_dot L t (the error printed
//    is rounded up to the next power of ten);
//  - the recession of the metal volume against m_dot t / rho_m, the same
//    bound over rho_m L;
//  - the energy balance of the run: stored enthalpy change + evaporation
//    loss + the heat carried away by the removed metal (booked per removed
//    piece, m [e(T) - e(T_ref) - (rho_g c_g/rho_m)(T - T_ref)]) = 0 within
//    1e-8 of the energy that left (loss + carried; with the raised heat
//    capacity the carried heat is 5e5 times the loss): the booked heat
//    against the change of the stored enthalpy that the new alpha gives,
//    up to the heat step's local Newton iteration (stops at 1e-12 of a
//    cell's enthalpy) and round-off over 600 steps;
//  - with 'Remove evaporated mass = false' no mass leaves.
// The same on 1 and 2 ranks (per-cell removal; sums differ by round-off).
#include <femp/coupling/point_heat_exchange.h>
#include <femp/grid/material_points.h>
#include <femp/heat/heat_transfer.h>

#include "test_tools.h"

using namespace femp_test;

namespace
{
  constexpr int dim = 2;
  const double  R   = 8.314462618;

  double
  m_dot_closed(const double zeta, const Material &m, const double T)
  {
    const double M = m.molar_mass, Lv = m.latent_heat_evaporation;
    const double p_sat =
      m.ambient_pressure * std::exp(Lv * M * (T - m.evaporation_temperature) /
                                    (R * T * m.evaporation_temperature));
    return zeta * p_sat * std::sqrt(M / (2 * M_PI * R * T));
  }

  struct Result
  {
    double evaporated = 0; // heat's evaporation loss / L_v, kg/m
    double removed    = 0; // point mass lost, kg/m
    double receded    = 0; // metal volume lost / L, m
    double balance    = 0; // |dH + loss + carried| / (loss + carried)
    double T_drift    = 0; // largest |T - T0| of metal cells, K
    double deleted    = 0; // points deleted
    double time       = 0; // s
  };

  double
  point_mass(const MaterialPoints<dim> &points, MPI_Comm comm)
  {
    using P    = MaterialPoints<dim>::PropertyIndex;
    double sum = 0;
    for (std::size_t c = 0; c < points.occupied_cells().size(); ++c)
      for (const double *p : points.cell_point_properties(c))
        sum += p[P::mass];
    return Utilities::MPI::sum(sum, comm);
  }

  double
  metal_volume(const BackgroundGrid<dim> &grid,
               const std::vector<double> &alpha,
               MPI_Comm                   comm)
  {
    double v = 0;
    for (const auto idx : grid.owned_cells())
      v += alpha[idx];
    return Utilities::MPI::sum(v, comm) * grid.h() * grid.h();
  }

  Result
  run(const double T0,
      const bool   remove,
      const double L,
      const double h,
      const double t_end,
      MPI_Comm     comm)
  {
    const auto gp = box<dim>(Point<dim>(0, 0), Point<dim>(L, 64e-6), h);
    BackgroundGrid<dim> grid(gp, comm);
    grid.create();
    Material mat;
    mat.specific_heat = PiecewiseLinear(1e9);
    Laser<dim> laser(laser_off<dim>());
    auto       p              = heat_parameters<dim>(T0, {});
    p.evaporation_coefficient = 0.82;
    p.remove_evaporated_mass  = remove;
    p.reference_temperature   = 300; // (the ambient: evaporation cools)
    HeatTransfer<dim> heat(p, mat, laser, grid);
    heat.initialize();

    MaterialPoints<dim>::Parameters pp;
    pp.point_spacing   = h / 2;
    pp.subcells        = 2;
    pp.layer_thickness = 0;
    MaterialPoints<dim> points(pp, mat, grid);
    points.create_region([](const Point<dim> &x) { return x[1] < 30e-6; },
                         T0,
                         MaterialPoints<dim>::fluid);
    PointHeatExchange<dim> exchange(points, heat, grid, true);
    exchange.start({}, p);

    const double H0 = heat.stored_enthalpy();
    const double M0 = point_mass(points, comm);
    const double V0 = metal_volume(grid, heat.metal_fraction(), comm);
    const double n0 = points.n_global_points();
    const double dt = 1e-7;
    const auto   n  = static_cast<unsigned int>(std::round(t_end / dt));
    for (unsigned int i = 0; i < n; ++i)
      {
        heat.advance(dt, i * dt);
        points.cells_to_points(heat.temperature(), &heat.metal_fraction());
        exchange.remove_evaporated_mass();
        exchange.follow_points();
      }
    Result r;
    r.time            = n * dt;
    const double loss = heat.energy_budget().evaporation;
    r.evaporated      = loss / mat.latent_heat_evaporation;
    r.removed         = M0 - point_mass(points, comm);
    r.receded = (V0 - metal_volume(grid, heat.metal_fraction(), comm)) / L;
    const double carried = exchange.evaporated_mass_account().enthalpy;
    r.balance =
      std::abs(heat.stored_enthalpy() - H0 + loss + carried) / (loss + carried);
    double drift = 0;
    for (const auto idx : grid.owned_cells())
      if (heat.metal_fraction()[idx] > 0)
        drift = std::max(drift, std::abs(heat.temperature()[idx] - T0));
    r.T_drift = Utilities::MPI::max(drift, comm);
    r.deleted = n0 - points.n_global_points();
    return r;
  }

  // The next power of ten above x (0 stays 0): a printout that does not
  // move with round-off.
  double
  decade(const double x)
  {
    return x > 0 ? std::pow(10., std::ceil(std::log10(x))) : 0.;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);

  const double   L = 40e-6, h = 4e-6, t_end = 6e-5;
  const Material mat;
  const double   m_point = mat.density * (h / 2) * (h / 2);
  for (const double T0 : {3500., 4000.})
    {
      const Result      r   = run(T0, true, L, h, t_end, comm);
      const double      m   = m_dot_closed(0.82, mat, T0);
      const double      ref = m * L * r.time;
      const std::string at  = "T = " + std::to_string(int(T0)) + " K: ";
      checks.print(at + "m_dot closed form, kg/(m^2 s)", m);
      checks.print(at + "recession m_dot t / rho_m closed form, um",
                   m * r.time / mat.density * 1e6);
      checks.print(at + "recession of the metal volume, um",
                   std::round(r.receded * 1e7) / 10,
                   3);
      checks.at_most(at + "|evaporated (loss / L_v) / (m_dot L t) - 1|",
                     decade(std::abs(r.evaporated / ref - 1)),
                     1e-4);
      const double bound = 0.01 * m_point * r.deleted / ref;
      checks.print(at + "points deleted", r.deleted);
      checks.at_most(at + "|removed / (m_dot L t) - 1| <= 0.01 rho_m s^2 "
                          "deleted / (m_dot L t)",
                     std::abs(r.removed / ref - 1) <= bound + 1e-12 ? 0. : 1.,
                     0.);
      checks.at_most(at + "|removed / (m_dot L t) - 1|, next power of ten",
                     decade(std::abs(r.removed / ref - 1)),
                     decade(bound));
      checks.at_most(at + "|recession / (m_dot t / rho_m) - 1|, next power "
                          "of ten",
                     decade(std::abs(r.receded * mat.density * L / ref - 1)),
                     decade(bound));
      checks.at_most(at + "|stored change + loss + carried| / (loss + "
                          "carried), next power of ten",
                     decade(r.balance),
                     1e-8);
      checks.at_most(at + "temperature drift, K", r.T_drift, 0.01);
    }
  const Result off = run(4000., false, L, h, 1e-5, comm);
  checks.print("Remove evaporated mass = false: evaporated mass > 0",
               off.evaporated > 0);
  checks.at_most("Remove evaporated mass = false: |mass lost| / evaporated",
                 std::abs(off.removed) / off.evaporated,
                 0.);
  return checks.exit_code();
}
