// femp tests: the runs of tests/cooling_step.prm that the quasi-static
// cooling tests share (doc/solid.md, "Quasi-static cooling"): a common run
// to 140 us, past solidification, that writes a checkpoint, and runs
// resumed from a copy of a checkpoint to an end time, all with 1 us
// temperature steps after solidification and no hourglass control.
#ifndef femp_cooling_step_runs_h
#define femp_cooling_step_runs_h

#include <cmath>
#include <string>
#include <vector>

#include "resume_tools.h"
#include "scene_driver.h"

namespace femp_test
{
  struct CoolingStepRuns
  {
    std::string    scene;
    MPI_Comm       comm;
    const Override dt    = {"Time stepping",
                            "Time step after solidification",
                            "1e-6"};
    const Override no_hg = {"Solid FEM", "Hourglass coefficient", "0"};
    /// The quasi-static switch after solidification.
    const Override quasi = {"Solid",
                            "Mass scaling after solidification",
                            "adaptive"};

    /// The common state after solidification, in the output directory
    /// "common" (a checkpoint at its end, 140 us).
    void
    common() const
    {
      run_scene<3>(scene,
                   comm,
                   {{"Output", "Directory", "common"},
                    {"Time stepping", "End time", "1.4e-4"},
                    dt,
                    no_hg,
                    {"Checkpoint", "Every simulated time", "1.4e-4"}});
    }

    /// A run into @p dir, resumed from the newest checkpoint of @p from,
    /// to the end time @p end (s), with the overrides @p extra.
    void
    resume_to_end(const std::string    &from,
                  const std::string    &dir,
                  const std::string    &end,
                  std::vector<Override> extra) const
    {
      const auto resume = copy_for_resume(from, dir, comm, true);
      extra.insert(extra.begin(),
                   {{"Output", "Directory", dir},
                    {"Time stepping", "End time", end},
                    dt,
                    no_hg,
                    {"Checkpoint", "Resume from", resume}});
      run_scene<3>(scene, comm, extra);
    }

    /// A quasi-static run (the switch after solidification) into @p dir,
    /// resumed from the newest checkpoint of @p from, to 300 us, with the
    /// overrides @p extra.
    void
    quasi_to_300us(const std::string    &from,
                   const std::string    &dir,
                   std::vector<Override> extra) const
    {
      extra.insert(extra.begin(), quasi);
      resume_to_end(from, dir, "3e-4", extra);
    }

    /// The runs and checks that an option of the quasi-static cooling
    /// that takes kinetic energy out of the finite-element nodes shares
    /// (doc/solid.md, "Quasi-static cooling"): from the common run, a
    /// quasi-static run without the option ("plain") and one with
    /// @p option (into @p dir, a checkpoint at 250 us) to 300 us; the
    /// energy that the option took out and booked with
    /// transfer_dissipation (its growth beyond the plain run's) must be
    /// above 0 and the energy balance may move by at most 2 % of it
    /// against the plain run's (unbooked it would move by all of it); the
    /// stresses on the probe lines CD and EF stay within 3 % of the plain
    /// run's peak; the run with the option resumed from its checkpoint at
    /// 250 us ends with the same solid energy rows (time, step, factor,
    /// stress work, kinetic energy, transfer dissipation). The check
    /// names say what the option does: @p taken_by ("the damping"),
    /// @p with and @p without ("damped", "undamped").
    template <typename Checks>
    void
    check_option(Checks            &checks,
                 const Override    &option,
                 const std::string &dir,
                 const std::string &taken_by,
                 const std::string &with,
                 const std::string &without) const
    {
      common();
      quasi_to_300us("common", "plain", {});
      quasi_to_300us("common",
                     dir,
                     {option,
                      {"Checkpoint", "Every simulated time", "2.5e-4"}});
      const auto e_plain  = read_csv_columns("plain/solid_energy.csv");
      const auto e_option = read_csv_columns(dir + "/solid_energy.csv");
      const auto change   = [](const auto &e, const std::string &col) {
        return e.at(col).back() - e.at(col).front();
      };
      const double out = change(e_option, "transfer_dissipation") -
                         change(e_plain, "transfer_dissipation");
      checks.in_range("kinetic energy taken out by " + taken_by +
                        " above 0 (1: yes)",
                      out > 0 ? 1 : 0,
                      1,
                      1);
      checks.at_most("balance " + with + " - " + without +
                       " over the energy taken out",
                     std::ceil(100 *
                                 std::abs(change(e_option, "balance") -
                                          change(e_plain, "balance")) /
                                 out -
                               1e-9) /
                       100,
                     0.02);
      for (const std::string col : {"sigma_xx", "von_mises"})
        checks.at_most(col + " " + with + " against " + without + ", / peak",
                       resumed_end_difference("plain", dir, col),
                       0.03);

      // Resumed after the switch.
      quasi_to_300us(dir, "resumed", {option});
      const auto   e_res  = read_csv_columns("resumed/solid_energy.csv");
      const double d_rows = energy_rows_difference(e_res,
                                                   e_option,
                                                   {"time",
                                                    "step",
                                                    "mass_scaling",
                                                    "internal_work",
                                                    "kinetic",
                                                    "transfer_dissipation"});
      checks.at_most("resumed against straight: solid energy rows (relative)",
                     d_rows,
                     1e-12);
    }
  };
} // namespace femp_test

#endif
