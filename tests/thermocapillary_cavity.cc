// Melt flow, thermocapillary return flow (doc/verification.md): a shallow
// liquid layer of depth D = 8 h and length 10 D on a no-slip solid floor
// (one row of solid points), free surface kept flat by a strong gravity
// (1000 m/s^2), imposed temperature
// T = T0 + G x. The Marangoni shear tau_s = dsigma/dT G drives
// u(zeta) = tau_s D/(4 mu) (3 zeta^2 - 2 zeta), zeta from the floor, at low
// Reynolds number. At mid-length, the cell-centre velocity profile must
// match within 5 % of the surface speed, and the zero crossing must lie
// within 5 % of zeta = 2/3. 2D; 1 and 2 ranks give the same output.
#include "flow_tools.h"

using namespace femp_test;

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  constexpr int                    dim = 2;
  const double h = 1e-3, D = 8 * h, Lx = 10 * D, rho = 1000, mu = 1;
  const double dsdT = -1e-3, G = 100, tau = dsdT * G, U = tau * D / (4 * mu);
  try
    {
      typename IncompressibleFlow<dim>::Parameters prm;
      prm.viscosity                = mu;
      prm.surface_tension_gradient = dsdT;
      // The analytic profile assumes a flat surface: a strong gravity keeps
      // the tilt that carries the return-flow pressure gradient far below a
      // cell (3 tau_s Lx/(2 D rho g) ~ 1e-6 m) and lets it settle quickly.
      prm.gravity[dim - 1] = -1000;
      FlowScene<dim> scene(
        Point<dim>(Lx, D + 3 * h),
        h,
        rho,
        [&](const Point<dim> &x) { return x[1] < D + h; },
        prm,
        comm);
      // The bottom row of points is solid: a no-slip floor at y = h.
      for (auto &p : scene.points->particle_handler())
        if (p.get_location()[1] < h)
          p.get_properties()[MaterialPoints<dim>::PropertyIndex::state] =
            MaterialPoints<dim>::solid;
      std::vector<double> T = scene.grid.make_field();
      for (std::size_t i = 0; i < T.size(); ++i)
        if (scene.grid.cell_status()[i] != BackgroundGrid<dim>::outside)
          T[i] = 1000 + G * scene.grid.cell_center(i)[0];
      CellFields<dim> fields;
      fields.temperature   = &T;
      const double dt      = scene.flow->stable_time_step().min();
      const double t_end   = 4 * rho * D * D / mu; // 4 viscous times
      unsigned int n_steps = 0;
      for (double t = 0; t < t_end; t += dt, ++n_steps)
        scene.flow->step(dt, fields);
      // Profile in the cell column at mid-length (x = Lx/2 is a node line:
      // mean of the two columns beside it).
      const auto         &u  = scene.flow->cell_velocity()[0];
      const int           nz = 8;
      std::vector<double> prof(nz, 0.);
      for (const auto idx : scene.grid.owned_cells())
        {
          const auto ijk = scene.grid.global_index(idx);
          const int  i0  = int(std::round(Lx / 2 / h));
          if ((ijk[0] == i0 - 1 || ijk[0] == i0) && ijk[1] >= 1 && ijk[1] <= nz)
            prof[ijk[1] - 1] += 0.5 * u[idx];
        }
      double err = 0, zero = -1;
      for (int j = 0; j < nz; ++j)
        {
          prof[j]          = Utilities::MPI::sum(prof[j], comm);
          const double z   = (j + 0.5) / nz;
          const double ref = U * (3 * z * z - 2 * z);
          err = std::max(err, std::abs(prof[j] - ref) / std::abs(U));
          checks.print("u/U_s at zeta = " + std::to_string(z).substr(0, 6) +
                         " (analytic " + std::to_string(ref / U).substr(0, 6) +
                         ")",
                       std::round(prof[j] / U * 1000) / 1000);
          if (j > 0 && zero < 0 && prof[j - 1] * prof[j] <= 0 &&
              prof[j] != prof[j - 1])
            zero = (j - 0.5 + prof[j - 1] / (prof[j - 1] - prof[j])) / nz;
        }
      checks.print("steps", n_steps);
      checks.print("Reynolds number rho U D/mu", std::abs(rho * U * D / mu));
      checks.at_most("max |u - u_exact| / U_s", err, 0.05);
      checks.at_most("|zero crossing - 2/3| / (2/3)",
                     std::abs(zero - 2. / 3) * 1.5,
                     0.05);
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
