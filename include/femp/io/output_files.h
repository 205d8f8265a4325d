// femp: what the writers of femp's output files share: a failed write
// names the file, an index file (.pvd, .xdmf) is replaced atomically once
// every rank has written its pieces, and a selection of names ('all' or a
// list) is looked up. No equation of the paper.
#ifndef femp_output_files_h
#define femp_output_files_h

#include <deal.II/base/mpi.h>

#include <functional>
#include <ostream>
#include <string>
#include <vector>

namespace femp
{
  /// Throw, naming the file, if writing @p file failed (@p ok false).
  void
  check_written(const bool ok, const std::string &file);
  /// Throw, naming the file, if a write to @p out failed.
  void
  check_stream(const std::ostream &out, const std::string &file);

  /// Replace the index @p file by the one @p write puts into the stream,
  /// once every rank has written its pieces (barrier), atomically: rank 0
  /// writes a temporary file and renames it over the old one, so that a
  /// reader, or a run killed meanwhile, never leaves a half-written index.
  void
  replace_index(const std::string                              &file,
                const std::function<void(const std::string &)> &write,
                const MPI_Comm                                  comm);

  /// Whether @p name is in @p selection (empty: all are).
  bool
  selected(const std::vector<std::string> &selection, const std::string &name);
} // namespace femp

#endif
