// femp: the metal attached to the substrate, for the peak temperature that
// ends a run after cooling ('Time stepping/Stop when peak temperature
// below', doc/cases.md "Residual stress after cooling").
//
// With the melt flow, droplets that the flow throws off the pool (spatter)
// can sit in the gas as single metal cells; surrounded by gas they lose heat
// only through the surface and stay near the liquidus long after the track
// has cooled, so the hottest metal cell would never fall below a stop
// temperature. The workpiece is the metal connected to the bottom of the
// domain:
//   - attached cells: the cells with alpha > 1/2 connected to a cell of the
//     bottom row (alpha > 1/2) through a chain of face neighbours with
//     alpha > 1/2 (a flood fill: within each rank, then across the ghost
//     layer, repeated until no rank finds a new cell; the set is a property
//     of the field, so it does not depend on the partition);
//   - counted cells: the attached cells and the cells with 0 < alpha <= 1/2
//     that share a face with an attached cell (the partly filled cells on
//     the surface of the pool and of the bead).
// Metal that is not counted (a detached droplet, powder not touching the
// workpiece) does not enter the peak temperature.
#ifndef femp_attached_metal_h
#define femp_attached_metal_h

#include <femp/grid/background_grid.h>

#include <cstdint>
#include <vector>

namespace femp
{
  /// Per cell of the local box, 1 for the counted cells (above), 0 else;
  /// valid on owned cells. @p alpha: the metal fraction (owned cells
  /// used). @p sweeps, if given, receives the number of exchange rounds.
  /// Collective.
  template <int dim>
  std::vector<std::uint8_t>
  attached_metal_cells(const BackgroundGrid<dim> &grid,
                       const std::vector<double> &alpha,
                       unsigned int              *sweeps = nullptr);

  /// Global maximum of @p T over the counted cells; the maximum over all
  /// metal cells (alpha > 0) when there is none. Collective.
  template <int dim>
  double
  attached_metal_max_temperature(const BackgroundGrid<dim> &grid,
                                 const std::vector<double> &T,
                                 const std::vector<double> &alpha);
} // namespace femp

#endif
