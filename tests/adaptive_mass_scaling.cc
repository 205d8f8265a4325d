// Adaptive mass scaling of the solid (Solid/Mass scaling = adaptive,
// doc/speed_accuracy.md section 3) on the reduced coupled single track
// (tests/adaptive_mass_scaling.prm: laser switch-on, melt flow, FE zone
// below the points, first microsecond). Two runs: the fixed factor s = 1
// (reference) and the adaptive controller starting at s = 1 with the
// default target K / U_el <= r_max = 1e-3 and range [1, 1e4]. Checked:
//   (a) the controller: from the energy file's mass_scaling and
//       kinetic_to_elastic columns, the factor rises in the quasi-static
//       start (largest factor >= 8), falls at least once, every rise
//       follows a measured ratio below r_max and every fall one above it,
//       and the factor stays in [1, 1e4];
//   (b) the energy balance: |balance| / |stress work| within the 5 % of the
//       coupling tests for both runs (measured 0.0012 with s = 1, 0.0042
//       adaptive; the fixed factors 10 and 100 give 0.0021 and 0.0035), and
//       the booked kinetic-energy jump of the factor changes printed (rises
//       at small K and falls at larger K nearly cancel here: -0.06 % of
//       the stress work);
//   (c) sigma_xx at the 12 solid probe points at 1 us: relative RMS
//       difference to the s = 1 run (measured 0.099 when the test was
//       written; gate 0.15), and the solid step counts (cost) of both runs.
// Same output on 1 and 2 ranks (the ratio is a global sum, the factor is
// rounded to powers of 2^(1/4)).
#include <map>

#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

namespace
{
  constexpr int dim = 3;

  /// sigma_xx of every probe at the last row of a solid probe file.
  std::vector<double>
  last_sigma_xx(const std::map<std::string, std::vector<double>> &probes)
  {
    std::vector<double> s;
    for (unsigned int i = 0; probes.count("sigma_xx_" + std::to_string(i)); ++i)
      s.push_back(probes.at("sigma_xx_" + std::to_string(i)).back());
    return s;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  try
    {
      const double r_max = 1e-3; // the default of the parameter
      std::map<std::string, typename FempProblem<dim>::Summary>         sum;
      std::map<std::string, std::map<std::string, std::vector<double>>> energy,
        probes;
      for (const std::string run : {"fixed", "adaptive"})
        {
          sum[run] = run_scene<dim>(argv[1],
                                    comm,
                                    {{"Solid", "Mass scaling", run},
                                     {"Output", "Directory", "out_" + run}});
          MPI_Barrier(comm); // rank 0 wrote the CSV files
          energy[run] = read_csv_columns("out_" + run + "/solid_energy.csv");
          probes[run] = read_csv_columns("out_" + run + "/solid_probes.csv");
        }

      // (a) The controller's decisions.
      const auto &s     = energy["adaptive"].at("mass_scaling");
      const auto &r     = energy["adaptive"].at("kinetic_to_elastic");
      double      s_max = 0, s_min = 1e300;
      int         rises = 0, falls = 0, wrong = 0;
      for (std::size_t i = 0; i < s.size(); ++i)
        {
          s_max = std::max(s_max, s[i]);
          s_min = std::min(s_min, s[i]);
          if (i == 0 || s[i] == s[i - 1])
            continue;
          // The row after a change holds the ratio that caused it.
          if (s[i] > s[i - 1])
            ++rises, wrong += !(r[i] < r_max);
          else
            ++falls, wrong += !(r[i] > r_max);
        }
      checks.print("adaptive: largest factor", s_max, 3);
      checks.in_range("adaptive: largest factor (raised while quasi-static)",
                      s_max,
                      8,
                      1e4);
      checks.in_range("adaptive: smallest factor", s_min, 1, 1e4);
      checks.print("adaptive: rises of the factor", rises, 3);
      checks.in_range("adaptive: falls of the factor (ratio above r_max)",
                      falls,
                      1,
                      1000);
      checks.at_most("adaptive: changes against the measured ratio", wrong, 0);
      checks.print("adaptive: factor at the end", s.back(), 3);

      // (b) Energy balance.
      for (const std::string run : {"fixed", "adaptive"})
        {
          const auto &E = sum[run].solid_energy;
          checks.at_most(run + ": |solid energy balance| / |stress work|",
                         std::abs(E.balance()) / std::abs(E.internal),
                         0.05);
        }
      {
        const auto &E = sum["adaptive"].solid_energy;
        checks.print("adaptive: booked kinetic-energy jump / |stress work|",
                     std::round(E.scaling_jump / std::abs(E.internal) * 1e4) /
                       1e4,
                     1);
      }

      // (c) Stress accuracy and cost.
      const auto ref = last_sigma_xx(probes["fixed"]);
      const auto ada = last_sigma_xx(probes["adaptive"]);
      AssertThrow(ref.size() == 12 && ada.size() == ref.size(),
                  ExcMessage("probe files of the two runs differ"));
      double num = 0, den = 0;
      for (std::size_t i = 0; i < ref.size(); ++i)
        num += (ada[i] - ref[i]) * (ada[i] - ref[i]), den += ref[i] * ref[i];
      checks.at_most("relative RMS sigma_xx difference, adaptive vs s = 1",
                     std::round(std::sqrt(num / den) * 100) / 100,
                     0.15);
      const double n_ref = energy["fixed"].at("step").back(),
                   n_ada = energy["adaptive"].at("step").back();
      checks.print("solid steps, s = 1", n_ref, 5);
      checks.print("solid steps, adaptive", n_ada, 5);
      checks.at_most("solid steps adaptive / s = 1", n_ada / n_ref, 0.6);
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
