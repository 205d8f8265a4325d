// Verification: the paper's case 3.1, Danilovskaya thermal shock
// (doc/verification.md; doc/method.md). A bar 5 m long with cells and
// point spacing h = 0.02 m, all constants 1 (rho = c = lambda = E = 1,
// alpha = 1, nu = 0, so beta = 1 and the wave speed is 1), stress-free at
// T_ref = 1 K; the face x = 0 is held at 1.001 K (T0 = 0.001 K) from t = 0,
// both ends traction-free, all other faces adiabatic and on rollers. The
// physics is 1D, so the bar is a 2D strip one cell high (plane strain with
// nu = 0 and rollers on y- and y+ is uniaxial strain with M = E). 2 s.
//
// Three discretizations of the solid: all material points (one per cell,
// at the cell centre), FEMP (finite elements on x < 0.6 m, points beyond),
// all finite elements. The probe is the cell that holds x = 1 m, whose
// point/Gauss point sits at its centre x_A = 1.01 m: the closed form is
// evaluated there (theta = erfc(a); S from the erfcx forms).
// Checks (doc/verification.md, "Danilovskaya thermal shock"):
//   T at the probe within 1 % of T0 (all t);
//   sigma_x within 5 % of beta T0 for |t - x_A/c| > 5 h/c;
//   front arrival (S crossing the middle of the jump) within 2 h/c;
//   jump S(x_A + 5h) - S(x_A - 5h) (times) within 0.15 of the exact one;
//   FEMP vs all-MPM at the probe away from the front within 0.05 beta T0;
//   interface continuity at t = 1 (cells at 0.59 m, FE, and 0.61 m, MPM):
//   FEMP within 0.05 beta T0 of all-MPM in both cells, and the FEMP stress
//   step across the interface within 0.05 beta T0 of the exact step;
//   energy balance of the solid (no external work: stress work + kinetic
//   energy change = 0).
// Also printed: the oscillation amplitude behind the front, max |S - exact|
// for t in [x_A + 5h, 2], in every run (for FEMP at A in its MPM part and at
// x_B = 0.51 m in its FE part), and the
// all-MPM run with the FLIP velocity transfer (not checked: it misses the
// 5 % target; APIC is the default, see doc/solid.md).
#include <femp/grid/material_points.h>
#include <femp/solid/solid_sub_cycle.h>

#include <fstream>

#include "test_tools.h"

using namespace femp_test;

namespace
{
  constexpr int dim = 2;
  // Cell size; the study mode (below) changes it.
  double h = 0.02;

  double
  theta_exact(const double x, const double t)
  {
    return std::erfc(x / (2 * std::sqrt(t)));
  }

  /// erfcx(z) = exp(z^2) erfc(z), stable for large z.
  double
  erfcx(const double z)
  {
    if (z < 25)
      return std::exp(z * z) * std::erfc(z);
    // asymptotic series for large z
    const double z2 = z * z;
    return 1 / (z * std::sqrt(numbers::PI)) *
           (1 - 1 / (2 * z2) + 3 / (4 * z2 * z2) - 15 / (8 * z2 * z2 * z2));
  }

  double
  S_exact(const double x, const double t)
  {
    const double a = x / (2 * std::sqrt(t)), b = std::sqrt(t),
                 G = std::exp(-a * a);
    if (t < x)
      return -0.5 * G * (erfcx(a - b) + erfcx(a + b));
    return 0.5 * G * (erfcx(b - a) - erfcx(a + b));
  }

  struct History
  {
    std::vector<double> t, S, theta; // at the probe
    std::vector<double> S_B;         // at x_B = 0.51 m (FE part of FEMP)
    double              S_left = 0, S_right = 0; // at 0.59 and 0.61 m, t = 1
    double              balance = 0, K_max = 0;
    std::vector<double> profile_S, profile_theta; // at the cell centres, t = 1
    std::array<double, 2> sizes;
  };

  /// fe_end: the FE zone is [0, fe_end] (0: none).
  History
  run(const double                          fe_end,
      MPI_Comm                              comm,
      const SolidMaterial::VelocityTransfer transfer =
        SolidMaterial::VelocityTransfer::apic,
      const unsigned int points_per_cell = 1,
      const double       bulk_viscosity  = 0.1)
  {
    const auto          gp = box<dim>(Point<dim>(0, 0), Point<dim>(5, h), h);
    BackgroundGrid<dim> grid(gp, comm);
    grid.create();
    Material   mat = unit_material();
    Laser<dim> laser(laser_off<dim>());

    typename MaterialPoints<dim>::Parameters pp;
    pp.point_spacing   = h / points_per_cell;
    pp.substrate_top   = h;
    pp.layer_thickness = 0;
    pp.subcells        = 1;
    MaterialPoints<dim> points(pp, mat, grid);
    points.create(1.);

    HeatTransfer<dim> heat(heat_parameters<dim>(1., {{"x-", 1.001}}),
                           mat,
                           laser,
                           grid);
    heat.initialize();
    heat.set_metal_fraction(points.metal_fraction());

    SolidMaterial sm(mat); // density 1, solidus 1e6
    sm.youngs_modulus    = PiecewiseLinear(1.);
    sm.plastic_modulus   = PiecewiseLinear(0.);
    sm.yield_stress      = PiecewiseLinear(1e30);
    sm.poisson_ratio     = 0;
    sm.expansion         = 1;
    sm.bulk_viscosity    = bulk_viscosity;
    sm.velocity_transfer = transfer;
    typename SolidSubCycle<dim>::Parameters sp;
    sp.safety_factor = 0.9;
    sp.roller_faces  = {"y-", "y+"};
    sp.energy_file   = "";
    typename SolidFEM<dim>::Parameters fp;
    fp.enabled      = fe_end > 0;
    fp.lower_corner = Point<dim>(0, 0);
    fp.upper_corner = Point<dim>(fe_end, h);
    SolidSubCycle<dim> solid(sp, fp, sm, grid, points);
    solid.initialize(heat.temperature(), "");

    const std::vector<Point<dim>> probes = {Point<dim>(1.0 + 1e-9, 0.5 * h),
                                            Point<dim>(0.59, 0.5 * h),
                                            Point<dim>(0.61, 0.5 * h),
                                            Point<dim>(0.5 + 1e-9, 0.5 * h)};
    History                       r;
    r.sizes                      = solid.sizes();
    const double       dt0       = 0.4 * heat.stable_time_step();
    const unsigned int n1        = std::ceil(1. / dt0);
    const double       dt        = 1. / n1;
    double             t         = 0;
    unsigned int       last_step = 0;
    for (unsigned int n = 0; n < 2 * n1; ++n)
      {
        heat.advance(dt, t);
        points.cells_to_points(heat.temperature());
        t                 = (n + 1) * dt;
        const bool at_one = (n + 1 == n1), at_end = (n + 1 == 2 * n1);
        solid.advance(t, heat.temperature(), at_one || at_end);
        if (solid.n_steps() != last_step)
          {
            last_step    = solid.n_steps();
            const auto p = solid.probe(probes);
            r.t.push_back(solid.time());
            r.S.push_back(p[0][0] / 1e-3);
            r.theta.push_back((p[0][1] - 1.) / 1e-3);
            r.S_B.push_back(p[3][0] / 1e-3);
            if (at_one)
              {
                r.S_left = p[1][0] / 1e-3, r.S_right = p[2][0] / 1e-3;
                std::vector<Point<dim>> centres;
                for (unsigned int i = 0; i < grid.n_cells()[0]; ++i)
                  centres.emplace_back((i + 0.5) * h, 0.5 * h);
                for (const auto &q : solid.probe(centres))
                  {
                    r.profile_S.push_back(q[0] / 1e-3);
                    r.profile_theta.push_back((q[1] - 1.) / 1e-3);
                  }
              }
            const auto e = solid.energies();
            r.K_max      = std::max(r.K_max, e.kinetic);
            r.balance    = std::max(r.balance, std::abs(e.balance()));
          }
      }
    return r;
  }
  /// Study mode, one discretization per call (contrib/study.py danilovskaya):
  ///   test_solid_danilovskaya --study METHOD H PPC TRANSFER BV
  /// METHOD mpm | femp | fe, H the cell size (m), PPC points per cell and
  /// direction, TRANSFER apic | flip, BV the bulk viscosity coefficient.
  /// Prints the errors at the probe cell (centre x_A) against the closed
  /// form, in units of beta T0: the largest away from the front
  /// (|t - x_A/c| > 5 h/c, the window of the test's gate, and > 0.2 s, a
  /// window that does not shrink with h), the mean and the RMS of |S -
  /// exact| over the history (time-weighted, front included), the front
  /// arrival error, and the energy balance over the largest kinetic energy.
  int
  study(char **argv, MPI_Comm comm)
  {
    const std::string method    = argv[2];
    h                           = std::stod(argv[3]);
    const unsigned int ppc      = std::stoi(argv[4]);
    const auto         transfer = std::string(argv[5]) == "flip" ?
                                    SolidMaterial::VelocityTransfer::flip :
                                    SolidMaterial::VelocityTransfer::apic;
    const double       bv       = std::stod(argv[6]);
    AssertThrow(method == "mpm" || method == "femp" || method == "fe",
                ExcMessage("METHOD must be mpm, femp or fe"));
    const double  fe_end = method == "mpm" ? 0 : method == "femp" ? 0.6 : 5;
    const History r      = run(fe_end, comm, transfer, ppc, bv);
    const double  xA     = (std::floor(1 / h + 1e-9) + 0.5) * h;
    double        err_S = 0, err_far = 0, sum1 = 0, sum2 = 0, t_front = -1;
    const double  mid = S_exact(xA, xA * (1 - 1e-12)) + 0.5;
    for (std::size_t i = 0; i < r.t.size(); ++i)
      {
        const double e    = std::abs(r.S[i] - S_exact(xA, r.t[i]));
        const double dt_i = r.t[i] - (i > 0 ? r.t[i - 1] : 0.);
        sum1 += e * dt_i;
        sum2 += e * e * dt_i;
        if (std::abs(r.t[i] - xA) > 5 * h)
          err_S = std::max(err_S, e);
        if (std::abs(r.t[i] - xA) > 0.2)
          err_far = std::max(err_far, e);
        if (t_front < 0 && i > 0 && r.t[i] > 0.5 && r.S[i - 1] < mid &&
            r.S[i] >= mid)
          t_front = r.t[i - 1] + (mid - r.S[i - 1]) / (r.S[i] - r.S[i - 1]) *
                                   (r.t[i] - r.t[i - 1]);
      }
    if (Utilities::MPI::this_mpi_process(comm) == 0)
      std::cout << "points " << r.sizes[0] << " elements " << r.sizes[1]
                << " steps " << r.t.size() << " max_error_away " << err_S
                << " max_error_far " << err_far << " mean_error "
                << sum1 / r.t.back() << " rms_error "
                << std::sqrt(sum2 / r.t.back()) << " front_error "
                << std::abs(t_front - xA) << " balance " << r.balance / r.K_max
                << std::endl;
    return 0;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  if (argc == 7 && std::string(argv[1]) == "--study")
    return study(argv, comm);
  Checks       checks(comm);
  const double xA = 1.01, c = 1;

  const History mpm = run(0, comm);

  const History flip = run(0, comm, SolidMaterial::VelocityTransfer::flip);
  const History femp = run(0.6, comm);
  const History fe   = run(5, comm);
  if (argc > 1 && Utilities::MPI::this_mpi_process(comm) == 0)
    {
      // History table for contrib/plot_danilovskaya.py: t, exact S, S of
      // all-MPM, FEMP, all-FE; exact theta, theta (all-MPM).
      std::ofstream f(argv[1]);
      f << "t,S_exact,S_mpm,S_femp,S_fe,theta_exact,theta_mpm,S_mpm_flip\n";
      for (std::size_t i = 0; i < mpm.t.size(); ++i)
        f << mpm.t[i] << "," << S_exact(xA, mpm.t[i]) << "," << mpm.S[i] << ","
          << femp.S[i] << "," << fe.S[i] << "," << theta_exact(xA, mpm.t[i])
          << "," << mpm.theta[i] << "," << flip.S[i] << "\n";
      if (argc > 2)
        {
          // Profiles at t = 1 for Fig. 6.
          std::ofstream g(argv[2]);
          g << "x,S_exact,S_mpm,S_femp,S_fe,theta_exact,theta_mpm,theta_femp,"
               "S_mpm_flip\n";
          for (std::size_t i = 0; i < mpm.profile_S.size(); ++i)
            {
              const double x = (i + 0.5) * h;
              g << x << "," << S_exact(x, 1) << "," << mpm.profile_S[i] << ","
                << femp.profile_S[i] << "," << fe.profile_S[i] << ","
                << theta_exact(x, 1) << "," << mpm.profile_theta[i] << ","
                << femp.profile_theta[i] << "," << flip.profile_S[i] << "\n";
            }
        }
    }
  for (const auto &[name, r] : {std::make_pair("all-MPM", &mpm),
                                std::make_pair("FEMP", &femp),
                                std::make_pair("all-FE", &fe)})
    {
      checks.print(std::string(name) + ": solid material points",
                   r->sizes[0],
                   6);
      checks.print(std::string(name) + ": finite elements", r->sizes[1], 6);
      checks.print(std::string(name) + ": solid steps", r->t.size(), 6);
    }

  const char    *names[3] = {"all-MPM", "FEMP", "all-FE"};
  const History *runs[3]  = {&mpm, &femp, &fe};
  double         behind[3];
  for (int k = 0; k < 3; ++k)
    {
      const History &r     = *runs[k];
      double         err_T = 0, err_S = 0, t_front = -1, beh = 0;
      for (std::size_t i = 0; i < r.t.size(); ++i)
        {
          err_T =
            std::max(err_T, std::abs(r.theta[i] - theta_exact(xA, r.t[i])));
          const double e = std::abs(r.S[i] - S_exact(xA, r.t[i]));
          if (std::abs(r.t[i] - xA / c) > 5 * h / c)
            err_S = std::max(err_S, e);
          if (r.t[i] > xA / c + 5 * h / c)
            beh = std::max(beh, e);
          // Front: first crossing of the middle of the exact jump.
          const double mid = S_exact(xA, xA * (1 - 1e-12)) + 0.5;
          if (t_front < 0 && i > 0 && r.t[i] > 0.5 && r.S[i - 1] < mid &&
              r.S[i] >= mid)
            t_front = r.t[i - 1] + (mid - r.S[i - 1]) / (r.S[i] - r.S[i - 1]) *
                                     (r.t[i] - r.t[i - 1]);
        }
      // Jump over +-5 h/c around the exact arrival, by linear interpolation.
      auto at = [&](const double time) {
        for (std::size_t i = 1; i < r.t.size(); ++i)
          if (r.t[i] >= time)
            return r.S[i - 1] + (time - r.t[i - 1]) / (r.t[i] - r.t[i - 1]) *
                                  (r.S[i] - r.S[i - 1]);
        return r.S.back();
      };
      const double      d     = 5 * h / c;
      const double      jump  = at(xA + d) - at(xA - d);
      const double      exact = S_exact(xA, xA + d) - S_exact(xA, xA - d);
      const std::string n     = names[k];
      checks.at_most(n + ": max |theta - exact| at the probe (T / T0)",
                     err_T,
                     0.01);
      checks.at_most(
        n + ": max |S - exact| away from the front (sigma / beta T0)",
        err_S,
        0.05);
      checks.at_most(n + ": |front arrival - x/c| (s)",
                     std::abs(t_front - xA / c),
                     2 * h / c);
      checks.at_most(n + ": |jump - exact jump| over +-5h/c (beta T0)",
                     std::abs(jump - exact),
                     0.15);
      checks.print(n + ": oscillation behind the front, max |S - exact|",
                   beh,
                   2);
      checks.at_most(n + ": energy balance / max kinetic energy",
                     r.balance / r.K_max,
                     0.05);
      behind[k] = beh;
    }
  (void) behind;
  {
    // All-MPM with the FLIP transfer, for comparison (printed only).
    double err_S = 0, beh = 0;
    for (std::size_t i = 0; i < flip.t.size(); ++i)
      {
        const double e = std::abs(flip.S[i] - S_exact(xA, flip.t[i]));
        if (std::abs(flip.t[i] - xA / c) > 5 * h / c)
          err_S = std::max(err_S, e);
        if (flip.t[i] > xA / c + 5 * h / c)
          beh = std::max(beh, e);
      }
    checks.print("all-MPM with FLIP: max |S - exact| away from the front",
                 err_S,
                 2);
    checks.print("all-MPM with FLIP: oscillation behind the front", beh, 2);
  }

  // Oscillation behind the front at x_B = 0.51 m, in the FE part of FEMP
  // (the probe A lies in its MPM part), and in the other runs (printed).
  {
    const double xB = 0.51;
    for (int k = 0; k < 3; ++k)
      {
        double beh = 0;
        for (std::size_t i = 0; i < runs[k]->t.size(); ++i)
          if (runs[k]->t[i] > xB / c + 5 * h / c)
            beh =
              std::max(beh,
                       std::abs(runs[k]->S_B[i] - S_exact(xB, runs[k]->t[i])));
        checks.print(std::string(names[k]) +
                       ": oscillation behind the front at "
                       "x = 0.51 m" +
                       (k == 1 ? " (FE part)" : ""),
                     beh,
                     2);
      }
  }

  // FEMP against all-MPM at the probe, away from the front.
  {
    double diff = 0;
    for (std::size_t i = 0; i < std::min(mpm.t.size(), femp.t.size()); ++i)
      if (std::abs(mpm.t[i] - xA / c) > 5 * h / c)
        diff = std::max(diff, std::abs(mpm.S[i] - femp.S[i]));
    checks.at_most("FEMP vs all-MPM: max |S difference| away from the front",
                   diff,
                   0.05);
  }

  // Interface continuity at t = 1: cells at 0.59 (FE in FEMP) and 0.61 m.
  {
    const double exact_step = S_exact(0.61, 1) - S_exact(0.59, 1);
    const double femp_step  = femp.S_right - femp.S_left;
    const double mpm_step   = mpm.S_right - mpm.S_left;
    const double mpm_err    = std::max(std::abs(mpm.S_left - S_exact(0.59, 1)),
                                    std::abs(mpm.S_right - S_exact(0.61, 1)));
    checks.print("t = 1: S exact at 0.59 m", S_exact(0.59, 1), 4);
    checks.print("t = 1: S exact at 0.61 m", S_exact(0.61, 1), 4);
    checks.print("t = 1: FEMP S at 0.59 m (FE)", femp.S_left, 3);
    checks.print("t = 1: FEMP S at 0.61 m (MPM)", femp.S_right, 3);
    checks.print("t = 1: all-MPM S at 0.59 m", mpm.S_left, 3);
    checks.print("t = 1: all-MPM S at 0.61 m", mpm.S_right, 3);
    checks.print("t = 1: all-MPM step across 0.6 m minus exact",
                 mpm_step - exact_step,
                 2);
    checks.print("t = 1: all-MPM max |S - exact| at 0.59, 0.61 m", mpm_err, 2);
    checks.at_most("t = 1: |FEMP - all-MPM| at 0.59 m (FE in FEMP)",
                   std::abs(femp.S_left - mpm.S_left),
                   0.05);
    checks.at_most("t = 1: |FEMP - all-MPM| at 0.61 m (MPM in FEMP)",
                   std::abs(femp.S_right - mpm.S_right),
                   0.05);
    checks.at_most("t = 1: |FEMP step across the interface - exact step|",
                   std::abs(femp_step - exact_step),
                   0.05);
  }
  return checks.exit_code();
}
