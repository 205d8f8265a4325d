// femp: the bounds check of StateReader (see the header).
#include <deal.II/base/exceptions.h>

#include <femp/base/state_stream.h>

namespace femp
{
  using namespace dealii;

  void
  StateReader::check(const std::uint64_t n) const
  {
    AssertThrow(n <= std::uint64_t(end - p),
                ExcMessage("checkpoint: the section '" + what +
                           "' is shorter than its reader expects (a "
                           "checkpoint of another version of femp?)"));
  }
} // namespace femp
