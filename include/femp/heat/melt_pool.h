// femp: melt-pool size from the temperature field on the background grid.
// The pool is the region above the melting isotherm T_m (the liquidus by
// default); its boundary is located by linear interpolation of T between
// cell centres, the lateral one also at the surface (T extrapolated there).
//   length: extent along x of the isotherm,
//   width:  extent along y (3D) of the isotherm (2D: equal to the length),
//   depth:  reference top surface height minus the lowest crossing.
// The pool is the melt connected to colder metal (spatter in the gas is
// not counted); where nothing is colder, all melt counts. Given the cells
// of the workpiece (the metal attached to the substrate, MetalBodies), only
// these count: a detached drop, liquid or partly solid, is no pool.
// Given a lower bound x_min, only the cells with centre x >= x_min count
// (the others are taken as gas): the cross-sections of a track's start,
// which a boundary near it may keep hot and wide, are then left out.
// Beside this liquidus box, the size as a cross-section of the track is
// measured: the fusion zone is the region above the solidus T_s inside
// the original substrate (cell centres below the substrate top), so the
// bead or molten powder above the original surface does not count:
//   solidus_width: extent along y (3D; 2D: along x) of that region,
//   solidus_depth: substrate top minus its lowest crossing of T_s.
#ifndef femp_melt_pool_h
#define femp_melt_pool_h

#include <femp/grid/background_grid.h>

#include <cstdint>
#include <limits>
#include <vector>

namespace femp
{
  struct MeltPoolSize
  {
    double length = 0, width = 0, depth = 0; ///< m, zero when nothing melted
    double volume = 0;                       ///< m^3 (2D: m^2), cells above T_m
    double T_max  = 0;                       ///< K, over metal cells
    /// Fusion zone inside the original substrate at the solidus, m.
    double                solidus_width = 0, solidus_depth = 0;
    std::array<double, 3> lower{}, upper{}; ///< bounding box of the pool, m
  };

  /// Global melt-pool size; @p T needs valid ghosts; @p alpha marks metal.
  /// @p T_melt: the pool's isotherm (liquidus); @p surface_height: the
  /// original substrate top, m; @p T_solidus: the isotherm of the fusion
  /// zone inside the substrate (solidus_width, solidus_depth);
  /// @p workpiece: per cell of the local box 1 for the cells of the
  /// workpiece (MetalBodies::workpiece_cells(), valid on owned cells), the
  /// only metal the pool and the fusion zone count (nullptr: all metal);
  /// @p x_min: only the cells with centre x >= x_min count, m (-inf: all).
  /// T_max is over all metal cells. Collective.
  template <int dim>
  MeltPoolSize
  measure_melt_pool(
    const BackgroundGrid<dim>       &grid,
    const std::vector<double>       &T,
    const std::vector<double>       &alpha,
    const double                     T_melt,
    const double                     surface_height,
    const double                     T_solidus,
    const std::vector<std::uint8_t> *workpiece = nullptr,
    const double x_min = -std::numeric_limits<double>::infinity());
} // namespace femp

#endif
