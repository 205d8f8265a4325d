// Verification of the upwind convection term with a prescribed velocity:
// a temperature step at x0 = 0.5 carried at u = 1 along a strip with
// diffusivity 0.01 (Peclet u L / kappa = 100). Exact on the infinite line:
// T = 1 + 0.5 erfc((x - x0 - u t) / (2 sqrt(kappa t))), here from t0 = 0.02
// (smooth start) to t = 0.5. First-order upwinding adds a numerical
// diffusion u h / 2: the observed order must be about 1.
#include "test_tools.h"

using namespace femp_test;

const double kappa = 0.01, u = 1., x0 = 0.5, t0 = 0.02;

double
exact(const double x, const double t)
{
  return 1 + 0.5 * std::erfc((x - x0 - u * t) / (2 * std::sqrt(kappa * t)));
}

double
run(const double h, MPI_Comm comm)
{
  const int           dim = 2;
  const auto          gp  = box<dim>(Point<dim>(0, 0), Point<dim>(2, 2 * h), h);
  BackgroundGrid<dim> grid(gp, comm);
  grid.create();
  Material mat     = unit_material();
  mat.conductivity = PiecewiseLinear(kappa);
  Laser<dim> laser(laser_off<dim>());
  auto       p          = heat_parameters<dim>(1., {});
  p.prescribed_velocity = "1; 0";
  HeatTransfer<dim> heat(p, mat, laser, grid);
  heat.initialize();
  heat.set_metal_fraction(grid.make_field(1.));
  const auto &T = heat.temperature();
  for (std::size_t idx = 0; idx < T.size(); ++idx)
    heat.set_cell_temperature(idx, exact(grid.cell_center(idx)[0], t0));

  const double       t_end = 0.5;
  const double       dt0   = 0.5 * heat.stable_time_step();
  const unsigned int n     = std::ceil((t_end - t0) / dt0);
  const double       dt    = (t_end - t0) / n;
  double             t     = t0;
  for (unsigned int i = 0; i < n; ++i, t += dt)
    heat.advance(dt, t);

  double err = 0;
  for (const auto idx : grid.owned_cells())
    err =
      std::max(err, std::abs(T[idx] - exact(grid.cell_center(idx)[0], t_end)));
  return Utilities::MPI::max(err, comm);
}

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  const double                     e1 = run(1. / 100, comm);
  const double                     e2 = run(1. / 200, comm);
  const double                     e3 = run(1. / 400, comm);
  checks.print("max error h=1/100", e1, 2);
  checks.print("max error h=1/200", e2, 2);
  checks.print("max error h=1/400", e3, 2);
  checks.in_range("observed order (1/200 -> 1/400)",
                  std::log2(e2 / e3),
                  0.8,
                  1.3);
  checks.at_most("max error h=1/400", e3, 0.03);
  return checks.exit_code();
}
