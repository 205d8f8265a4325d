// Melt flow, hydrostatics (doc/verification.md): a pool of depth H at
// rest in a box under gravity (H a whole number of cells, and H = 11.5
// cells: the free surface inside a cell, the sub-cell interface position).
// After many fluid steps the cell-centre pressure must match rho g (H - z)
// within 1 % of rho g H, and the point velocities must stay at round-off level
// (compare: free fall would reach g t). 2D and 3D; 1 and 2 ranks give the same
// output.
#include "flow_tools.h"

using namespace femp_test;

template <int dim>
void
check(Checks &checks, MPI_Comm comm, const unsigned int n_steps, const double H)
{
  const double h = 0.025, rho = 1000, g = 9.81;
  Point<dim>   size;
  for (int d = 0; d < dim; ++d)
    size[d] = (dim == 2 ? 0.4 : 0.2);
  size[dim - 1] = 0.4;
  typename IncompressibleFlow<dim>::Parameters prm;
  prm.viscosity                 = 1e-3;
  prm.pressure.solver_tolerance = 1e-12;
  FlowScene<dim> scene(
    size,
    h,
    rho,
    [&](const Point<dim> &x) { return x[dim - 1] < H; },
    prm,
    comm);
  const auto   limits = scene.flow->stable_time_step();
  const double dt     = limits.min();
  for (unsigned int n = 0; n < n_steps; ++n)
    scene.flow->step(dt);

  // The material surface: top lattice point (spacing h/2) + half a spacing.
  const double s  = h / 2;
  const double Hm = std::ceil(H / s - 0.5) * s;
  // Pressure error at the centres of fluid cells.
  const auto &p    = scene.flow->pressure();
  const auto &type = scene.flow->cell_type();
  double      err = 0, n_fluid = 0;
  for (const auto idx : scene.grid.owned_cells())
    if (type[idx] == IncompressibleFlow<dim>::fluid)
      {
        const double z = scene.grid.cell_center(idx)[dim - 1];
        err            = std::max(err, std::abs(p[idx] - rho * g * (Hm - z)));
        ++n_fluid;
      }
  err     = Utilities::MPI::max(err, comm) / (rho * g * Hm);
  n_fluid = Utilities::MPI::sum(n_fluid, comm);
  const double umax =
    scene.max_over_points([](const Point<dim> &, ArrayView<const double> v) {
      return point_speed<dim>(v);
    });
  const std::string D =
    std::to_string(dim) + "D, H = " + std::to_string(H).substr(0, 4) + ": ";
  checks.print(D + "fluid cells", n_fluid);
  checks.print(D + "material surface H_m, m", Hm);
  checks.print(D + "steps", n_steps);
  checks.print(D + "time, s", std::round(n_steps * dt * 1e4) / 1e4);
  checks.print(D + "pressure matrix builds",
               scene.flow->statistics().matrix_rebuilds);
  checks.at_most(D + "max |p - rho g (H_m - z)| / (rho g H_m)", err, 0.01);
  checks.at_most(D + "max point speed / (g t)",
                 umax / (g * n_steps * dt),
                 1e-9);
}

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  Checks                           checks(MPI_COMM_WORLD);
  try
    {
      check<2>(checks, MPI_COMM_WORLD, 400, 0.3);
      check<3>(checks, MPI_COMM_WORLD, 100, 0.15);
      check<2>(checks, MPI_COMM_WORLD, 400, 0.29);
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
