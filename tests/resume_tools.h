// femp tests: helpers for the tests that resume a run from its checkpoint.
#ifndef femp_resume_tools_h
#define femp_resume_tools_h

#include <deal.II/base/exceptions.h>
#include <deal.II/base/mpi.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace femp_test
{
  /// Copy the output directory @p from, checkpoints included, to @p to
  /// (rank 0) and return the checkpoint to resume in the copy: the newest
  /// but one of its index (the one before the end's, if the end wrote one),
  /// or the only one. Collective.
  inline std::string
  copy_for_resume(const std::string &from, const std::string &to,
                  MPI_Comm comm)
  {
    std::ifstream            index(from + "/checkpoint/index");
    std::vector<std::string> steps; // newest first
    for (std::string line; index >> line;)
      steps.push_back(line);
    AssertThrow(!steps.empty(),
                dealii::ExcMessage("no checkpoint written in " + from));
    if (dealii::Utilities::MPI::this_mpi_process(comm) == 0)
      std::filesystem::copy(from, to,
                            std::filesystem::copy_options::recursive);
    MPI_Barrier(comm);
    return to + "/checkpoint/" + (steps.size() > 1 ? steps[1] : steps[0]);
  }
} // namespace femp_test

#endif
