// femp: melt-pool size from the temperature field on the background grid.
// The pool is the region above the melting isotherm T_m (the liquidus by
// default); its boundary is located to sub-cell accuracy by linear
// interpolation of T between neighbouring cell centres, in each direction.
//   length: extent along x of the isotherm,
//   width:  extent along y (3D) of the isotherm (2D: equal to the length),
//   depth:  reference top surface height minus the lowest crossing.
// The pool is the melt connected to colder metal (spatter in the gas is
// not counted); where nothing is colder, all melt counts.
#ifndef femp_melt_pool_h
#define femp_melt_pool_h

#include <femp/grid/background_grid.h>

namespace femp
{
  struct MeltPoolSize
  {
    double length = 0, width = 0, depth = 0; ///< m, zero when nothing melted
    double volume = 0;                       ///< m^3 (2D: m^2), cells above T_m
    double T_max  = 0;                       ///< K, over metal cells
    std::array<double, 3> lower{}, upper{};  ///< bounding box of the pool, m
  };

  /// Global melt-pool size; @p T needs valid ghosts; @p alpha marks metal.
  template <int dim>
  MeltPoolSize
  measure_melt_pool(const BackgroundGrid<dim> &grid,
                    const std::vector<double> &T,
                    const std::vector<double> &alpha,
                    const double               T_melt,
                    const double               surface_height);
} // namespace femp

#endif
