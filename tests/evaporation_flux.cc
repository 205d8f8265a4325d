// Evaporative heat loss at a prescribed surface temperature against its
// closed form (Hertz-Knudsen flux of the saturated vapour, the pressure from
// Clausius-Clapeyron):
//   p_sat(T) = p0 exp[L_v M (T - T_v)/(R T T_v)],
//   q_evap(T) = zeta_q L_v p_sat(T) sqrt(M / (2 pi R T))      (W/m^2),
// the loss of eq. (1) (the recoil pressure zeta_p p_sat(T) of the same
// exponential is checked in tests/recoil_pressure.cc). A block of 316L-like
// metal with a flat top through cell faces, uniform T at 3090, 4000 and
// 5000 K, evaporation the only loss, laser off: the energy lost in one very
// short step (1e-12 s, the surface cools by < 0.1 K) divided by the top
// area and the step must be q_evap(T) within 1e-3 (the density weighting of
// the surface term with the gas's heat capacity shifts it by 2e-4). Also
// printed: the temperature at which q_evap equals the peak absorbed flux
// 2 eta P/(pi r_b^2) of prm/melt_track_3d.prm (evaporation-limited surface
// temperature, doc/absorption.md).
#include "test_tools.h"

using namespace femp_test;

namespace
{
  constexpr int dim = 3;
  const double  R   = 8.314462618;

  double
  q_closed(const HeatTransfer<dim>::Parameters &p,
           const Material                      &m,
           const double                         T)
  {
    const double M = m.molar_mass, Lv = m.latent_heat_evaporation;
    const double p_sat =
      m.ambient_pressure * std::exp(Lv * M * (T - m.evaporation_temperature) /
                                    (R * T * m.evaporation_temperature));
    return p.evaporation_coefficient * Lv * p_sat *
           std::sqrt(M / (2 * M_PI * R * T));
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);

  const double h = 8e-6, L = 80e-6, z_top = 32e-6;
  const auto   gp = box<dim>(Point<dim>(0, 0, 0), Point<dim>(L, L, 64e-6), h);
  BackgroundGrid<dim> grid(gp, comm);
  grid.create();
  const Material      mat; // 316L-like defaults, molten above 1730 K
  Laser<dim>          laser(laser_off<dim>());
  std::vector<double> alpha = grid.make_field(0.);
  for (std::size_t i = 0; i < alpha.size(); ++i)
    alpha[i] = grid.cell_center(i)[dim - 1] < z_top ? 1. : 0.;

  for (const double T0 : {3090., 4000., 5000.})
    {
      auto p                    = heat_parameters<dim>(T0, {});
      p.evaporation_coefficient = 0.82;
      HeatTransfer<dim> heat(p, mat, laser, grid);
      heat.initialize();
      heat.set_metal_fraction(alpha);
      const double dt = 1e-12;
      heat.advance(dt, 0.);
      const double      q   = heat.energy_budget().evaporation / (L * L * dt);
      const double      ref = q_closed(p, mat, T0);
      const std::string at  = "T = " + std::to_string(int(T0)) + " K: ";
      checks.print(at + "q_evap closed form, W/m^2", ref);
      checks.at_most(at + "|q_evap / closed form - 1|",
                     std::abs(q / ref - 1),
                     1e-3);
    }

  // Evaporation-limited surface temperature of the 3D track's beam axis.
  const auto   p      = HeatTransfer<dim>::Parameters();
  const double q_peak = 2 * 0.35 * 200 / (M_PI * 20e-6 * 20e-6);
  double       lo = 3000, hi = 8000;
  for (int i = 0; i < 60; ++i)
    {
      const double m                           = 0.5 * (lo + hi);
      (q_closed(p, mat, m) < q_peak ? lo : hi) = m;
    }
  checks.print("peak absorbed flux of prm/melt_track_3d.prm, W/m^2", q_peak);
  checks.print("T with q_evap(T) = that flux, K", 0.5 * (lo + hi));
  checks.print("q_evap(T_v) / that flux",
               q_closed(p, mat, mat.evaporation_temperature) / q_peak);
  return checks.exit_code();
}
