// 'Solid/Mass scaling after solidification = adaptive' (doc/solid.md,
// "Quasi-static cooling") on the short coupled track of
// tests/cooling_step.prm (melt flow and solid, s = 1000 at C = 0.5, the
// laser off after 20 us, the workpiece below the solidus near 135 us),
// without hourglass control (with the scene's 0.1 the fixed factor's own
// stresses drift with the number of solid steps, see the study below),
// cooled to 400 us with 1 us temperature steps after solidification.
//   1. A common run to 140 us writes a checkpoint after solidification;
//      both runs below resume from a copy of it, so that the melt flow
//      before it plays no part in their difference.
//   2. The reference keeps s = 1000 to the end; the quasi-static run must
//      switch to the adaptive controller at its first step (141 us), raise
//      the factor (more than 4x by the end), take fewer solid steps (less
//      than half of the reference's over 140-400 us), and end with the
//      reference's stresses: the largest |sigma_xx| and von Mises
//      differences on the probe lines CD (material points) and EF (finite
//      elements) over the reference's peak there, rounded up to 0.01, gate
//      3 % each (measured when the test was written: 0.3 % and 0.5 %,
//      with 12x fewer solid steps; doc/studies/2026-12-05-quasi-static-
//      cooling.md).
//   3. The quasi-static run resumed from its checkpoint at 300 us (after
//      the switch, with a raised factor) must end with the same probe
//      lines and solid energy rows.
// Runs on 1 and 2 ranks with the same output.
#include "cooling_step_runs.h"
#include "test_tools.h"

using namespace femp_test;

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  try
    {
      const std::string     scene = argv[1];
      const std::string     end   = "4e-4";
      const CoolingStepRuns runs{scene, comm};
      const Override        quasi = runs.quasi;
      // 1. The common state after solidification.
      runs.common();
      const double steps_0 =
        read_csv_columns("common/solid_energy.csv").at("step").back();

      const auto resume_to_end = [&](const std::string           &from,
                                     const std::string           &dir,
                                     const std::vector<Override> &extra) {
        runs.resume_to_end(from, dir, end, extra);
      };

      // 2. Fixed factor and quasi-static from there.
      resume_to_end("common", "fixed", {});
      resume_to_end("common",
                    "quasi",
                    {quasi, {"Checkpoint", "Every simulated time", "3e-4"}});
      // The switch, from the log of the quasi-static run (rank 0's).
      double t_switch = 0;
      {
        std::ifstream     log("scene.log");
        const std::string key = "Solid: the melt has solidified after the "
                                "laser's path (t = ";
        for (std::string line; std::getline(log, line);)
          if (line.rfind(key, 0) == 0 &&
              line.find("mass scaling adaptive from 1000") != std::string::npos)
            t_switch = std::stod(line.substr(key.size()));
      }
      t_switch = Utilities::MPI::max(t_switch, comm);
      checks.in_range("switch to the controller (us)",
                      std::round(t_switch * 1e6),
                      141,
                      141);
      const auto   e_fixed = read_csv_columns("fixed/solid_energy.csv");
      const auto   e_quasi = read_csv_columns("quasi/solid_energy.csv");
      const auto  &s       = e_quasi.at("mass_scaling");
      const double n_fixed = e_fixed.at("step").back() - steps_0;
      const double n_quasi = e_quasi.at("step").back() - steps_0;
      checks.in_range("factor at the end / at the switch above 4 (1: yes)",
                      s.back() / s.front() > 4 ? 1 : 0,
                      1,
                      1);
      checks.in_range("solid steps after the checkpoint, quasi-static / "
                      "fixed below 0.5 (1: yes)",
                      n_quasi / n_fixed < 0.5 ? 1 : 0,
                      1,
                      1);
      for (const std::string col : {"sigma_xx", "von_mises"})
        checks.at_most(col + " quasi-static against fixed, / peak",
                       resumed_end_difference("fixed", "quasi", col),
                       0.03);

      // 3. Resumed after the switch.
      resume_to_end("quasi", "resumed", {quasi});
      const auto   e_res  = read_csv_columns("resumed/solid_energy.csv");
      const double d_rows = energy_rows_difference(
        e_res,
        e_quasi,
        {"time", "step", "mass_scaling", "internal_work", "kinetic"});
      checks.at_most("resumed against straight: solid energy rows (relative)",
                     d_rows,
                     1e-12);
      double d_lines = 0;
      for (const std::string col : {"T", "sigma_xx", "von_mises"})
        d_lines = std::max(
          d_lines,
          probe_line_difference("quasi", "resumed", {"CD", "EF"}, col, 0, 2)
            .first);
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
