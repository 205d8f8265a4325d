// Melt flow, front-wall expulsion (Melt flow/Front wall expulsion;
// doc/flow.md, "Front wall expulsion"): a melt film one cell thick on a
// solid substrate across the whole box, no gravity, no surface tension, its
// temperature falling linearly along it from 3500 K at the wall x = 0 to
// 3200 K at x = L (above the evaporation temperature 3090 K everywhere),
// the recoil taken from each cell's own temperature. Every surface cell
// boils and the surface gradient of T points along -x, so the model raises
// the x velocity of the film's top nodes to the Bernoulli speed
// u_B = sqrt(2 p_r / rho) of each cell's recoil; the bottom nodes (corners
// of the solid substrate) stay at rest. The points lie at 1/4 and 3/4 of
// the cell height and move with the bilinear nodal velocity, so the film's
// points must move on average by u_B t / 2 (u_B averaged over the film's
// cells) in a time t:
//  1. with the option, the mean x displacement of the fluid points over
//     (mean u_B) t / 2 lies within 10 % of 1 (printed; the pressure
//     correction of the converging film and the points stopped at x = L
//     make up the difference);
//  2. without it the same ratio stays below 0.3 (the grid's own recoil
//     gradient moves the film far less), so the first check can fail;
//  3. the points are moved, not removed: the points' mass with the option
//     equals that without (relative 1e-12);
//  4. a cold film (300 K: no boiling cell) has no expelling cell and gives
//     the same points with and without the option (relative 1e-12).
// 2D, 1 and 2 ranks give the same output.
#include <cmath>

#include "flow_tools.h"

using namespace femp_test;

namespace
{
  constexpr int          dim = 2;
  constexpr double       h = 0.025, rho = 1000, y_wall = 0.2, L = 1.0;
  constexpr double       T_wall = 3500, T_end = 3200; // K, at x = 0 and L
  constexpr double       dt      = 2e-4;
  constexpr unsigned int n_steps = 10;

  double
  film_temperature(const double x)
  {
    return T_wall + (T_end - T_wall) * x / L;
  }

  struct Result
  {
    double        displacement = 0, mass = 0, sum_position = 0;
    unsigned long expelling = 0, n_fluid = 0;
  };

  Result
  run(const bool expel, const bool hot, MPI_Comm comm)
  {
    IncompressibleFlow<dim>::Parameters prm;
    prm.viscosity          = 1e-3;
    prm.gravity            = Tensor<1, dim>();
    prm.recoil_coefficient = 0.54;
    // zeta_p p_sat(T): every surface cell above T_v boils.
    prm.recoil_above_ambient = false;
    prm.recoil_temperature =
      FreeSurface<dim>::Parameters::RecoilTemperature::cell;
    prm.pressure.solver_tolerance = 1e-12;
    prm.front_wall_expulsion      = expel;
    FlowScene<dim> scene(
      Point<dim>(L, 0.4),
      h,
      rho,
      [](const Point<dim> &x) { return x[1] < y_wall + h; },
      prm,
      comm);
    // Beam radius and far-field temperature for the piston's film; the
    // scene's material melts at 1e6 K, so the film is zero and every
    // boiling surface cell holds melt beyond it.
    scene.flow->enable_front_wall_expulsion(30e-6, 300);
    // The substrate's points solid, the film's fluid (the state follows
    // the cell temperature against the material's solidus, 1e6 K).
    std::vector<double> state_T = scene.grid.make_field(300.);
    for (std::size_t i = 0; i < state_T.size(); ++i)
      if (scene.grid.cell_center(i)[1] > y_wall)
        state_T[i] = 2e6;
    scene.points->cells_to_points(state_T);
    std::vector<double> temperature = scene.grid.make_field(300.);
    if (hot)
      for (std::size_t i = 0; i < temperature.size(); ++i)
        temperature[i] = film_temperature(scene.grid.cell_center(i)[0]);
    CellFields<dim> fields;
    fields.temperature = &temperature;
    using P            = MaterialPoints<dim>::PropertyIndex;
    auto sums          = [&](double &sum_x, double &mass, unsigned long &n) {
      sum_x = mass = 0;
      n            = 0;
      for (const auto &particle : scene.points->particle_handler())
        {
          const auto v = particle.get_properties();
          mass += v[P::mass];
          if (v[P::state] != MaterialPoints<dim>::fluid)
            continue;
          sum_x += particle.get_location()[0];
          ++n;
        }
      sum_x = Utilities::MPI::sum(sum_x, comm);
      mass  = Utilities::MPI::sum(mass, comm);
      n     = Utilities::MPI::sum(n, comm);
    };
    Result r;
    double x0, m0;
    sums(x0, m0, r.n_fluid);
    for (unsigned int n = 0; n < n_steps; ++n)
      scene.flow->step(dt, fields);
    r.expelling = scene.flow->statistics().expelling_cell_steps;
    sums(r.sum_position, r.mass, r.n_fluid);
    r.displacement = (r.sum_position - x0) / r.n_fluid;
    return r;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  try
    {
      IncompressibleFlow<dim>::Parameters prm;
      prm.recoil_coefficient   = 0.54;
      prm.recoil_above_ambient = false;
      // The mean over the film's cells of the Bernoulli speed of their
      // recoil (the temperature is constant per cell, taken at its
      // centre).
      const unsigned int n_cells = std::round(L / h);
      double             u_mean  = 0;
      for (unsigned int i = 0; i < n_cells; ++i)
        u_mean += std::sqrt(
          2 * recoil_pressure<dim>(prm, film_temperature((i + 0.5) * h)) / rho);
      u_mean /= n_cells;
      const double expected = 0.5 * u_mean * n_steps * dt;
      checks.print("mean Bernoulli speed of the film's cells, m/s", u_mean);
      checks.print("expected mean displacement u_B t / 2, m", expected);

      const Result on = run(true, true, comm);
      checks.print("expulsion: mean displacement, m", on.displacement);
      checks.at_most("expulsion: |displacement / (u_B t / 2) - 1|",
                     std::abs(on.displacement / expected - 1),
                     0.1);
      checks.in_range("expulsion: expelling cells per fluid step",
                      on.expelling / n_steps,
                      1,
                      n_cells);

      const Result off = run(false, true, comm);
      checks.print("without: mean displacement, m", off.displacement);
      checks.in_range("without: displacement / (u_B t / 2)",
                      std::round(off.displacement / expected * 100) / 100,
                      -0.3,
                      0.3);
      checks.at_most("points' mass with / without - 1",
                     std::abs(on.mass / off.mass - 1),
                     1e-12);

      const Result cold_on  = run(true, false, comm);
      const Result cold_off = run(false, false, comm);
      checks.in_range("cold film: expelling cells", cold_on.expelling, 0, 0);
      checks.at_most("cold film: |sum x (with) / sum x (without) - 1|",
                     std::abs(cold_on.sum_position / cold_off.sum_position - 1),
                     1e-12);
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
