// femp: the place named by a run-time error that every rank meets.
//
// A collective check (doc/stability.md) finds that the run must stop after a
// global reduction; the position it names in its message was found on one
// rank only. share_location() lets the lowest rank that found one tell the
// others, so that every rank throws the same CollectiveError.
#ifndef femp_base_error_location_h
#define femp_base_error_location_h

#include <deal.II/base/exceptions.h>
#include <deal.II/base/mpi.h>
#include <deal.II/base/point.h>

#include <femp/base/input_checks.h>

#include <string>

namespace femp
{
  /// The lowest rank with @p found sends its @p where to all ranks of
  /// @p comm (unchanged where no rank found one). Collective.
  template <int dim>
  void
  share_location(const bool found, dealii::Point<dim> &where, MPI_Comm comm)
  {
    const unsigned int me   = dealii::Utilities::MPI::this_mpi_process(comm);
    const unsigned int none = 1u << 30;
    const unsigned int root =
      dealii::Utilities::MPI::min(found ? me : none, comm);
    if (root < none)
      {
        const int ierr = MPI_Bcast(&where[0], dim, MPI_DOUBLE, root, comm);
        AssertThrowMPI(ierr);
      }
  }

  /// A position for a message: "(x, y[, z])".
  template <int dim>
  std::string
  location_text(const dealii::Point<dim> &p)
  {
    std::string s = "(";
    for (int d = 0; d < dim; ++d)
      s += (d > 0 ? ", " : "") + num(p[d]);
    return s + ")";
  }
} // namespace femp

#endif
