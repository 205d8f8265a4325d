// femp: feedback during a long run. On rank 0 a watchdog thread prints a
// line 'femp: still working: <phase> ...' whenever no progress line was
// printed for the interval (30 s of wall time), whatever the run is doing
// (setting up, a temperature step, melt-flow or solid sub-steps, writing
// output or a checkpoint). The run names its phase and reports its
// simulated time through the functions below; they only store values (no
// MPI, no output) and cost a few nanoseconds. No paper equations.
#ifndef femp_base_progress_watchdog_h
#define femp_base_progress_watchdog_h

#include <deal.II/base/mpi.h>

namespace femp
{
  namespace progress
  {
    /// Start the watchdog (rank 0 of @p comm; a no-op elsewhere), with a
    /// line after @p interval seconds of wall time without one.
    void
    start(MPI_Comm comm, double interval = 30.);

    /// Stop and join the watchdog thread (also done at exit).
    void
    stop();

    /// The phase the run is in now; @p name must be a string literal.
    void
    phase(const char *name);

    /// The simulated time (s) and step reached.
    void
    time(double t, unsigned int step);

    /// A sub-step of @p phase_name: its count and size (s), for the line.
    void
    substep(unsigned int n, double dt);

    /// A progress line was printed now: the next watchdog line comes one
    /// interval later.
    void
    reported();
  } // namespace progress
} // namespace femp

#endif
