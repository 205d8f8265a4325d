// Melt flow, static droplet in 3D (doc/verification.md, "Static droplet"):
// a sphere of radius R = 0.25 m in a 1 m box, no gravity, sigma = 1 N/m,
// mu = 0.5 Pa s, with point shifting (A = 2) and two passes of curvature
// smoothing, run to 1.5 capillary times sqrt(rho R^3/sigma) at the
// automatic step. The pressure inside (mean over the cells within R/2 of
// the centre) must match the Laplace jump 2 sigma/R within 5 %; the
// spurious-current capillary number mu u_max/sigma is printed. Run with
// both curvatures of Melt flow/Curvature: the alpha gradient and the
// height function (whose 3D form, with the mixed derivative, this test
// is the check of).
//
// Optional arguments: R/h (default 8), the curvature (0: alpha gradient,
// 1: height function; default: both), and the number of capillary times
// (default 1.5).
#include "flow_tools.h"

using namespace femp_test;

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  constexpr int                    dim   = 3;
  const double                     R_h   = argc > 1 ? std::atof(argv[1]) : 8;
  const int                        which = argc > 2 ? std::atoi(argv[2]) : -1;
  const double                     times = argc > 3 ? std::atof(argv[3]) : 1.5;
  const double L = 1, R = 0.25, h = R / R_h, rho = 1000, sigma = 1, mu = 0.5;
  const Point<dim> centre(0.5, 0.5, 0.5);
  for (const int hf : {0, 1})
    {
      if (which >= 0 && hf != which)
        continue;
      typename IncompressibleFlow<dim>::Parameters prm;
      prm.point_shifting      = 2;
      prm.curvature_smoothing = 2;
      prm.curvature = (hf == 1) ? decltype(prm.curvature)::height_function :
                                  decltype(prm.curvature)::alpha_gradient;
      prm.viscosity = mu;
      prm.gravity   = Tensor<1, dim>();
      prm.surface_tension = sigma;
      checks.print(hf ? "curvature: height function" :
                        "curvature: alpha gradient",
                   R_h);
      FlowScene<dim> scene(
        Point<dim>(L, L, L),
        h,
        rho,
        [&](const Point<dim> &x) { return x.distance(centre) < R; },
        prm,
        comm);
      const double       dt      = scene.flow->stable_time_step().min();
      const double       t_sigma = std::sqrt(rho * R * R * R / sigma);
      const unsigned int n_steps =
        static_cast<unsigned int>(std::ceil(times * t_sigma / dt));
      for (unsigned int n = 0; n < n_steps; ++n)
        scene.flow->step(dt);
      const double p_in = scene.mean_pressure_within(centre, R / 2);
      const double umax = scene.max_over_points(
        [](const Point<dim> &, auto v) { return point_speed<dim>(v); });
      const double jump = 2 * sigma / R;
      if (Utilities::MPI::this_mpi_process(comm) == 0)
        std::cerr << std::setprecision(8) << "unrounded: Laplace jump error "
                  << std::abs(p_in - jump) / jump << ", mu u_max/sigma "
                  << mu * umax / sigma << ", steps " << n_steps << std::endl;
      checks.print("steps", n_steps);
      checks.print("inside pressure / (2 sigma/R)",
                   std::round(p_in / jump * 1000) / 1000);
      checks.at_most("|Laplace jump error|",
                     std::round(std::abs(p_in - jump) / jump * 1000) / 1000,
                     0.05);
      checks.print("spurious-current capillary number mu u_max/sigma",
                   std::round(mu * umax / sigma * 1e4) / 1e4);
    }
  return checks.exit_code();
}
