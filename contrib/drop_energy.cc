// femp study tool (doc/stability.md, "An energy check for the surface
// tension, measured and not adopted"): the mechanical energy of a 2D drop
// under surface tension over time, to see whether a failing surface
// representation can be told from a correct one by the energy it creates.
//
// The scene is that of tests/static_droplet.cc and tests/oscillating_
// droplet.cc (R = 0.25 m in a 1 m box, rho = 1000 kg/m^3, sigma = 1 N/m,
// no gravity), optionally with a mode-2 shape r = R (1 + eps cos 2 theta).
// Every 20 flow steps it prints, relative to the surface energy sigma A0 of
// the start,
//   K      kinetic energy of the points, sum 1/2 m v^2;
//   dA     change of the interface length A, the length of the alpha = 1/2
//          contour (marching squares) of the nodal metal fraction mapped
//          from the points with tent weights (the alpha the flow sees);
//   dE     (K + sigma A) - (K0 + sigma A0), which no drop without a drive
//          can make positive beyond the errors of the measure;
// and the shape measure S of tests/flow_tools.h; at the end the largest dE.
//
// Usage (one rank): drop_energy R/h C passes shifting eps t_end [height
// function 0|1] [mu, Pa s, default 0.5] [FLIP fraction, default 0.95]
//   R/h      cells per radius; C the step as a multiple of the capillary
//   limit (forced past it above 1); passes of curvature smoothing; point
//   shifting A; eps the mode-2 amplitude (0: a static drop); t_end in
//   capillary times sqrt(rho R^3/sigma).
// Example: build/contrib/drop_energy 40 0.5 0 0 0 2.5
#include <array>
#include <cstdlib>
#include <iostream>

#include "../tests/flow_tools.h"

using namespace femp_test;

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  constexpr int                    dim  = 2;
  if (argc < 7 || Utilities::MPI::n_mpi_processes(comm) != 1)
    {
      std::cerr << "usage (one rank): drop_energy R/h C passes shifting eps "
                   "t_end [height function 0|1] [mu] [FLIP fraction]\n";
      return 1;
    }
  const double     R_h    = std::atof(argv[1]);
  const double     C      = std::atof(argv[2]);
  const int        passes = std::atoi(argv[3]);
  const double     shift  = std::atof(argv[4]);
  const double     eps    = std::atof(argv[5]);
  const double     t_end  = std::atof(argv[6]);
  const bool       hf     = argc > 7 && std::atoi(argv[7]) != 0;
  const double     mu     = argc > 8 ? std::atof(argv[8]) : 0.5;
  const double     flip   = argc > 9 ? std::atof(argv[9]) : 0.95;
  const double     L = 1, R = 0.25, h = R / R_h, rho = 1000, sigma = 1;
  const Point<dim> centre(0.5, 0.5);

  typename IncompressibleFlow<dim>::Parameters prm;
  prm.viscosity           = mu;
  prm.gravity             = Tensor<1, dim>();
  prm.surface_tension     = sigma;
  prm.flip_fraction       = flip;
  prm.point_shifting      = shift;
  prm.curvature_smoothing = passes;
  prm.curvature           = (hf) ? decltype(prm.curvature)::height_function :
                                   decltype(prm.curvature)::alpha_gradient;
  FlowScene<dim> scene(
    Point<dim>(L, L),
    h,
    rho,
    [&](const Point<dim> &x) {
      const double th = std::atan2(x[1] - centre[1], x[0] - centre[0]);
      return x.distance(centre) < R * (1 + eps * std::cos(2 * th));
    },
    prm,
    comm);
  const int n = static_cast<int>(std::round(L / h));

  // K and A of the current points.
  auto energies = [&](double &K, double &A) {
    std::vector<double> node((n + 1) * (n + 1), 0.);
    K = 0;
    for (const auto &p : scene.points->particle_handler())
      {
        const auto   x  = p.get_location();
        const double fx = x[0] / h, fy = x[1] / h;
        const int    i = std::min(n - 1, int(fx)), j = std::min(n - 1, int(fy));
        const double wx = fx - i, wy = fy - j, v0 = 0.25; // point volume / h^2
        node[i + (n + 1) * j] += v0 * (1 - wx) * (1 - wy);
        node[i + 1 + (n + 1) * j] += v0 * wx * (1 - wy);
        node[i + (n + 1) * (j + 1)] += v0 * (1 - wx) * wy;
        node[i + 1 + (n + 1) * (j + 1)] += v0 * wx * wy;
        const double v = point_speed<dim>(p.get_properties());
        K += 0.5 * rho * h * h / 4 * v * v;
      }
    auto a = [&](int i, int j) { return node[i + (n + 1) * j]; };
    A      = 0;
    const double corner[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        {
          const double                       c[4] = {a(i, j) - 0.5,
                                                     a(i + 1, j) - 0.5,
                                                     a(i + 1, j + 1) - 0.5,
                                                     a(i, j + 1) - 0.5};
          std::vector<std::array<double, 2>> cut;
          for (int e = 0; e < 4; ++e)
            {
              const double p = c[e], q = c[(e + 1) % 4];
              if ((p < 0) != (q < 0))
                {
                  const double t = p / (p - q);
                  const auto  &u = corner[e], &w = corner[(e + 1) % 4];
                  cut.push_back(
                    {u[0] + t * (w[0] - u[0]), u[1] + t * (w[1] - u[1])});
                }
            }
          for (std::size_t k = 0; k + 1 < cut.size(); k += 2)
            A += h * std::hypot(cut[k][0] - cut[k + 1][0],
                                cut[k][1] - cut[k + 1][1]);
        }
  };

  const double t_sigma = std::sqrt(rho * R * R * R / sigma);
  double       K0, A0;
  energies(K0, A0);
  std::cout << "A0 = " << A0 << " m (2 pi R = " << 2 * M_PI * R << ")\n";
  double t = 0, dE_max = 0;
  try
    {
      for (unsigned int k = 1; t < t_end * t_sigma; ++k)
        {
          const double dt = C * scene.flow->stable_time_step().capillary;
          scene.flow->forced_step(dt);
          t += dt;
          if (k % 20 == 0)
            {
              double K, A;
              energies(K, A);
              const double dE = (K + sigma * A) - (K0 + sigma * A0);
              dE_max          = std::max(dE_max, dE);
              std::cout << "t/t_sigma " << t / t_sigma << "  K "
                        << K / (sigma * A0) << "  dA " << (A - A0) / A0
                        << "  dE " << dE / (sigma * A0) << "  S "
                        << shape_measure(scene, comm) << '\n';
            }
        }
    }
  catch (const std::exception &e)
    {
      std::cout << "stopped: " << e.what() << '\n';
    }
  std::cout << "largest dE / (sigma A0) = " << dE_max / (sigma * A0)
            << std::endl;
  return 0;
}
