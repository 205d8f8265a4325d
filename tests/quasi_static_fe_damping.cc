// 'Solid/Adaptive mass scaling/Finite-element damping after solidification'
// (doc/solid.md, "Quasi-static cooling") on the short coupled track of
// tests/cooling_step.prm (as tests/quasi_static_cooling.cc: no hourglass
// control, 1 us temperature steps after solidification, the controller
// taking over at 141 us).
//   1. A common run to 140 us writes a checkpoint; the runs below resume
//      from copies of it and cool to 300 us with the controller.
//   2. Without damping and with beta = 0.01: the damping takes kinetic
//      energy out of the finite-element nodes (the transfer dissipation
//      grows by more than without it) and books it, so that the energy
//      balance of the damped run moves by at most 2 % of that energy
//      against the undamped run's (measured when the test was written:
//      0.4 %; unbooked it would move by all of it); the stresses on the
//      probe lines CD (points) and EF (elements) stay within 3 % of the
//      undamped run's peak. (This small zone keeps no vibration after the
//      switch, so the damping does not change its factor; the scene where
//      it does is doc/studies/2026-12-06-cooled-two-layer-kinetic-energy.md.)
//   3. The damped run resumed from its checkpoint at 250 us (after the
//      switch) ends with the same solid energy rows.
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
      const CoolingStepRuns runs{scene, comm};
      const Override        damp = {"Solid/Adaptive mass scaling",
                                    "Finite-element damping after solidification",
                                    "0.01"};
      runs.common();

      // A quasi-static run into @p dir, resumed from the newest checkpoint
      // of @p from, to 300 us, with the overrides @p extra.
      const auto resume_to_end = [&](const std::string    &from,
                                     const std::string    &dir,
                                     std::vector<Override> extra) {
        extra.insert(extra.begin(), runs.quasi);
        runs.resume_to_end(from, dir, "3e-4", extra);
      };
      resume_to_end("common", "plain", {});
      resume_to_end("common",
                    "damped",
                    {damp, {"Checkpoint", "Every simulated time", "2.5e-4"}});
      const auto e_plain  = read_csv_columns("plain/solid_energy.csv");
      const auto e_damped = read_csv_columns("damped/solid_energy.csv");
      // What the damping took out: the transfer dissipation beyond the
      // undamped run's; the balance must not move by more than 2 % of it
      // (it would move by all of it if the energy were not booked).
      const auto change = [](const auto &e, const std::string &col) {
        return e.at(col).back() - e.at(col).front();
      };
      const double taken = change(e_damped, "transfer_dissipation") -
                           change(e_plain, "transfer_dissipation");
      checks.in_range("kinetic energy taken out by the damping above 0 (1: "
                      "yes)",
                      taken > 0 ? 1 : 0,
                      1,
                      1);
      checks.at_most("balance damped - undamped over the energy taken out",
                     std::ceil(100 *
                                 std::abs(change(e_damped, "balance") -
                                          change(e_plain, "balance")) /
                                 taken -
                               1e-9) /
                       100,
                     0.02);
      for (const std::string col : {"sigma_xx", "von_mises"})
        checks.at_most(col + " damped against undamped, / peak",
                       resumed_end_difference("plain", "damped", col),
                       0.03);

      // 3. Resumed after the switch.
      resume_to_end("damped", "resumed", {damp});
      const auto   e_res  = read_csv_columns("resumed/solid_energy.csv");
      const double d_rows = energy_rows_difference(e_res,
                                                   e_damped,
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
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
