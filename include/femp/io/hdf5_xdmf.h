// femp: the HDF5/XDMF format of the output: each rank's part of a mesh
// with its data sets, written collectively by all ranks into one HDF5 file
// through MPI-IO with zlib compression, and the XDMF index (one <Grid> per
// output in a temporal collection) that ParaView and VisIt read. No
// equation of the paper.
#ifndef femp_hdf5_xdmf_h
#define femp_hdf5_xdmf_h

#include <deal.II/base/mpi.h>

#include <cstdint>
#include <string>
#include <vector>

namespace femp
{
  /// One rank's part of an unstructured mesh with data sets on its nodes
  /// or cells, as it goes into an HDF5 file: node coordinates and cells
  /// (corner indices into this rank's nodes; none for points, corners =
  /// 1: XDMF's Polyvertex needs no connectivity). Data sets flagged single
  /// are stored as 4-byte floats (the VTU writer's precision), the others
  /// as doubles.
  struct H5Part
  {
    unsigned int              dim = 0, corners = 0;
    std::uint64_t             n_nodes = 0, n_cells = 0;
    bool                      single_nodes = false, compress = false;
    std::vector<double>       nodes;
    std::vector<unsigned int> cells;
    struct DataSet
    {
      std::string         name;
      bool                single, on_cells;
      std::vector<double> values;
    };
    std::vector<DataSet> data;
  };

  /// Global sizes of the parts of all ranks and this rank's offsets.
  struct H5Layout
  {
    std::uint64_t nodes = 0, cells = 0, node_offset = 0, cell_offset = 0;
  };

  /// Write the parts of all ranks (collective; a rank may have none)
  /// into one HDF5 file: with @p write_mesh the data sets /nodes and
  /// /cells into @p mesh_file, the data sets into @p data_file (the same
  /// name: one file). Returns the global sizes.
  H5Layout
  write_h5(const std::string &mesh_file,
           const std::string &data_file,
           const bool         write_mesh,
           const H5Part      &part,
           const MPI_Comm     comm);

  /// The XDMF <Grid> element of one output: geometry and topology from
  /// @p mesh_file, the data sets of @p part from @p data_file (names
  /// relative to the index's directory), sizes from @p l.
  std::string
  xdmf_entry(const double       time,
             const std::string &mesh_file,
             const std::string &data_file,
             const H5Part      &part,
             const H5Layout    &l);

  /// The XDMF index of a series of HDF5 files: one temporal collection
  /// of the <Grid> elements @p entries (rank 0 writes it).
  void
  write_xdmf(const std::string              &file,
             const std::vector<std::string> &entries,
             const MPI_Comm                  comm);
} // namespace femp

#endif
