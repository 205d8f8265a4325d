// femp: one run per output folder. A run takes the lock file
// '<Output/Directory>/femp.lock' (its process id, host and start time)
// before it clears or writes anything there, and removes it when it ends.
// A second run into a locked folder is refused with the holder's pid, host
// and start time; a lock whose process is gone (same host, no such pid: a
// run killed by a signal or by MPI_Abort) is taken over with a note. With
// MPI, rank 0 takes the lock and broadcasts the outcome. No paper
// equations.
#ifndef femp_io_output_lock_h
#define femp_io_output_lock_h

#include <deal.II/base/mpi.h>

#include <string>

namespace femp
{
  class OutputLock
  {
  public:
    /// Name of the lock file inside the output folder.
    static constexpr const char *file_name = "femp.lock";

    /// Collective. Rank 0 takes the lock of @p directory (which must
    /// exist); every rank returns the same outcome: an empty string when
    /// the lock is held by this run (a note about a stale lock taken over
    /// goes to @p note), else the message why not (another live run holds
    /// it, or the file cannot be written).
    static std::string
    acquire(const std::string &directory, MPI_Comm comm, std::string &note);

    /// Remove the locks this process holds (called at exit as well).
    static void
    release_all();
  };
} // namespace femp

#endif
