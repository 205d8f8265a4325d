// femp: shared helpers of the output writers (see output_files.h).
#include <deal.II/base/exceptions.h>
#include <deal.II/base/mpi.h>

#include <femp/io/output_files.h>

#include <algorithm>
#include <filesystem>

namespace femp
{
  using namespace dealii;

  /// Throw, naming the file, if writing @p file failed (@p ok false).
  void
  check_written(const bool ok, const std::string &file)
  {
    AssertThrow(ok,
                ExcMessage("cannot write the output file '" + file +
                           "' (missing directory, no permission or disk "
                           "full?)"));
  }

  /// Throw, naming the file, if a write to @p out failed.
  void
  check_stream(const std::ostream &out, const std::string &file)
  {
    check_written(static_cast<bool>(out), file);
  }

  /// Replace the index @p file by the one @p write puts into the stream,
  /// once every rank has written its pieces (barrier), atomically: rank 0
  /// writes a temporary file and renames it over the old one, so that a
  /// reader, or a run killed meanwhile, never leaves a half-written index.
  void
  replace_index(const std::string                              &file,
                const std::function<void(const std::string &)> &write,
                const MPI_Comm                                  comm)
  {
    const int ierr = MPI_Barrier(comm);
    AssertThrowMPI(ierr);
    if (Utilities::MPI::this_mpi_process(comm) != 0)
      return;
    const std::string tmp = file + ".tmp";
    write(tmp);
    std::error_code error;
    std::filesystem::rename(tmp, file, error);
    AssertThrow(!error,
                ExcMessage("cannot replace '" + file + "' by '" + tmp +
                           "': " + error.message()));
  }

  /// Whether @p name is in @p selection (empty: all are).
  bool
  selected(const std::vector<std::string> &selection, const std::string &name)
  {
    return selection.empty() ||
           std::find(selection.begin(), selection.end(), name) !=
             selection.end();
  }
} // namespace femp
