// 'Solid/Mass scaling after solidification = adaptive' (doc/solid.md,
// "Quasi-static cooling") on the short coupled track of
// tests/cooling_step.prm (melt flow and solid, s = 1000 at C = 0.5, the
// laser off after 20 us, the workpiece below the solidus near 135 us),
// cooled to 400 us with 1 us temperature steps after solidification.
//   1. A common run to 140 us writes a checkpoint after solidification;
//      both runs below resume from a copy of it, so that the melt flow
//      before it plays no part in their difference.
//   2. The reference keeps s = 1000 to the end; the quasi-static run must
//      switch to the adaptive controller at its first step, raise the
//      factor (at least 4x by the end) and take fewer solid steps (at
//      most half of the reference's over 140-400 us), and end with the
//      reference's stresses: the largest |sigma_xx| and von Mises
//      differences on the probe lines CD (material points) and EF (finite
//      elements) over the reference's peak there, gate 2 % each (measured
//      when the test was written: doc/studies/2026-12-05-quasi-static-
//      cooling.md).
//   3. The quasi-static run resumed from its checkpoint at 300 us (after
//      the switch, with a raised factor) must end with the same probe
//      lines and solid energy rows.
// Runs on 1 and 2 ranks with the same output.
#include "resume_tools.h"
#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

namespace
{
  /// Rounded up to one significant digit (the flow's pressure solver
  /// agrees across partitions to its tolerance only).
  double
  one_digit_up(const double x)
  {
    if (!(x > 0))
      return x;
    const double e = std::pow(10., std::floor(std::log10(x)));
    return std::ceil(x / e - 1e-9) * e;
  }

  /// Copy the output directory @p from to @p to and return its newest
  /// checkpoint (collective).
  std::string
  copy_newest(const std::string &from, const std::string &to, MPI_Comm comm)
  {
    std::ifstream index(from + "/checkpoint/index");
    std::string   newest;
    index >> newest;
    AssertThrow(!newest.empty(),
                ExcMessage("no checkpoint written in " + from));
    if (Utilities::MPI::this_mpi_process(comm) == 0)
      std::filesystem::copy(from, to, std::filesystem::copy_options::recursive);
    MPI_Barrier(comm);
    return to + "/checkpoint/" + newest;
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
      const std::string scene    = argv[1];
      const std::string mode     = "Mass scaling after solidification";
      const std::string t_common = "1.4e-4", t_end = "4e-4";
      const Override    cool_dt = {"Time stepping",
                                   "Time step after solidification",
                                   "1e-6"};
      // 1. The common state after solidification.
      run_scene<3>(scene,
                   comm,
                   {{"Output", "Directory", "common"},
                    {"Time stepping", "End time", t_common},
                    cool_dt,
                    {"Checkpoint", "Every simulated time", t_common}});
      const auto   e_common = read_csv_columns("common/solid_energy.csv");
      const double steps_0  = e_common.at("step").back();

      // 2. Fixed factor and quasi-static from there.
      const auto from_fixed = copy_newest("common", "fixed", comm);
      run_scene<3>(scene,
                   comm,
                   {{"Output", "Directory", "fixed"},
                    {"Time stepping", "End time", t_end},
                    cool_dt,
                    {"Checkpoint", "Resume from", from_fixed}});
      const auto from_quasi = copy_newest("common", "quasi", comm);
      run_scene<3>(scene,
                   comm,
                   {{"Output", "Directory", "quasi"},
                    {"Time stepping", "End time", t_end},
                    cool_dt,
                    {"Solid", mode, "adaptive"},
                    {"Checkpoint", "Every simulated time", "3e-4"},
                    {"Checkpoint", "Resume from", from_quasi}});
      const auto  e_fixed = read_csv_columns("fixed/solid_energy.csv");
      const auto  e_quasi = read_csv_columns("quasi/solid_energy.csv");
      const auto &s       = e_quasi.at("mass_scaling");
      checks.in_range("mass scaling at the checkpoint", s.front(), 1000, 1000);
      checks.in_range("mass scaling at the end / at the checkpoint",
                      std::min(s.back() / s.front(), 1e6) >= 4 ? 1. : 0.,
                      1,
                      1);
      const double n_fixed = e_fixed.at("step").back() - steps_0;
      const double n_quasi = e_quasi.at("step").back() - steps_0;
      checks.at_most("solid steps after the checkpoint, quasi-static / fixed",
                     n_quasi / n_fixed <= 0.5 ? 0.5 : n_quasi / n_fixed,
                     0.5);
      for (const std::string col : {"sigma_xx", "von_mises"})
        {
          const auto [d, peak] =
            probe_line_difference("fixed", "quasi", {"CD", "EF"}, col);
          checks.at_most(col + " quasi-static against fixed, / peak",
                         one_digit_up(d / peak),
                         0.02);
        }

      // 3. Resumed after the switch.
      const auto from_res = copy_newest("quasi", "resumed", comm);
      run_scene<3>(scene,
                   comm,
                   {{"Output", "Directory", "resumed"},
                    {"Time stepping", "End time", t_end},
                    cool_dt,
                    {"Solid", mode, "adaptive"},
                    {"Checkpoint", "Resume from", from_res}});
      const auto e_res = read_csv_columns("resumed/solid_energy.csv");
      double     d_rows =
        e_res.at("step").size() == e_quasi.at("step").size() ? 0. : 1.;
      for (const std::string col :
           {"time", "step", "mass_scaling", "internal_work", "kinetic"})
        for (std::size_t i = 0; d_rows == 0 && i < e_res.at(col).size(); ++i)
          d_rows = std::max(d_rows,
                            std::abs(e_res.at(col)[i] - e_quasi.at(col)[i]) /
                              std::max(1e-300, std::abs(e_quasi.at(col)[i])));
      checks.at_most("resumed against straight: solid energy rows (relative)",
                     d_rows,
                     1e-12);
      double d_lines = 0;
      for (const std::string col : {"T", "sigma_xx", "von_mises"})
        d_lines = std::max(
          d_lines,
          probe_line_difference("quasi", "resumed", {"CD", "EF"}, col).first);
      checks.at_most("resumed against straight: T and stresses on the lines",
                     d_lines,
                     1e-12);
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
