// femp: the records and the .pvd index of the VTU/PVTU output (see
// vtu_pvtu.h).
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

  template <int patch_dim, int spacedim>
  void
  write_vtu_record(DataOutInterface<patch_dim, spacedim>       &data,
                   const std::string                           &directory,
                   const std::string                           &name,
                   const unsigned int                           n,
                   const double                                 time,
                   std::vector<std::pair<double, std::string>> &records,
                   const MPI_Comm                               comm)
  {
    DataOutBase::VtkFlags flags;
    flags.time              = time;
    flags.compression_level = DataOutBase::VtkFlags::best_speed;
    data.set_flags(flags);
    const std::string record =
      data.write_vtu_with_pvtu_record(directory + "/", name, n, comm, 5, 8);
    records.emplace_back(time, record);
    write_pvd(directory + "/" + name + ".pvd", records, comm);
  }

#define FEMP_INSTANTIATE(P, S)                     \
  template void write_vtu_record(                  \
    DataOutInterface<P, S> &,                      \
    const std::string &,                           \
    const std::string &,                           \
    unsigned int,                                  \
    double,                                        \
    std::vector<std::pair<double, std::string>> &, \
    MPI_Comm);
  FEMP_INSTANTIATE(2, 2)
  FEMP_INSTANTIATE(3, 3)
  FEMP_INSTANTIATE(0, 2)
  FEMP_INSTANTIATE(0, 3)
#undef FEMP_INSTANTIATE
} // namespace femp
