// femp tests: helpers for the tests that resume a run from its checkpoint
// and compare the probe lines of two runs.
#ifndef femp_resume_tools_h
#define femp_resume_tools_h

#include <deal.II/base/exceptions.h>
#include <deal.II/base/mpi.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "scene_driver.h"

namespace femp_test
{
  /// Copy the output directory @p from, checkpoints included, to @p to
  /// (rank 0) and return the checkpoint to resume in the copy: the newest
  /// but one of its index (the one before the end's, if the end wrote one),
  /// or the only one; with @p newest the newest. Collective.
  inline std::string
  copy_for_resume(const std::string &from,
                  const std::string &to,
                  MPI_Comm           comm,
                  const bool         newest = false)
  {
    std::ifstream            index(from + "/checkpoint/index");
    std::vector<std::string> steps; // newest first
    for (std::string line; index >> line;)
      steps.push_back(line);
    AssertThrow(!steps.empty(),
                dealii::ExcMessage("no checkpoint written in " + from));
    if (dealii::Utilities::MPI::this_mpi_process(comm) == 0)
      std::filesystem::copy(from, to, std::filesystem::copy_options::recursive);
    MPI_Barrier(comm);
    return to + "/checkpoint/" +
           (steps.size() > 1 && !newest ? steps[1] : steps[0]);
  }
  /// Largest |a - b| of the columns @p cols of the CSV files @p a and @p b
  /// (read_csv_columns()), and the largest |a - offset| there (the
  /// reference's peak; T: its rise above @p offset). Throws if a column is
  /// missing, empty or of another length in @p b.
  inline std::pair<double, double>
  columns_difference(const std::string              &a,
                     const std::string              &b,
                     const std::vector<std::string> &cols,
                     const double                    offset = 0)
  {
    const auto x    = read_csv_columns(a);
    const auto y    = read_csv_columns(b);
    double     diff = 0, peak = 0;
    for (const auto &col : cols)
      {
        AssertThrow(x.count(col) && y.count(col) &&
                      x.at(col).size() == y.at(col).size() &&
                      !x.at(col).empty(),
                    dealii::ExcMessage(a + " and " + b + " differ in " + col));
        const auto &u = x.at(col), &v = y.at(col);
        for (std::size_t i = 0; i < u.size(); ++i)
          {
            diff = std::max(diff, std::abs(u[i] - v[i]));
            peak = std::max(peak, std::abs(u[i] - offset));
          }
      }
    return {diff, peak};
  }

  /// Largest |a - b| of column @p col over the probe lines @p lines (at
  /// output @p output, 1: the end of a run with 'Output interval = 0'; 2:
  /// the end of a run resumed from such a run's end) of the output
  /// directories @p a and @p b, and the largest |a - offset| there
  /// (columns_difference()).
  inline std::pair<double, double>
  probe_line_difference(const std::string              &a,
                        const std::string              &b,
                        const std::vector<std::string> &lines,
                        const std::string              &col,
                        const double                    offset = 0,
                        const unsigned int              output = 1)
  {
    double diff = 0, peak = 0;
    for (const auto &line : lines)
      {
        const std::string file =
          "/probe_line_" + line + "_0000" + std::to_string(output) + ".csv";
        const auto [d, p] =
          columns_difference(a + file, b + file, {col}, offset);
        diff = std::max(diff, d);
        peak = std::max(peak, p);
      }
    return {diff, peak};
  }

  /// probe_line_difference() over both probe lines (CD and EF), as a
  /// fraction of the reference's peak.
  inline double
  probe_line_relative_difference(const std::string &a,
                                 const std::string &b,
                                 const std::string &col,
                                 const double       offset = 0)
  {
    const auto [diff, peak] =
      probe_line_difference(a, b, {"CD", "EF"}, col, offset);
    return diff / peak;
  }

  /// probe_line_difference() of @p col over the lines CD and EF at the ends
  /// of two runs resumed from one checkpoint (output 2), as a fraction of
  /// the reference's (@p a) peak, rounded up to 0.01.
  inline double
  resumed_end_difference(const std::string &a,
                         const std::string &b,
                         const std::string &col)
  {
    const auto [diff, peak] =
      probe_line_difference(a, b, {"CD", "EF"}, col, 0, 2);
    return std::ceil(100 * diff / peak - 1e-9) / 100;
  }

  /// Largest relative difference between the columns @p cols of the
  /// energy files (read_csv_columns()) @p a (the resumed run) and @p b
  /// (the run straight through), row by row; 1 if their row counts differ.
  template <typename Columns>
  inline double
  energy_rows_difference(const Columns                  &a,
                         const Columns                  &b,
                         const std::vector<std::string> &cols)
  {
    double d = a.at("step").size() == b.at("step").size() ? 0. : 1.;
    for (const auto &col : cols)
      for (std::size_t i = 0; d == 0 && i < a.at(col).size(); ++i)
        d = std::max(d,
                     std::abs(a.at(col)[i] - b.at(col)[i]) /
                       std::max(1e-300, std::abs(b.at(col)[i])));
    return d;
  }

  /// Checks that two runs of the two-layer build of
  /// tests/checkpoint_handover.prm end alike: T and sigma_xx on its probe
  /// line AB (at output @p output, see probe_line_difference()) and
  /// sigma_xx at its four solid probes, each as a fraction of the peak of
  /// @p a, rounded up to 1e-12, at most @p tolerance. @p pair names the
  /// two runs in the checks' labels.
  template <typename Checks>
  inline void
  check_same_build_end(Checks            &checks,
                       const std::string &a,
                       const std::string &b,
                       const std::string &pair,
                       const unsigned int output,
                       const double       tolerance)
  {
    for (const auto &[col, offset] :
         std::vector<std::pair<std::string, double>>{{"T", 300.},
                                                     {"sigma_xx", 0.}})
      {
        const auto [diff, peak] =
          probe_line_difference(a, b, {"AB"}, col, offset, output);
        checks.at_most(col + " on AB: " + pair + ", / peak",
                       std::ceil(1e12 * diff / peak) / 1e12,
                       tolerance);
      }
    const auto [diff, peak] = columns_difference(
      a + "/solid_probes.csv",
      b + "/solid_probes.csv",
      {"sigma_xx_0", "sigma_xx_1", "sigma_xx_2", "sigma_xx_3"});
    checks.at_most("solid probes sigma_xx: " + pair + ", / peak",
                   std::ceil(1e12 * diff / peak) / 1e12,
                   tolerance);
  }

} // namespace femp_test

#endif
