// The front-wall piston ('Heat transfer/Front wall piston', FrontWallPiston,
// doc/equations.md "Front wall piston"): the flux that reaches the melting
// front under a boiling surface through the sub-cell melt film. A 2D slab
// (default material, 8 um cells, 8 columns): a half-filled surface row
// (alpha = 1/2) at T_s = 3500 K, above the evaporation temperature, over a
// full row of solid at 1650 K (just below the solidus) and a substrate at
// 300 K; the laser (first-surface deposition, a beam 100 um in radius,
// so l = r_b/2 = 50 um) heats the surface, evaporation the only loss. One
// temperature step of 1 ns with the model and one without, from the same
// state. Closed form of the piston (Semak and Matsunawa, J. Phys. D 30
// (1997) 2541), computed here independently of the code: the melt made at
// the drilling speed v_d over the spot leaves through its rim at the
// Bernoulli speed u = sqrt(2 p_r/rho) of the recoil p_r = zeta_p p0
// exp[L_v M (T_s - T_v)/(R T_s T_v)], delta = v_d l/u; the film conducts
// k (T_s - T_l)/delta = rho H v_d to the melting front, H = c (T_l - T_0) +
// L_m; so v_d = sqrt(k (T_s - T_l) u/(l rho H)).
// Checked (tolerances set before the first run):
//  - with the model, the flux into each solid cell under the surface, the
//    grid's own conduction plus what the step moved there beyond the step
//    without the model, over rho H, is the closed-form drilling speed
//    within 1e-6 (the local enthalpy solve stops at 1e-12 of a cell's
//    enthalpy), where the absorbed flux exceeds the film's;
//    (absorbed flux at least the film's flux plus twice the evaporation at
//    T_s, so that the cap, absorbed minus evaporated, does not bind);
//  - with a weaker laser (absorbed flux between the grid's conduction and
//    the film's flux) and no evaporation, that flux is the absorbed flux
//    (the cap), within 1e-6;
//  - with the cell under the surface fully liquid (2000 K) and the solid
//    one cell further in, the same for the flux into that solid cell (the
//    grid's conduction out of the surface cell plus what was moved), 1e-6;
//  - with the laser off, nothing moves (the film never takes more than the
//    absorbed flux less the evaporation);
//  - energy: the stored enthalpy change plus the losses equals the laser's
//    energy within 1e-9 of it;
//  - without the model the same quantity is the grid's conduction only,
//    far from the closed form (the check above fails without it);
//  - with the recoil net of the ambient pressure (Melt flow/Recoil above
//    ambient, the flow's law p_r = max(0, zeta_p p_sat - p0)), the front
//    speed of the strong beam is the closed form with that p_r within
//    1e-6 (8 % slower than with zeta_p p_sat at 3500 K); at T_s = 3150 K,
//    where zeta_p p_sat < p0, no recoil expels the melt and the model
//    moves nothing, where with zeta_p p_sat it moves enthalpy into the
//    solid.
// The same on 1 and 2 ranks.
#include <femp/heat/heat_transfer.h>

#include "test_tools.h"

using namespace femp_test;

namespace
{
  constexpr int    dim = 2;
  constexpr double R   = 8.314462618;
  constexpr double h   = 8e-6;
  constexpr double Ts = 3500, Tj = 1650, T0 = 300;
  constexpr double zeta = 0.54;
  constexpr double rb   = 100e-6;
  constexpr double dt   = 1e-9;
  // The melt of the second case, between the surface and the front, K.
  constexpr double T_liquid = 2000;

  struct Step
  {
    std::vector<double> enthalpy_j; // rho e of the solid row, per column
    std::vector<double> q_abs;      // absorbed flux of the surface cell
    double              balance = 0;
    double              laser   = 0;
  };

  Step
  step(const bool   piston,
       const double power,
       const double zeta_q,
       MPI_Comm     comm,
       const bool   liquid_between = false,
       const double T_s            = Ts,
       const bool   above_ambient  = false)
  {
    const unsigned int nx = 8;
    const auto gp = box<dim>(Point<dim>(0, 0), Point<dim>(nx * h, 10 * h), h);
    BackgroundGrid<dim> grid(gp, comm);
    grid.create();
    Material                        mat;
    typename Laser<dim>::Parameters lp;
    lp.power       = power;
    lp.beam_radius = rb;
    lp.scan_speed  = 1.;
    lp.start_point = Point<dim>(0.5 * nx * h, 10 * h);
    lp.end_point   = Point<dim>(0.5 * nx * h + 1e-6, 10 * h);
    lp.start_time  = power > 0 ? 0. : 1e30;
    Laser<dim> laser(lp);
    auto       p              = heat_parameters<dim>(T0, {});
    p.evaporation_coefficient = zeta_q;
    p.front_wall_piston       = piston;
    HeatTransfer<dim> heat(p, mat, laser, grid);
    heat.initialize();
    heat.enable_front_wall_piston(RecoilLaw(mat, zeta, above_ambient));
    // Rows 0-5 full, row 6 half filled, gas above.
    auto alpha = grid.make_field(0.);
    for (std::size_t idx = 0; idx < alpha.size(); ++idx)
      if (grid.cell_status()[idx] != BackgroundGrid<dim>::outside)
        {
          const int j = grid.global_index(idx)[1];
          alpha[idx]  = j < 6 ? 1. : (j == 6 ? 0.5 : 0.);
        }
    heat.set_metal_fraction(alpha);
    for (const auto idx : grid.owned_cells())
      {
        const int    j = grid.global_index(idx)[1];
        const double Tc =
          liquid_between ?
            (j == 6 ? T_s : (j == 5 ? T_liquid : (j == 4 ? Tj : T0))) :
            (j == 6 ? T_s : (j == 5 ? Tj : T0));
        heat.set_cell_temperature(idx, Tc);
      }
    heat.update_ghosts();
    const double H0 = heat.stored_enthalpy();
    heat.advance(dt, 0.);
    Step s;
    s.enthalpy_j.assign(nx, 0.);
    s.q_abs.assign(nx, 0.);
    for (const auto idx : grid.owned_cells())
      {
        const auto ijk = grid.global_index(idx);
        if (ijk[1] == (liquid_between ? 4 : 5))
          s.enthalpy_j[ijk[0]] =
            mat.density * heat.specific_enthalpy(heat.temperature()[idx]);
        if (ijk[1] == 6)
          s.q_abs[ijk[0]] = heat.laser_source()[idx] * h;
      }
    for (auto *v : {&s.enthalpy_j, &s.q_abs})
      {
        const std::vector<double> local = *v;
        Utilities::MPI::sum(ArrayView<const double>(local),
                            comm,
                            ArrayView<double>(*v));
      }
    const auto b = heat.energy_budget();
    s.laser      = b.laser;
    s.balance    = std::abs(heat.stored_enthalpy() - H0 + b.evaporation +
                         b.convection + b.radiation - b.laser);
    return s;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           c(comm);
  const Material                   mat;

  // Closed form.
  const double Tv = mat.evaporation_temperature, Tl = mat.liquidus;
  auto         p_sat = [&](const double T) {
    return mat.ambient_pressure *
           std::exp(mat.latent_heat_evaporation * mat.molar_mass * (T - Tv) /
                    (R * T * Tv));
  };
  const double p_r = zeta * p_sat(Ts);
  const double k   = mat.conductivity.value(0.5 * (Ts + Tl));
  const double H   = mat.specific_heat.antiderivative(Tl) -
                   mat.specific_heat.antiderivative(T0) +
                   mat.latent_heat_fusion;
  const double rH = mat.density * H;
  const double l  = rb / 2;
  // The drilling speed at T_s = Ts for a recoil pressure p.
  auto drilling_speed = [&](const double p) {
    return std::sqrt(k * (Ts - Tl) * std::sqrt(2 * p / mat.density) / (l * rH));
  };
  const double u     = std::sqrt(2 * p_r / mat.density);
  const double v_d   = drilling_speed(p_r);
  const double delta = v_d * l / u;
  c.print("recoil pressure at T_s, MPa", p_r * 1e-6);
  c.print("Bernoulli speed u, m/s", u);
  c.print("closed-form film thickness delta, um", delta * 1e6);
  c.print("closed-form drilling speed v_d, m/s", v_d);
  // The grid's own conduction between the surface cell and the cell below.
  const double k_i =
    0.5 * mat.conductivity.value(Ts) + 0.5 * mat.gas_conductivity;
  const double k_j    = mat.conductivity.value(Tj);
  const double q_grid = 2 * k_i * k_j / (k_i + k_j) * (Ts - Tj) / h;
  c.print("grid conduction to the solid / film flux", q_grid / (rH * v_d));

  // Errors rounded up to the next power of ten, at least @p least (round-off
  // differs with the rank count).
  auto up = [](const double e, const double least) {
    return e > least ? std::pow(10., std::ceil(std::log10(e))) : least;
  };
  const std::string floor = ", next power of ten (at least 1e-9)";
  auto              front_speed =
    [&](const Step &on, const Step &off, const unsigned int x) {
      return (q_grid + (on.enthalpy_j[x] - off.enthalpy_j[x]) * h / dt) / rH;
    };
  // Evaporation at T_s (zeta_q = 0.82), W/m^2, for the first case.
  const double q_evap = mat.latent_heat_evaporation * 0.82 * p_r / zeta *
                        std::sqrt(mat.molar_mass / (2 * M_PI * R * Ts));
  for (const double power : {1e7, 3e6})
    {
      // The strong beam with evaporation, the weak one without (its cap is
      // then the absorbed flux itself).
      const double      zq  = power > 5e6 ? 0.82 : 0.;
      const std::string tag = "P = " + num(power) + " W/m: ";
      const Step        on  = step(true, power, zq, comm);
      const Step        off = step(false, power, zq, comm);
      double            err = 0, q_min = 1e300, q_max = 0;
      for (unsigned int x = 0; x < on.q_abs.size(); ++x)
        {
          q_min          = std::min(q_min, on.q_abs[x]);
          q_max          = std::max(q_max, on.q_abs[x]);
          const double v = front_speed(on, off, x);
          err            = std::max(err,
                         zq > 0 ? std::abs(v / v_d - 1) :
                                             std::abs(v * rH / on.q_abs[x] - 1));
        }
      if (zq > 0)
        {
          c.in_range(tag + "(least absorbed - 2 q_evap(T_s)) / film flux",
                     (q_min - 2 * q_evap) / (rH * v_d),
                     1.,
                     1e300);
          c.at_most(tag + "|front speed / v_d - 1|, worst column" + floor,
                    up(err, 1e-9),
                    1e-6);
          c.print(tag + "without the model: front speed / v_d",
                  q_grid / rH / v_d,
                  3);
        }
      else
        {
          c.in_range(tag + "least absorbed / grid conduction",
                     q_min / q_grid,
                     1.,
                     1e300);
          c.in_range(tag + "most absorbed / film flux",
                     q_max / (rH * v_d),
                     0.,
                     1.);
          c.at_most(tag + "|front flux / absorbed flux - 1|, worst column" +
                      floor,
                    up(err, 1e-9),
                    1e-6);
        }
      c.at_most(tag + "|stored change + losses - laser| / laser, next "
                      "power of ten (at least 1e-10)",
                up(on.balance / on.laser, 1e-10),
                1e-9);
    }
  {
    // The cell below the surface fully liquid (2000 K), the front one cell
    // further in: the film's flux goes there.
    const std::string tag = "melt between, P = 1e+07 W/m: ";
    const Step        on  = step(true, 1e7, 0.82, comm, true);
    const Step        off = step(false, 1e7, 0.82, comm, true);
    const double      k_l = mat.conductivity.value(T_liquid);
    const double      q_l = 2 * k_i * k_l / (k_i + k_l) * (Ts - T_liquid) / h;
    double            err = 0;
    for (unsigned int x = 0; x < on.q_abs.size(); ++x)
      err = std::max(err,
                     std::abs(
                       (q_l + (on.enthalpy_j[x] - off.enthalpy_j[x]) * h / dt) /
                         (rH * v_d) -
                       1));
    c.at_most(tag + "|front speed / v_d - 1|, worst column" + floor,
              up(err, 1e-9),
              1e-6);
    c.at_most(tag + "|stored change + losses - laser| / laser, next "
                    "power of ten (at least 1e-10)",
              up(on.balance / on.laser, 1e-10),
              1e-9);
  }
  {
    const Step on    = step(true, 0., 0.82, comm);
    const Step off   = step(false, 0., 0.82, comm);
    double     moved = 0;
    for (unsigned int x = 0; x < on.q_abs.size(); ++x)
      moved = std::max(moved, std::abs(on.enthalpy_j[x] - off.enthalpy_j[x]));
    c.at_most("laser off: largest enthalpy moved into the solid, J/m^3",
              moved,
              0.);
  }
  {
    // The recoil net of the ambient pressure (Recoil above ambient).
    const std::string tag   = "above ambient, P = 1e+07 W/m: ";
    const double      p_net = zeta * p_sat(Ts) - mat.ambient_pressure;
    const double      v_net = drilling_speed(p_net);
    c.print(tag + "recoil pressure at T_s, MPa", p_net * 1e-6);
    c.print(tag + "closed-form v_d / v_d with zeta_p p_sat", v_net / v_d);
    const Step on  = step(true, 1e7, 0.82, comm, false, Ts, true);
    const Step off = step(false, 1e7, 0.82, comm, false, Ts, true);
    double     err = 0, q_min = 1e300;
    for (unsigned int x = 0; x < on.q_abs.size(); ++x)
      {
        q_min = std::min(q_min, on.q_abs[x]);
        err   = std::max(err, std::abs(front_speed(on, off, x) / v_net - 1));
      }
    c.in_range(tag + "(least absorbed - 2 q_evap(T_s)) / film flux",
               (q_min - 2 * q_evap) / (rH * v_net),
               1.,
               1e300);
    c.at_most(tag + "|front speed / v_d(p_r net) - 1|, worst column" + floor,
              up(err, 1e-9),
              1e-6);
  }
  {
    // At 3150 K zeta_p p_sat = 0.73 p0: no recoil over the ambient.
    const double T_low = 3150;
    c.print("T_s = 3150 K: zeta_p p_sat / p0",
            zeta * p_sat(T_low) / mat.ambient_pressure);
    for (const bool net : {false, true})
      {
        const Step on    = step(true, 1e7, 0.82, comm, false, T_low, net);
        const Step off   = step(false, 1e7, 0.82, comm, false, T_low, net);
        double     moved = 0;
        for (unsigned int x = 0; x < on.q_abs.size(); ++x)
          moved =
            std::max(moved, std::abs(on.enthalpy_j[x] - off.enthalpy_j[x]));
        if (net)
          c.at_most("T_s = 3150 K, above ambient: largest enthalpy moved "
                    "into the solid, J/m^3",
                    moved,
                    0.);
        else
          c.in_range("T_s = 3150 K, zeta_p p_sat: largest enthalpy moved "
                     "into the solid, J/m^3",
                     moved,
                     1.,
                     1e300);
      }
  }
  return c.exit_code();
}
