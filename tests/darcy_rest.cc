// Melt flow, Darcy damping: a column of width a and height 2a (the dam-break
// column) whose liquid fraction gamma is 0 (fully solid, mushy-zone
// constant K_c = 1e8 kg/(m^3 s)) must stay at rest under gravity: after
// 0.1 s its points may have moved at most 1e-6 a and their speed must be
// below 1e-6 sqrt(g a). Control run with gamma = 1: the same column must
// collapse (front beyond 1.3 a), so the check can fail. 2D, 1 and 2 ranks.
#include "flow_tools.h"

using namespace femp_test;

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  constexpr int                    dim = 2;
  const double a = 0.05715, g = 9.81, rho = 1000, h = a / 8, t_end = 0.1;
  try
    {
      for (const double gamma_value : {0., 1.})
        {
          typename IncompressibleFlow<dim>::Parameters prm;
          prm.viscosity = 1e-3;
          FlowScene<dim> scene(
            Point<dim>(4 * a, 2.5 * a),
            h,
            rho,
            [&](const Point<dim> &x) { return x[0] < a && x[1] < 2 * a; },
            prm,
            comm);
          const std::vector<double> gamma = scene.grid.make_field(gamma_value);
          CellFields<dim>           fields;
          fields.liquid_fraction = &gamma;
          double time            = 0;
          while (time < t_end)
            {
              const double dt = std::min(scene.flow->stable_time_step().min(),
                                         t_end - time + 1e-12);
              scene.flow->step(dt, fields);
              time += dt;
            }
          // The column's points start on the lattice (i + 1/2) h/2: the
          // largest x is a - h/4 and the largest height 2a - h/4.
          const double front = scene.max_over_points(
            [](const Point<dim> &x, auto) { return x[0]; });
          const double top = scene.max_over_points(
            [](const Point<dim> &x, auto) { return x[1]; });
          const double umax = scene.max_over_points(
            [](const Point<dim> &, auto v) { return point_speed<dim>(v); });
          const std::string G =
            "gamma = " + std::to_string(int(gamma_value)) + ": ";
          if (gamma_value == 0)
            {
              checks.at_most(G + "front displacement / a",
                             std::abs(front - (a - h / 4)) / a,
                             1e-6);
              checks.at_most(G + "top displacement / a",
                             std::abs(top - (2 * a - h / 4)) / a,
                             1e-6);
              checks.at_most(G + "max speed / sqrt(g a)",
                             umax / std::sqrt(g * a),
                             1e-6);
            }
          else
            checks.in_range(G + "front position / a (collapses)",
                            std::round(front / a * 100) / 100,
                            1.3,
                            5);
        }
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
