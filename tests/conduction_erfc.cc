// Verification: 1D transient conduction into a half space (doc/verification.md,
// theta = erfc): a strip x in [0, 2] initially at T0 = 1 with the
// face x = 0 held at T0 + 1 from t = 0; all properties 1. Compares with
// T = T0 + erfc(x / (2 sqrt(t))) at t = 0.05 on three grids and prints the
// observed order of spatial convergence (diffusion step ~ h^2, so the time
// error shrinks at the same rate).
#include "test_tools.h"

using namespace femp_test;

double
run(const double h, MPI_Comm comm)
{
  const int           dim = 2;
  const auto          gp  = box<dim>(Point<dim>(0, 0), Point<dim>(2, 2 * h), h);
  BackgroundGrid<dim> grid(gp, comm);
  grid.create();
  const Material    mat = unit_material();
  Laser<dim>        laser(laser_off<dim>());
  HeatTransfer<dim> heat(heat_parameters<dim>(1., {{"x-", 2.}}),
                         mat,
                         laser,
                         grid);
  heat.initialize();
  heat.set_metal_fraction(grid.make_field(1.));

  const double       t_end = 0.05;
  double             t     = 0;
  const double       dt0   = 0.4 * heat.stable_time_step();
  const unsigned int n     = std::ceil(t_end / dt0);
  const double       dt    = t_end / n;
  for (unsigned int i = 0; i < n; ++i, t += dt)
    heat.advance(dt, t);

  double err = 0;
  for (const auto idx : grid.owned_cells())
    {
      const double x = grid.cell_center(idx)[0];
      err            = std::max(err,
                     std::abs(heat.temperature()[idx] -
                              (1 + std::erfc(x / (2 * std::sqrt(t_end))))));
    }
  return Utilities::MPI::max(err, comm);
}

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  const double                     e1 = run(1. / 20, comm);
  const double                     e2 = run(1. / 40, comm);
  const double                     e3 = run(1. / 80, comm);
  checks.print("max error h=1/20", e1, 2);
  checks.print("max error h=1/40", e2, 2);
  checks.print("max error h=1/80", e3, 2);
  const double order = std::log2(e2 / e3);
  checks.in_range("observed order (1/40 -> 1/80)", order, 1.8, 2.3);
  checks.at_most("max error h=1/80", e3, 2e-4);
  return checks.exit_code();
}
