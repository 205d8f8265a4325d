// Thermal history for microstructure codes on a scene with an analytic
// cooling history (tests/thermal_history.prm): 1D conduction from T0 = 2
// with the face x = 0 held at Tb = 1 and all properties 1, so that
//   T = Tb + (T0 - Tb) erf(eta),  eta = x / (2 sqrt(t)).
// A cell at x crosses the liquidus T_l = 1.6 at t_l = (x / (2 eta_l))^2,
// erf(eta_l) = 0.6, and the solidus 1.5 at t_s = (x / (2 eta_s))^2,
// erf(eta_s) = 0.5; at t_l the cooling rate is
//   cr = -dT/dt = (T0 - Tb) (2 / sqrt(pi)) exp(-eta_l^2) eta_l / (2 t_l),
// the gradient G = (T0 - Tb) (2 / sqrt(pi)) exp(-eta_l^2) / (2 sqrt(t_l))
// and R = cr / G = x / (2 t_l), the speed of the isotherm. Every cell
// starts liquid (t_m = 0). Reads the per-rank files the run writes and
// compares the cells with x in [0.2, 0.6] (t_s where t_s < 0.3 s, the end).
#include <fstream>

#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

namespace
{
  double
  inverse_erf(const double y)
  {
    double lo = 0, hi = 5;
    for (int i = 0; i < 200; ++i)
      (std::erf(0.5 * (lo + hi)) < y ? lo : hi) = 0.5 * (lo + hi);
    return 0.5 * (lo + hi);
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  run_scene<2>(argv[1], comm);
  MPI_Barrier(comm);
  if (Utilities::MPI::this_mpi_process(comm) != 0)
    return 0;

  const double dT = 1, eta_l = inverse_erf(0.6), eta_s = inverse_erf(0.5);
  const double t_end = 0.3;
  double       e_tm = 0, e_tl = 0, e_ts = 0, e_cr = 0, e_G = 0, e_R = 0;
  unsigned int n = 0, n_ts = 0, n_exaca = 0, bad_headers = 0;
  for (unsigned int r = 0; r < Utilities::MPI::n_mpi_processes(comm); ++r)
    {
      std::ifstream full("output/thermal_history_full_" + std::to_string(r) +
                         ".csv");
      std::ifstream exaca("output/thermal_history_" + std::to_string(r) +
                          ".csv");
      std::string   line;
      std::getline(exaca, line);
      bad_headers += line != "x,y,z,tm,tl,cr";
      while (std::getline(exaca, line))
        ++n_exaca;
      std::getline(full, line);
      while (std::getline(full, line))
        {
          std::replace(line.begin(), line.end(), ',', ' ');
          std::istringstream s(line);
          double             x, y, z, tm, tl, ts, cr, G, R;
          s >> x >> y >> z >> tm >> tl >> ts >> cr >> G >> R;
          if (x < 0.2 || x > 0.6)
            continue;
          ++n;
          const double t_l = std::pow(x / (2 * eta_l), 2);
          const double t_s = std::pow(x / (2 * eta_s), 2);
          const double f = dT * 2 / std::sqrt(M_PI) * std::exp(-eta_l * eta_l);
          e_tm           = std::max(e_tm, std::abs(tm));
          e_tl           = std::max(e_tl, std::abs(tl - t_l) / t_l);
          const double cr_exact = f * eta_l / (2 * t_l);
          e_cr = std::max(e_cr, std::abs(cr - cr_exact) / cr_exact);
          e_G  = std::max(e_G,
                         std::abs(G - f / (2 * std::sqrt(t_l))) /
                           (f / (2 * std::sqrt(t_l))));
          e_R  = std::max(e_R, std::abs(R - x / (2 * t_l)) / (x / (2 * t_l)));
          if (t_s < 0.98 * t_end)
            {
              ++n_ts;
              e_ts = std::max(e_ts, ts < 0 ? 1. : std::abs(ts - t_s) / t_s);
            }
        }
    }
  checks.at_most("ExaCA files without the header x,y,z,tm,tl,cr",
                 bad_headers,
                 0);
  checks.print("events with x in [0.2, 0.6]", n);
  checks.print("of these, solidus reached before the end", n_ts);
  checks.print("rows of the ExaCA files", n_exaca);
  checks.at_most("max |t_m| (s)", e_tm, 0);
  checks.at_most("max relative error of t_l", e_tl, 0.01);
  checks.at_most("max relative error of t_s", e_ts, 0.01);
  checks.at_most("max relative error of the cooling rate", e_cr, 0.01);
  checks.at_most("max relative error of G", e_G, 0.01);
  checks.at_most("max relative error of R", e_R, 0.01);
  return checks.exit_code();
}
