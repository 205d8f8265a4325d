// Melt flow, static droplet (doc/verification.md): a 2D drop of radius R
// = 10 h, no gravity, surface tension sigma; 400 steps at the automatic
// step (default Melt flow/Capillary step fraction). The pressure inside must
// match the Laplace jump sigma/R within 5 % (mean over the cells within R/2 of
// the centre), after many steps; the spurious-current capillary number mu u_max
// / sigma is printed. Run twice: with the solver's defaults and with point
// shifting (A = 2) and two passes of curvature smoothing, the settings of the
// oscillating-droplet test (doc/flow.md). 1 and 2 ranks give the same output.
//
// Optional arguments (for contrib/study.py static_droplet; the test runs
// without them): R/h (default 10; 4 R/h an integer), Melt flow/FLIP
// fraction (default 0.95) and Melt flow/Capillary step fraction (default
// 0.5), and as a fourth argument 1 for the smoothed settings (point
// shifting 2, two smoothing passes; default 0: the solver's defaults),
// plus 2 for the height-function curvature (Melt flow/Curvature), plus 4
// for the smoothing without point shifting, then the number of smoothing
// passes of the smoothed settings (default 2; odd numbers, which femp's
// input refuses, reproduce doc/stability.md "Curvature smoothing"), then
// the end time in capillary times sqrt(rho R^3/sigma) (default 2.5).
// With them only that one run is made, to that time instead of 400
// steps, and the unrounded errors go to stderr.
#include <cstdlib>
#include <iostream>

#include "flow_tools.h"

using namespace femp_test;

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  constexpr int                    dim   = 2;
  const bool                       study = argc > 1;
  const double                     R_h   = study ? std::atof(argv[1]) : 10;
  const double                     flip  = argc > 2 ? std::atof(argv[2]) : 0.95;
  const double                     c_frac = argc > 3 ? std::atof(argv[3]) : 0.5;
  const int                        variant = argc > 4 ? std::atoi(argv[4]) : 0;
  const bool                       study_smoothed  = (variant & 1) != 0;
  const bool                       height_function = (variant & 2) != 0;
  const int                        passes = argc > 5 ? std::atoi(argv[5]) : 2;
  const bool                       no_shifting = (variant & 4) != 0;
  const double                     t_end = argc > 6 ? std::atof(argv[6]) : 2.5;
  if (!(R_h >= 2 && R_h <= 100) ||
      std::abs(4 * R_h - std::round(4 * R_h)) > 1e-9 ||
      !(flip >= 0 && flip <= 1) || !(c_frac > 0 && c_frac <= 1))
    {
      std::cerr << "usage: test_static_droplet [R/h in [2, 100], 4 R/h an "
                   "integer] [FLIP fraction in [0, 1]] [capillary step "
                   "fraction in (0, 1]] [variant: 1 smoothed, +2 height "
                   "function, +4 without point shifting] [smoothing "
                   "passes] [end time / sqrt(rho R^3/sigma)]\n";
      return 1;
    }
  const double L = 1, R = 0.25, h = R / R_h, rho = 1000, sigma = 1, mu = 0.5;
  const Point<dim> centre(0.5, 0.5);
  for (const bool smoothed : {false, true})
    try
      {
        if (study && smoothed != study_smoothed)
          continue;
        typename IncompressibleFlow<dim>::Parameters prm;
        prm.flip_fraction      = flip;
        prm.capillary_fraction = c_frac;
        prm.curvature          = (height_function) ?
                                   decltype(prm.curvature)::height_function :
                                   decltype(prm.curvature)::alpha_gradient;
        if (smoothed)
          {
            prm.point_shifting      = no_shifting ? 0 : 2;
            prm.curvature_smoothing = passes;
          }
        checks.print("point shifting A", prm.point_shifting);
        checks.print("curvature smoothing passes", prm.curvature_smoothing);
        if (height_function)
          checks.print("height-function curvature", 1);
        prm.viscosity       = mu;
        prm.gravity         = Tensor<1, dim>();
        prm.surface_tension = sigma;
        FlowScene<dim> scene(
          Point<dim>(L, L),
          h,
          rho,
          [&](const Point<dim> &x) { return x.distance(centre) < R; },
          prm,
          comm);
        const auto         limits  = scene.flow->stable_time_step();
        const double       dt      = limits.min();
        const double       t_sigma = std::sqrt(rho * R * R * R / sigma);
        const unsigned int n_steps =
          study ? static_cast<unsigned int>(std::ceil(t_end * t_sigma / dt)) :
                  400;
        for (unsigned int n = 0; n < n_steps; ++n)
          scene.flow->step(dt);
        const double p_in = scene.mean_pressure_within(centre, R / 2);
        const double umax = scene.max_over_points(
          [](const Point<dim> &, auto v) { return point_speed<dim>(v); });
        if (study && Utilities::MPI::this_mpi_process(comm) == 0)
          std::cerr << std::setprecision(8) << "unrounded: Laplace jump error "
                    << std::abs(p_in - sigma / R) / (sigma / R)
                    << ", mu u_max/sigma " << mu * umax / sigma << ", steps "
                    << n_steps << ", dt " << dt << std::endl;
        checks.print("capillary time step limit, s", limits.capillary);
        checks.print("steps", n_steps);
        checks.print("time / sqrt(rho R^3/sigma)",
                     std::round(n_steps * dt / t_sigma * 100) / 100);
        checks.print("inside pressure / (sigma/R)",
                     std::round(p_in / (sigma / R) * 1000) / 1000);
        checks.at_most("|Laplace jump error|",
                       std::abs(p_in - sigma / R) / (sigma / R),
                       0.05);
        checks.print("spurious-current capillary number mu u_max/sigma",
                     std::round(mu * umax / sigma * 1e4) / 1e4);
      }
    catch (const std::exception &e)
      {
        std::cerr << e.what() << std::endl;
        return 1;
      }
  return checks.exit_code();
}
