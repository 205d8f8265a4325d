// femp: save and restore of cell fields of the background grid keyed by the
// global structured cell number, so that a checkpoint resumes on another
// number of ranks (doc/checkpoint.md). No equation of the paper.
#ifndef femp_cell_state_h
#define femp_cell_state_h

#include <femp/base/state_stream.h>
#include <femp/grid/background_grid.h>

#include <array>
#include <cstdint>
#include <vector>

namespace femp
{
  using namespace dealii;

  /// Global linear index i + n_0 (j + n_1 k) of the structured cell @p ijk.
  template <int dim, typename Index>
  std::uint64_t
  global_cell_number(const BackgroundGrid<dim> &grid, const Index &ijk)
  {
    std::uint64_t g = 0;
    for (int d = dim - 1; d >= 0; --d)
      g = g * grid.n_cells()[d] + ijk[d];
    return g;
  }

  /// Local flat index of the cell with global linear index @p g if this
  /// rank owns it, else numbers::invalid_size_type-like -1.
  template <int dim>
  std::int64_t
  owned_local_index(const BackgroundGrid<dim> &grid, std::uint64_t g)
  {
    std::array<int, dim> ijk;
    for (int d = 0; d < dim; ++d)
      {
        ijk[d] = g % grid.n_cells()[d];
        g /= grid.n_cells()[d];
      }
    if (!grid.in_box(ijk))
      return -1;
    const auto idx = grid.local_index(ijk);
    return grid.cell_status()[idx] == BackgroundGrid<dim>::owned ?
             std::int64_t(idx) :
             -1;
  }

  /// Save the owned values of cell fields (same size as the local box),
  /// keyed by the global cell number.
  template <int dim>
  void
  save_cell_fields(StateWriter                                    &out,
                   const BackgroundGrid<dim>                      &grid,
                   const std::vector<const std::vector<double> *> &fields)
  {
    const auto                &owned = grid.owned_cells();
    std::vector<std::uint64_t> keys(owned.size());
    for (std::size_t k = 0; k < owned.size(); ++k)
      keys[k] = global_cell_number(grid, grid.global_index(owned[k]));
    out.put<std::uint32_t>(fields.size());
    out.put_vector(keys);
    std::vector<double> v(owned.size());
    for (const auto *f : fields)
      {
        for (std::size_t k = 0; k < owned.size(); ++k)
          v[k] = (*f)[owned[k]];
        out.put_vector(v);
      }
  }

  /// Restore what save_cell_fields() wrote, from the parts of all saved
  /// ranks: each rank keeps its owned cells; ghosts are exchanged.
  template <int dim>
  void
  load_cell_fields(std::vector<StateReader>                 &parts,
                   const BackgroundGrid<dim>                &grid,
                   const std::vector<std::vector<double> *> &fields)
  {
    for (auto &in : parts)
      {
        const auto n_fields = in.get<std::uint32_t>();
        AssertThrow(n_fields == fields.size(),
                    ExcMessage("checkpoint: wrong number of cell fields"));
        const auto                keys = in.get_vector<std::uint64_t>();
        std::vector<std::int64_t> local(keys.size());
        for (std::size_t k = 0; k < keys.size(); ++k)
          local[k] = owned_local_index(grid, keys[k]);
        for (auto *f : fields)
          {
            const auto v = in.get_vector<double>();
            for (std::size_t k = 0; k < keys.size(); ++k)
              if (local[k] >= 0)
                (*f)[local[k]] = v[k];
          }
      }
    for (auto *f : fields)
      grid.update_ghosts(*f);
  }
} // namespace femp

#endif
