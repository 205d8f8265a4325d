// femp: HDF5 files written collectively, and their XDMF index (see
// hdf5_xdmf.h).
#include <deal.II/base/exceptions.h>
#include <deal.II/base/mpi.h>

#include <femp/io/hdf5_xdmf.h>
#include <femp/io/output_files.h>

#include <algorithm>
#include <fstream>
#include <hdf5.h>
#include <iomanip>
#include <sstream>

namespace femp
{
  using namespace dealii;

  namespace
  {
    /// Write rows [@p offset, @p offset + @p rows) of the 2D data set
    /// @p name (global size @p global_rows x @p columns) from @p values,
    /// collectively; a rank without rows takes part with an empty selection.
    void
    write_h5_dataset(const hid_t         file,
                     const std::string  &name,
                     const hid_t         file_type,
                     const hid_t         memory_type,
                     const std::uint64_t global_rows,
                     const std::uint64_t columns,
                     const std::uint64_t offset,
                     const std::uint64_t rows,
                     const void         *values,
                     const std::string  &file_name,
                     const bool          compress = false)
    {
      const hsize_t dims[2]    = {global_rows, columns};
      const hsize_t count[2]   = {rows, columns};
      const hsize_t start[2]   = {offset, 0};
      const hid_t   file_space = H5Screate_simple(2, dims, nullptr);
      // Compressed: zlib level 1 (as the VTU pieces) on chunks of 2^16 rows.
      const hid_t create = H5Pcreate(H5P_DATASET_CREATE);
      if (compress && global_rows > 0)
        {
          const hsize_t chunk[2] = {std::min<hsize_t>(global_rows, 1 << 16),
                                    columns};
          H5Pset_chunk(create, 2, chunk);
          H5Pset_deflate(create, 1);
        }
      const hid_t set = H5Dcreate2(file,
                                   name.c_str(),
                                   file_type,
                                   file_space,
                                   H5P_DEFAULT,
                                   create,
                                   H5P_DEFAULT);
      H5Pclose(create);
      const hid_t memory_space = H5Screate_simple(2, count, nullptr);
      herr_t      status       = 0;
      if (rows > 0)
        status = H5Sselect_hyperslab(
          file_space, H5S_SELECT_SET, start, nullptr, count, nullptr);
      else
        status =
          std::min(H5Sselect_none(file_space), H5Sselect_none(memory_space));
      const hid_t transfer = H5Pcreate(H5P_DATASET_XFER);
      H5Pset_dxpl_mpio(transfer, H5FD_MPIO_COLLECTIVE);
      static const double none = 0;
      const bool ok = file_space >= 0 && set >= 0 && memory_space >= 0 &&
                      status >= 0 &&
                      H5Dwrite(set,
                               memory_type,
                               memory_space,
                               file_space,
                               transfer,
                               rows > 0 ? values : &none) >= 0;
      H5Pclose(transfer);
      H5Sclose(memory_space);
      H5Dclose(set);
      H5Sclose(file_space);
      AssertThrow(ok,
                  ExcMessage("cannot write the data set '" + name +
                             "' of the output file '" + file_name + "'"));
    }

    /// Create @p name for parallel writing by all ranks of @p comm.
    hid_t
    create_h5_file(const std::string &name, const MPI_Comm comm)
    {
      const hid_t access = H5Pcreate(H5P_FILE_ACCESS);
      H5Pset_fapl_mpio(access, comm, MPI_INFO_NULL);
      const hid_t file =
        H5Fcreate(name.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, access);
      H5Pclose(access);
      check_written(file >= 0, name);
      return file;
    }
  } // namespace

  /// Write the parts of all ranks (collective; a rank may have none)
  /// into one HDF5 file: with @p write_mesh the data sets /nodes and
  /// /cells into @p mesh_file, the data sets into @p data_file (the same
  /// name: one file). Returns the global sizes.
  H5Layout
  write_h5(const std::string &mesh_file,
           const std::string &data_file,
           const bool         write_mesh,
           const H5Part      &part,
           const MPI_Comm     comm)
  {
    H5Layout            l;
    const std::uint64_t local[2]  = {part.n_nodes, part.n_cells};
    std::uint64_t       offset[2] = {0, 0}, total[2] = {0, 0};
    int ierr = MPI_Exscan(local, offset, 2, MPI_UINT64_T, MPI_SUM, comm);
    AssertThrowMPI(ierr);
    if (Utilities::MPI::this_mpi_process(comm) == 0)
      offset[0] = offset[1] = 0;
    ierr = MPI_Allreduce(local, total, 2, MPI_UINT64_T, MPI_SUM, comm);
    AssertThrowMPI(ierr);
    l.nodes = total[0], l.cells = total[1];
    l.node_offset = offset[0], l.cell_offset = offset[1];
    hid_t file = -1;
    if (write_mesh)
      {
        AssertThrow(part.nodes.size() == local[0] * part.dim &&
                      part.cells.size() ==
                        (part.corners > 1 ? local[1] * part.corners : 0),
                    ExcInternalError());
        file = create_h5_file(mesh_file, comm);
        // Single precision converted here: with compression, HDF5 writes
        // collectively only without type conversions.
        std::vector<float> single(part.single_nodes ? part.nodes.size() : 0);
        std::copy(part.nodes.begin(),
                  part.nodes.begin() + single.size(),
                  single.begin());
        write_h5_dataset(
          file,
          "nodes",
          part.single_nodes ? H5T_NATIVE_FLOAT : H5T_NATIVE_DOUBLE,
          part.single_nodes ? H5T_NATIVE_FLOAT : H5T_NATIVE_DOUBLE,
          l.nodes,
          part.dim,
          l.node_offset,
          local[0],
          part.single_nodes ? static_cast<const void *>(single.data()) :
                              static_cast<const void *>(part.nodes.data()),
          mesh_file,
          part.compress);
        if (part.corners > 1)
          {
            std::vector<std::uint32_t> cells(part.cells.size());
            for (std::size_t i = 0; i < cells.size(); ++i)
              cells[i] = part.cells[i] + l.node_offset;
            write_h5_dataset(file,
                             "cells",
                             H5T_NATIVE_UINT32,
                             H5T_NATIVE_UINT32,
                             l.cells,
                             part.corners,
                             l.cell_offset,
                             local[1],
                             cells.data(),
                             mesh_file);
          }
        if (mesh_file != data_file)
          {
            AssertThrow(H5Fclose(file) >= 0,
                        ExcMessage("cannot close '" + mesh_file + "'"));
            file = -1;
          }
      }
    if (file < 0)
      file = create_h5_file(data_file, comm);
    for (const auto &set : part.data)
      {
        const unsigned int k = set.on_cells;
        AssertThrow(set.values.size() == local[k],
                    ExcMessage("data set '" + set.name + "' of " +
                               std::to_string(set.values.size()) +
                               " values for " + std::to_string(local[k]) +
                               (k ? " cells" : " nodes")));
        std::vector<float> single(set.single ? set.values.size() : 0);
        std::copy(set.values.begin(),
                  set.values.begin() + single.size(),
                  single.begin());
        const hid_t type = set.single ? H5T_NATIVE_FLOAT : H5T_NATIVE_DOUBLE;
        write_h5_dataset(file,
                         set.name,
                         type,
                         type,
                         total[k],
                         1,
                         offset[k],
                         local[k],
                         set.single ?
                           static_cast<const void *>(single.data()) :
                           static_cast<const void *>(set.values.data()),
                         data_file,
                         part.compress);
      }
    AssertThrow(H5Fclose(file) >= 0,
                ExcMessage("cannot close '" + data_file + "'"));
    return l;
  }

  /// The XDMF <Grid> element of one output: geometry and topology from
  /// @p mesh_file, the data sets of @p part from @p data_file (names
  /// relative to the index's directory), sizes from @p l.
  std::string
  xdmf_entry(const double       time,
             const std::string &mesh_file,
             const std::string &data_file,
             const H5Part      &part,
             const H5Layout    &l)
  {
    std::ostringstream x;
    auto               item = [&](const std::uint64_t rows,
                    const unsigned int  columns,
                    const std::string  &number,
                    const unsigned int  precision,
                    const std::string  &file,
                    const std::string  &set) {
      x << "          <DataItem Dimensions=\"" << rows << ' ' << columns
        << "\" NumberType=\"" << number << "\" Precision=\"" << precision
        << "\" Format=\"HDF\">\n            " << file << ":/" << set
        << "\n          </DataItem>\n";
    };
    x << "      <Grid Name=\"mesh\" GridType=\"Uniform\">\n"
      << "        <Time Value=\"" << std::setprecision(10) << time << "\"/>\n"
      << "        <Geometry GeometryType=\"" << (part.dim == 2 ? "XY" : "XYZ")
      << "\">\n";
    item(l.nodes,
         part.dim,
         "Float",
         part.single_nodes ? 4 : 8,
         mesh_file,
         "nodes");
    x << "        </Geometry>\n";
    if (part.corners == 1)
      x << "        <Topology TopologyType=\"Polyvertex\" NumberOfElements=\""
        << l.cells << "\" NodesPerElement=\"1\"/>\n";
    else
      {
        x << "        <Topology TopologyType=\""
          << (part.corners == 4 ? "Quadrilateral" : "Hexahedron")
          << "\" NumberOfElements=\"" << l.cells << "\">\n";
        item(l.cells, part.corners, "UInt", 4, mesh_file, "cells");
        x << "        </Topology>\n";
      }
    for (const auto &set : part.data)
      {
        x << "        <Attribute Name=\"" << set.name
          << "\" AttributeType=\"Scalar\" Center=\""
          << (set.on_cells ? "Cell" : "Node") << "\">\n";
        item(set.on_cells ? l.cells : l.nodes,
             1,
             "Float",
             set.single ? 4 : 8,
             data_file,
             set.name);
        x << "        </Attribute>\n";
      }
    x << "      </Grid>\n";
    return x.str();
  }

  /// The XDMF index of a series of HDF5 files: one temporal collection
  /// of the <Grid> elements @p entries (rank 0 writes it).
  void
  write_xdmf(const std::string              &file,
             const std::vector<std::string> &entries,
             const MPI_Comm                  comm)
  {
    replace_index(
      file,
      [&](const std::string &tmp) {
        std::ofstream x(tmp);
        x << "<?xml version=\"1.0\" ?>\n"
          << "<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
          << "<Xdmf Version=\"2.0\">\n  <Domain>\n"
          << "    <Grid Name=\"CellTime\" GridType=\"Collection\" "
             "CollectionType=\"Temporal\">\n";
        for (const auto &e : entries)
          x << e;
        x << "    </Grid>\n  </Domain>\n</Xdmf>\n";
        x.close();
        check_stream(x, tmp);
      },
      comm);
  }
} // namespace femp
