// Solid/Row interval: the energy and probe files of the solid written at a
// simulated-time interval instead of after every solid step. The scene
// (tests/checkpoint_solid.prm: 2D track over points and an FE zone) runs
// twice, with a row after every step and with Row interval = 1 us.
// Checked: every row of the second run is, character for character, the
// row of the first run at the same step (the accounts are summed at every
// step either way), it is the first step at or past a multiple of the
// interval, no multiple is skipped, and the summaries of both runs agree
// exactly. Same output on 1 and 2 ranks.
#include <cmath>
#include <map>

#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

namespace
{
  constexpr int dim = 2;

  /// Data rows of a CSV file (header dropped).
  std::vector<std::string>
  rows(const std::string &file)
  {
    std::ifstream in(file);
    AssertThrow(in, ExcMessage("cannot read " + file));
    std::vector<std::string> r;
    std::string              line;
    std::getline(in, line);
    while (std::getline(in, line))
      r.push_back(line);
    return r;
  }

  double
  first_value(const std::string &row)
  {
    return Utilities::string_to_double(row.substr(0, row.find(',')));
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
      const double                                              interval = 1e-6;
      std::map<std::string, typename FempProblem<dim>::Summary> sum;
      std::map<std::string, std::vector<std::string>>           energy, probes;
      for (const std::string run : {"every", "interval"})
        {
          sum[run] = run_scene<dim>(
            argv[1],
            comm,
            {{"Solid", "Row interval", run == "every" ? "0" : "1e-6"},
             {"Output", "Directory", "out_" + run}});
          MPI_Barrier(comm); // rank 0 wrote the CSV files
          energy[run] = rows("out_" + run + "/solid_energy.csv");
          probes[run] = rows("out_" + run + "/solid_probes.csv");
        }
      const auto &all = energy["every"], &few = energy["interval"];
      checks.print("solid steps", all.size(), 6);
      checks.print("rows with Row interval = 1 us", few.size(), 6);

      // Expected rows: the steps whose end crosses a multiple of the
      // interval, from the every-step file's times.
      std::vector<std::size_t> expected;
      double                   t_old = 0;
      for (std::size_t i = 0; i < all.size(); ++i)
        {
          const double t = first_value(all[i]);
          if (std::floor(t / interval * (1 + 1e-12)) >
              std::floor(t_old / interval * (1 + 1e-12)))
            expected.push_back(i);
          t_old = t;
        }
      const double t_end = first_value(all.back());
      checks.at_most("multiples of the interval without a row",
                     std::abs(double(expected.size()) -
                              std::floor(t_end / interval * (1 + 1e-12))),
                     0);
      checks.at_most("rows written - rows expected",
                     std::abs(double(few.size()) - double(expected.size())),
                     0);
      int differ = 0;
      for (std::size_t k = 0; k < std::min(few.size(), expected.size()); ++k)
        differ += few[k] != all[expected[k]] ||
                  probes["interval"][k] != probes["every"][expected[k]];
      checks.at_most("rows that differ from the every-step files", differ, 0);
      const auto &a = sum["every"].solid_energy,
                 &b = sum["interval"].solid_energy;
      checks.at_most("summaries differ (stress work, kinetic, balance)",
                     double(a.internal != b.internal ||
                            a.kinetic != b.kinetic ||
                            a.balance() != b.balance()),
                     0);
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
