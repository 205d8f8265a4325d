// femp: the .pvd index of the VTU/PVTU output (see vtu_pvtu.h).
#include <femp/io/output_files.h>
#include <femp/io/vtu_pvtu.h>

#include <fstream>

namespace femp
{
  /// The ParaView index of a series of PVTU records.
  void
  write_pvd(const std::string                                 &file,
            const std::vector<std::pair<double, std::string>> &records,
            const MPI_Comm                                     comm)
  {
    replace_index(
      file,
      [&](const std::string &tmp) {
        std::ofstream pvd(tmp);
        DataOutBase::write_pvd_record(pvd, records);
        pvd.close();
        check_stream(pvd, tmp);
      },
      comm);
  }
} // namespace femp
