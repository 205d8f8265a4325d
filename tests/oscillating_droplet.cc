// Melt flow, oscillating droplet (doc/verification.md, Rayleigh/Lamb):
// a 2D drop r = R (1 + eps cos 2 theta), no gravity, surface tension sigma,
// small viscosity. Mode n = 2 of a 2D drop oscillates with
//   omega^2 = (n^3 - n) sigma / (rho R^3) = 6 sigma / (rho R^3)
// (weakly damped: the reference is omega_d = sqrt(omega^2 - gamma^2),
// gamma = 4 nu/R^2 the 2D mode-2 viscous decay rate; gamma/omega = 0.05,
// so the shift is 0.14 %). The shape measure
//   S = sum (x^2 - y^2) / sum (x^2 + y^2)
// over the points (about centre of mass), S = 2 eps cos(omega t) for small
// eps, is recorded every step; its upward and downward zero crossings
// (linear interpolation) give the period T = t_3 - t_1 (first and third
// crossing) and 2 (t_2 - t_1). The test fails when the period error
// exceeds 5 %. The automatic step uses the capillary step
// fraction given per case; the flow runs with point shifting (A = 2) and
// two passes of curvature smoothing (doc/studies/flow.md: without them the
// period was not robust to the step). 1 and 2 ranks give the same output.
//
// Runs R = 20 h at step fractions 1/2 and 1/4 (gated) and R = 10 h at 1/2
// (printed, not gated: +7 %, the smoothing bias at this resolution).
// Arguments (optional, for the study in doc/studies/flow.md; one gated run):
// capillary step fraction, R/h (default 20), series file (CSV for
// contrib/flow_plots.py: t/T, S/S0 and void diagnostics per step: enclosed
// empty cells, free faces, free faces of enclosed cells, interior cells with
// one point, cells with points, most points in a cell; "" for none),
// viscosity mu (default 0.5 Pa s: Ohnesorge number mu/sqrt(rho sigma R) =
// 0.03), the amplitude eps (default 0.1; 0 gives a static drop whose point
// speeds are the spurious currents), the FLIP fraction (-1: the solver's),
// the point shifting A (-1: 2), the curvature smoothing passes (-1: 2) and
// the volume correction c (Melt flow/Volume correction; -1: the solver's
// default 0 -- doc/studies/flow.md, "Volume correction": with c = 0.5 the
// period error grows to 10-21 %, so the droplet runs without it), and 1 for the
// height-function curvature (Melt flow/Curvature; default: alpha gradient).
#include <fstream>

#include "flow_tools.h"

using namespace femp_test;

/// Melt flow/Curvature = height function (tenth argument 1; the test: off).
static bool height_function = false;

/// One droplet run; returns false when it threw.
bool
run(const double       fraction,
    const double       R_over_h,
    const bool         gated,
    const double       mu,
    const double       eps,
    const double       flip,
    const double       shifting,
    const int          smoothing,
    const double       volume,
    const std::string &series_file,
    Checks            &checks,
    MPI_Comm           comm)
{
  constexpr int                                dim = 2;
  typename IncompressibleFlow<dim>::Parameters prm;
  const double R = Droplet::R, h = R / R_over_h, L = 4 * R;
  try
    {
      prm.viscosity          = mu;
      prm.capillary_fraction = fraction;
      if (flip >= 0)
        prm.flip_fraction = flip;
      // Point shifting A = 2 and two passes of curvature smoothing (see
      // doc/flow.md; the solver's defaults are off) unless given.
      prm.point_shifting      = shifting >= 0 ? shifting : 2.;
      prm.curvature_smoothing = smoothing >= 0 ? smoothing : 2;
      if (volume >= 0)
        prm.volume_correction = volume;
      prm.curvature = (height_function) ?
                        decltype(prm.curvature)::height_function :
                        decltype(prm.curvature)::alpha_gradient;
      const Droplet   drop(R_over_h, eps, prm, comm);
      FlowScene<dim> &scene   = *drop.scene;
      const double    omega   = drop.omega;
      const double    gamma   = drop.gamma;
      const double    T_exact = drop.period();

      const auto shape = [&]() { return shape_measure(scene, comm); };

      // Void diagnostics (collective): points per cell over the whole
      // grid; a hole is an empty cell not connected through empty cells to
      // the domain boundary (enclosed by the liquid), a free face a face
      // between a cell with points and an empty one. Returns {holes, free
      // faces, free faces of holes, interior cells with a single point, cells
      // with points, most points in a cell}.
      const unsigned int N     = static_cast<unsigned int>(std::lround(L / h));
      const auto         voids = [&]() {
        std::vector<double> count(N * N, 0.);
        for (const auto &p : scene.points->particle_handler())
          {
            const auto x = p.get_location();
            const int  i = std::min<int>(N - 1, std::max(0, int(x[0] / h)));
            const int  j = std::min<int>(N - 1, std::max(0, int(x[1] / h)));
            count[j * N + i] += 1;
          }
        Utilities::MPI::sum(count, comm, count);
        std::vector<int> outside(N * N, 0), stack;
        for (unsigned int i = 0; i < N; ++i)
          for (const unsigned int c :
               {i, (N - 1) * N + i, i * N, i * N + N - 1})
            if (count[c] == 0 && !outside[c])
              outside[c] = 1, stack.push_back(c);
        while (!stack.empty())
          {
            const int c = stack.back();
            stack.pop_back();
            const int i = c % N, j = c / N;
            const int nb[4][2] = {{i - 1, j},
                                  {i + 1, j},
                                  {i, j - 1},
                                  {i, j + 1}};
            for (const auto &q : nb)
              if (q[0] >= 0 && q[0] < int(N) && q[1] >= 0 && q[1] < int(N))
                {
                  const int e = q[1] * N + q[0];
                  if (count[e] == 0 && !outside[e])
                    outside[e] = 1, stack.push_back(e);
                }
          }
        std::array<double, 6> r = {{0, 0, 0, 0, 0, 0}};
        for (unsigned int j = 1; j + 1 < N; ++j)
          for (unsigned int i = 1; i + 1 < N; ++i)
            {
              const unsigned int c     = j * N + i;
              const unsigned int nb[4] = {c - 1, c + 1, c - N, c + N};
              r[4] += count[c] > 0;
              r[5] = std::max(r[5], count[c]);
              if (count[c] == 0)
                {
                  r[0] += !outside[c];
                  for (const auto e : nb)
                    if (count[e] > 0)
                      r[1] += 1, r[2] += !outside[c];
                }
              else if (count[c] == 1)
                {
                  bool interior = true;
                  for (const auto e : nb)
                    interior = interior && count[e] > 0;
                  r[3] += interior;
                }
            }
        return r;
      };

      std::vector<double>                crossings;
      std::vector<std::array<double, 8>> series;
      double                             t = 0, S = shape(), S0 = S, S_min = S;
      unsigned int                       n_steps = 0;
      const auto                         first = scene.flow->stable_time_step();
      const auto                         v0    = voids();
      series.push_back({{0., S, v0[0], v0[1], v0[2], v0[3], v0[4], v0[5]}});
      while ((eps == 0 || crossings.size() < 3) && t < 2 * T_exact)
        {
          const double dt = scene.flow->stable_time_step().min();
          scene.flow->step(dt);
          t += dt;
          ++n_steps;
          const double S_new = shape();
          if ((S > 0) != (S_new > 0))
            crossings.push_back(t - dt * S_new / (S_new - S));
          S     = S_new;
          S_min = std::min(S_min, S);
          const auto v =
            series_file.empty() ? std::array<double, 6>() : voids();
          series.push_back({{t, S, v[0], v[1], v[2], v[3], v[4], v[5]}});
        }
      if (!series_file.empty() && Utilities::MPI::this_mpi_process(comm) == 0)
        {
          std::ofstream f(series_file);
          f << "# oscillating droplet R/h = " << R_over_h
            << ", capillary step fraction " << fraction << ", point shifting "
            << prm.point_shifting << ", curvature smoothing "
            << prm.curvature_smoothing << ", volume correction "
            << prm.volume_correction << ", analytic period " << T_exact
            << " s, gamma T = " << gamma * T_exact << "\n"
            << "t/T_exact,S/S0,holes,free faces,hole faces,single-point "
               "interior cells,cells with points,most points in a cell\n";
          for (const auto &r : series)
            f << r[0] / T_exact << "," << r[1] / S0 << "," << r[2] << ","
              << r[3] << "," << r[4] << "," << r[5] << "," << r[6] << ","
              << r[7] << "\n";
        }
      const double umax = scene.max_over_points(
        [](const Point<dim> &, auto v) { return point_speed<dim>(v); });

      checks.print("capillary step fraction", fraction);
      checks.print("capillary limit / T_exact",
                   std::round(first.capillary / T_exact * 1e5) / 1e5);
      checks.print("viscous decay rate / omega",
                   std::round(gamma / omega * 1e4) / 1e4);
      checks.print("initial shape measure S0 (2 eps = 0.2)",
                   std::round(S0 * 1000) / 1000);
      checks.print("steps", n_steps, 8);
      checks.print("zero crossings found", crossings.size());
      checks.print("first minimum S/S0", std::round(S_min / S0 * 100) / 100);
      double err = 1;
      if (crossings.size() == 3)
        {
          const double T1 = crossings[2] - crossings[0];
          const double T2 = 2 * (crossings[1] - crossings[0]);
          checks.print("first crossing t/T_exact (0.25)",
                       std::round(crossings[0] / T_exact * 1000) / 1000);
          checks.print("period 2 (t2 - t1) / T_exact",
                       std::round(T2 / T_exact * 1000) / 1000);
          checks.print("period (t3 - t1) / T_exact",
                       std::round(T1 / T_exact * 1000) / 1000);
          err = std::abs(T1 / T_exact - 1);
        }
      if (gated)
        checks.at_most("|period error|", std::round(err * 1000) / 1000, 0.05);
      else
        checks.print("|period error| (target 0.05; not met at R = 10 h: not "
                     "gated, see doc/flow.md)",
                     std::round(err * 1000) / 1000);
      checks.print(
        "max point speed / (omega eps R)",
        std::round(umax / (omega * std::max(eps, 1e-300) * R) * 100) / 100);
      if (eps == 0)
        checks.print("static drop: spurious capillary number mu u_max / sigma",
                     mu * umax / Droplet::sigma);
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return false;
    }
  return true;
}

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  // Default: R = 20 h at step fractions 1/2 and 1/4 (gated at 5 %), and
  // R = 10 h at 1/2 (printed: the curvature smoothing makes the period
  // 5-8 % long there, doc/flow.md). With arguments: one gated run.
  struct Case
  {
    double fraction, R_over_h;
    bool   gated;
  };
  std::vector<Case> cases = {{0.5, 10, false},
                             {0.5, 20, true},
                             {0.25, 20, true}};
  if (argc > 1)
    {
      cases = {{std::atof(argv[1]), 20, true}};
      if (argc > 2)
        cases[0].R_over_h = std::atof(argv[2]);
    }
  const std::string series = argc > 3 ? argv[3] : "";
  const double      mu     = argc > 4 ? std::atof(argv[4]) : 0.5;
  const double      eps    = argc > 5 ? std::atof(argv[5]) : 0.1;
  const double      flip   = argc > 6 ? std::atof(argv[6]) : -1;
  const double      shift  = argc > 7 ? std::atof(argv[7]) : -1;
  const int         smooth = argc > 8 ? std::atoi(argv[8]) : -1;
  const double      volume = argc > 9 ? std::atof(argv[9]) : -1;
  height_function          = argc > 10 && std::atoi(argv[10]) == 1;
  for (const auto &c : cases)
    {
      checks.print("R / h", c.R_over_h);
      if (!run(c.fraction,
               c.R_over_h,
               c.gated,
               mu,
               eps,
               flip,
               shift,
               smooth,
               volume,
               series,
               checks,
               comm))
        return 1;
    }
  return checks.exit_code();
}
