// femp: the VTU/PVTU format of the output (ParaView): one record of a
// series (a VTU piece per rank, their PVTU record, the .pvd index of the
// series), for the grid fields (deal.II's DataOut, filled by
// Output::write_grid_output) and for the material points as 0-dimensional
// patches. No equation of the paper.
#ifndef femp_vtu_pvtu_h
#define femp_vtu_pvtu_h

#include <deal.II/base/data_out_base.h>
#include <deal.II/base/mpi.h>
#include <deal.II/particles/particle_handler.h>

#include <femp/io/output_files.h>

#include <string>
#include <utility>
#include <vector>

namespace femp
{
  using namespace dealii;

  /// The ParaView index of a series of PVTU records.
  void
  write_pvd(const std::string                                 &file,
            const std::vector<std::pair<double, std::string>> &records,
            const MPI_Comm                                     comm);

  /// One record of the VTU series @p name in @p directory: the pieces of
  /// @p data (one per rank, compressed for speed, at @p time) and their
  /// PVTU record <name>_<n>.pvtu, added to @p records; then the index
  /// <name>.pvd of the series is replaced. Collective.
  template <int patch_dim, int spacedim>
  void
  write_vtu_record(DataOutInterface<patch_dim, spacedim>       &data,
                   const std::string                           &directory,
                   const std::string                           &name,
                   const unsigned int                           n,
                   const double                                 time,
                   std::vector<std::pair<double, std::string>> &records,
                   const MPI_Comm                               comm);

  /// Material points as 0-dimensional patches (one per point) with the
  /// point id and the chosen properties, for the VTU and the HDF5 writers.
  template <int dim>
  class PointPatches : public DataOutInterface<0, dim>
  {
  public:
    PointPatches(const Particles::ParticleHandler<dim> &points,
                 const std::vector<std::string>        &property_names,
                 const std::vector<std::string>        &selection)
    {
      std::vector<unsigned int> columns;
      names = {"id"};
      for (unsigned int i = 0; i < property_names.size(); ++i)
        if (selected(selection, property_names[i]))
          {
            columns.push_back(i);
            names.push_back(property_names[i]);
          }
      patches.resize(points.n_locally_owned_particles());
      unsigned int i = 0;
      for (const auto &point : points)
        {
          auto &patch       = patches[i];
          patch.vertices[0] = point.get_location();
          patch.patch_index = i++;
          patch.data.reinit(names.size(), 1);
          patch.data(0, 0) = point.get_id();
          const auto props = point.get_properties();
          for (unsigned int c = 0; c < columns.size(); ++c)
            patch.data(c + 1, 0) = props[columns[c]];
        }
    }

  private:
    std::vector<DataOutBase::Patch<0, dim>> patches;
    std::vector<std::string>                names;

    const std::vector<DataOutBase::Patch<0, dim>> &
    get_patches() const override
    {
      return patches;
    }
    std::vector<std::string>
    get_dataset_names() const override
    {
      return names;
    }
  };
} // namespace femp

#endif
