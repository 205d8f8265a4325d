// femp study tool (doc/stability.md, "A capillary wave on a flat layer"):
// a standing capillary wave on a liquid layer, no gravity, to see which
// free-surface settings keep a resolved wave stable.
//
// A layer of depth H = 0.25 m in a 1 m box (rho = 1000 kg/m^3, sigma = 1
// N/m, mu = 0.5 Pa s), its surface at y = H + a0 cos(pi x) between the
// free-slip side walls. Linear theory: omega^2 = (sigma k^3/rho)
// tanh(k H) with k = pi, a period of 44.1 s, and a viscous decay of the
// amplitude by exp(-2 nu k^2 t), 0.80 per half period. Every 200 flow
// steps (each half the capillary limit) it prints the time, the amplitude
// a = 2 H mean(cos(pi x)) over the points (a0 at the start) and the
// kinetic energy of the points over sigma L; at the end the zero
// crossings of a and the largest kinetic energy.
//
// Usage (one rank): capillary_wave cells a0 t_end [passes] [height
// function 0|1] [point shifting]
//   cells   cells across the box (the wave's 1/k spans cells/pi of them);
//   a0      the starting amplitude, m; t_end, s; passes of curvature
//   smoothing (default 0), the height-function curvature (default 0, the
//   alpha gradient), point shifting A (default 0).
// Example: build/contrib/capillary_wave 64 0.01 60
#include "../tests/flow_tools.h"

#include <cstdlib>
#include <iostream>

using namespace femp_test;

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  constexpr int                    dim  = 2;
  if (argc < 4 || Utilities::MPI::n_mpi_processes(comm) != 1)
    {
      std::cerr << "usage (one rank): capillary_wave cells a0 t_end [passes] "
                   "[height function 0|1] [point shifting]\n";
      return 1;
    }
  const double n_cells = std::atof(argv[1]);
  const double a0      = std::atof(argv[2]);
  const double t_end   = std::atof(argv[3]);
  const double L = 1, H = 0.25, h = L / n_cells, rho = 1000, sigma = 1,
               mu = 0.5;

  typename IncompressibleFlow<dim>::Parameters prm;
  prm.viscosity           = mu;
  prm.gravity             = Tensor<1, dim>();
  prm.surface_tension     = sigma;
  prm.curvature_smoothing = argc > 4 ? std::atoi(argv[4]) : 0;
  prm.height_function     = argc > 5 && std::atoi(argv[5]) != 0;
  prm.point_shifting      = argc > 6 ? std::atof(argv[6]) : 0;
  FlowScene<dim> scene(Point<dim>(L, L), h, rho,
                       [&](const Point<dim> &x) {
                         return x[1] < H + a0 * std::cos(M_PI * x[0]);
                       },
                       prm, comm);

  const double k = M_PI, nu = mu / rho;
  const double omega =
    std::sqrt(sigma * k * k * k / rho * std::tanh(k * H));
  std::cout << "linear theory: period " << 2 * M_PI / omega
            << " s, amplitude decay per half period "
            << std::exp(-2 * nu * k * k * M_PI / omega) << '\n';

  // Amplitude and kinetic energy of the current points.
  auto measure = [&](double &a, double &K) {
    double n = 0;
    a = 0, K = 0;
    for (const auto &p : scene.points->particle_handler())
      {
        a += std::cos(M_PI * p.get_location()[0]), n += 1;
        const double v = point_speed<dim>(p.get_properties());
        K += 0.5 * rho * h * h / 4 * v * v;
      }
    a = 2 * H * a / n;
  };

  double t = 0, a_prev = a0, K_max = 0;
  std::vector<double> crossings;
  for (unsigned int step = 1; t < t_end; ++step)
    {
      const double dt = 0.5 * scene.flow->stable_time_step().capillary;
      scene.flow->forced_step(dt);
      t += dt;
      if (step % 200 == 0)
        {
          double a, K;
          measure(a, K);
          K_max = std::max(K_max, K);
          if ((a < 0) != (a_prev < 0))
            crossings.push_back(t);
          a_prev = a;
          std::cout << "t " << t << " s  a/a0 " << a / a0 << "  K/(sigma L) "
                    << K / (sigma * L) << '\n';
        }
    }
  std::cout << "zero crossings of a (s):";
  for (const double c : crossings)
    std::cout << ' ' << c;
  std::cout << "\nlargest K/(sigma L) " << K_max / (sigma * L) << std::endl;
  return 0;
}
