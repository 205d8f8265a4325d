// femp: the FE zone a checkpoint holds (section "fe zone", written by
// SolidSubCycle::save_fe_zone(), which this reader is defined next to),
// read without a solid: the resumed solid builds it, and the partition of
// a resumed run weighs the cells by it (doc/performance.md, "Balancing the
// ranks"). No equation of the paper.
#ifndef femp_saved_fe_zone_h
#define femp_saved_fe_zone_h

#include <femp/base/state_stream.h>

#include <array>
#include <cstdint>
#include <vector>

namespace femp
{
  /// What the section holds: the zone's top (m) and the mass-scaling
  /// factor its masses were built at, and its cells where the section has
  /// them (has_cells: the bounding box's first cell, its cells per
  /// direction and the mask, lexicographic, x fastest; a section without
  /// them stands for the scene's box up to the top).
  template <int dim>
  struct SavedFeZone
  {
    double                    top = 0, factor = 0;
    bool                      has_cells = false;
    std::array<int, dim>      first{}, n{};
    std::vector<std::uint8_t> mask;
  };

  /// Read the section from @p parts[0] (every part holds the same).
  template <int dim>
  SavedFeZone<dim>
  read_saved_fe_zone(std::vector<StateReader> &parts);
} // namespace femp

#endif
