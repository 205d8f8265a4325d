// femp: an error that every MPI rank meets at the same point of the run.
//
// Thrown only after a global reduction has told every rank that the run
// must stop (a non-finite field, a step above its stable limit, a broken
// maximum principle), with the same message on every rank. main() then
// prints it once and ends all ranks normally with exit status 1, without
// MPI_Abort (whose banner would bury the message). An error that only some
// ranks meet stays an ordinary exception and ends the run with MPI_Abort.
#ifndef femp_base_collective_error_h
#define femp_base_collective_error_h

#include <stdexcept>
#include <string>

namespace femp
{
  class CollectiveError : public std::runtime_error
  {
  public:
    explicit CollectiveError(const std::string &message)
        : std::runtime_error(message)
    {
    }
  };
} // namespace femp

#endif
