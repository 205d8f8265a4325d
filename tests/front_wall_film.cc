// Melt flow, front-wall film (Melt flow/Front wall film; doc/flow.md, "Front
// wall film"): a melt film one cell thick on a solid substrate across the
// whole box, no gravity, no surface tension, its temperature falling
// linearly along it from 3500 K at the wall x = 0 to 3200 K at x = L (above
// the evaporation temperature 3090 K everywhere), the recoil taken from each
// cell's own temperature. The recoil pressure presses the film onto the
// substrate; its surface is flat, so along the film only the walls at its
// ends act, with p_0 delta and p_L delta per unit depth (p the surface
// pressure of the end cells, delta the film's thickness, one cell).
//  1. With the option every surface cell is recoil-driven and the film
//     slips on the substrate: its momentum along x after a time t must be
//     (p_0 - p_L) delta t (printed error; tolerance 10 %: the projection is
//     approximate, doc/flow.md step 5, and the film thins at x = 0 as it
//     moves; 5 % after 20 steps, 6 % after 50).
//  2. Without it (no slip on the nodes of the solid cells) the substrate
//     takes most of that momentum: the ratio must stay below 0.5, so the
//     first check can fail.
//  3. With the option, a cold film (300 K, no recoil-driven cell) gives the
//     same points as without it (relative 1e-12).
// 2D, 1 and 2 ranks give the same output.
#include <cmath>

#include "flow_tools.h"

using namespace femp_test;

namespace
{
  constexpr int    dim = 2;
  constexpr double h = 0.025, rho = 1000, y_wall = 0.2, L = 1.0;
  constexpr double T_wall = 3500, T_end = 3200; // K, at x = 0 and x = L

  double
  film_temperature(const double x)
  {
    return T_wall + (T_end - T_wall) * x / L;
  }

  struct Result
  {
    double        momentum_x = 0, sum_position = 0;
    unsigned long driven = 0;
  };

  Result
  run(const bool film, const bool hot, MPI_Comm comm)
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
    prm.front_wall_film           = film;
    FlowScene<dim> scene(
      Point<dim>(L, 0.4),
      h,
      rho,
      [](const Point<dim> &x) { return x[1] < y_wall + h; },
      prm,
      comm);
    // The substrate's points solid: the points take the state of their
    // cell's temperature against the solidus of the scene's material
    // (1e6 K): below it in the substrate, above it in the film.
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
    fields.temperature         = &temperature;
    const double       dt      = 2e-4;
    const unsigned int n_steps = 20;
    Result             r;
    for (unsigned int n = 0; n < n_steps; ++n)
      {
        scene.flow->step(dt, fields);
        if (n == 0)
          r.driven = scene.flow->recoil_driven_cells();
      }
    using P = MaterialPoints<dim>::PropertyIndex;
    for (const auto &particle : scene.points->particle_handler())
      {
        const auto v = particle.get_properties();
        if (v[P::state] != MaterialPoints<dim>::fluid)
          continue;
        r.momentum_x += v[P::mass] * v[P::velocity];
        r.sum_position += particle.get_location()[0];
      }
    r.momentum_x   = Utilities::MPI::sum(r.momentum_x, comm);
    r.sum_position = Utilities::MPI::sum(r.sum_position, comm);
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
      prm.recoil_temperature =
        FreeSurface<dim>::Parameters::RecoilTemperature::cell;
      // The surface pressure of the first and the last cell (the
      // temperature is constant per cell, taken at its centre).
      const double p0 = recoil_pressure<dim>(prm, film_temperature(0.5 * h));
      const double p1 =
        recoil_pressure<dim>(prm, film_temperature(L - 0.5 * h));
      const double t        = 20 * 2e-4;
      const double expected = (p0 - p1) * h * t; // per unit depth
      checks.print("recoil pressure at the wall x = 0, Pa", p0);
      checks.print("recoil pressure at the wall x = L, Pa", p1);
      checks.print("expected momentum (p_0 - p_L) delta t, kg/s", expected);

      const Result on = run(true, true, comm);
      checks.print("slip: momentum along the film, kg/s", on.momentum_x);
      checks.at_most("slip: |momentum / ((p_0 - p_L) delta t) - 1|",
                     std::abs(on.momentum_x / expected - 1),
                     0.1);
      checks.in_range("slip: recoil-driven surface cells at the first step",
                      on.driven,
                      std::round(L / h),
                      std::round(L / h));

      const Result off = run(false, true, comm);
      checks.print("no slip: momentum along the film, kg/s", off.momentum_x);
      checks.in_range("no slip: momentum / ((p_0 - p_L) delta t)",
                      std::round(off.momentum_x / expected * 100) / 100,
                      0,
                      0.5);

      const Result cold_on  = run(true, false, comm);
      const Result cold_off = run(false, false, comm);
      checks.in_range("cold film: recoil-driven surface cells",
                      cold_on.driven,
                      0,
                      0);
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
