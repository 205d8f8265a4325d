// femp tests: the runs of tests/cooling_step.prm that the quasi-static
// cooling tests share (doc/solid.md, "Quasi-static cooling"): a common run
// to 140 us, past solidification, that writes a checkpoint, and runs
// resumed from a copy of a checkpoint to an end time, all with 1 us
// temperature steps after solidification and no hourglass control.
#ifndef femp_cooling_step_runs_h
#define femp_cooling_step_runs_h

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
  };
} // namespace femp_test

#endif
