// femp: the material points a checkpoint holds, counted per background
// cell without building them (doc/performance.md, "Balancing the ranks": a
// resumed run weighs its cells by them before it builds its grid). Reads
// the records of MaterialPoints::save_state(), which it is defined next to.
// No equation of the paper.
#ifndef femp_saved_points_h
#define femp_saved_points_h

#include <femp/base/state_stream.h>

#include <cstdint>
#include <vector>

namespace femp
{
  /// The points of a checkpoint's "points" section (all saved ranks'
  /// @p parts, read to their ends), counted per cell: @p all[g] and
  /// @p solid[g] (the points in state solid) of the cell with global number
  /// g (global_cell_number()), both resized to @p n_cells. The same on
  /// every rank; reads the file image only.
  template <int dim>
  void
  count_saved_points(std::vector<StateReader>   &parts,
                     const std::uint64_t         n_cells,
                     std::vector<std::uint32_t> &all,
                     std::vector<std::uint32_t> &solid);
} // namespace femp

#endif
