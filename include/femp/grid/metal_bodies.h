// femp: MetalBodies<dim>, the bodies of metal that the metal fraction alpha
// makes up, found once per change of alpha (whoever moved the points) and
// handed to their readers: the heat transfer (the heat loss of detached
// drops), the solid (whose points in a detached drop are set aside) and the
// stop test (the peak temperature of the workpiece).
//
// Detached drops (with 'Heat transfer/Detached drops = sphere'): a drop of
// at most K = 'Detached drop cells' face-connected metal cells with no
// other metal face neighbour inside the domain. Found on any partition: a
// metal cell with K or more metal face neighbours lies in a body of more
// than K cells; the others (candidates, a few per cent of the metal cells:
// edges and corners) collect the global indices of the cells they reach,
// one layer of face neighbours per round, the sets passing through the
// ghost layer. A set that exceeds K cells, or meets a cell with K or more
// neighbours, marks a larger body. After K rounds a set of at most K cells
// is a whole drop (a body of more than K cells has more than K cells within
// K steps of each of its cells). The drop's metal volume V = sum alpha h^3
// (2D: sum alpha h^2) sums the fractions of its cells in the order of their
// global indices, the same on every rank; its diameter is that of a sphere
// of that volume, d = (6 V/pi)^(1/3) (2D: a cylinder, (4 V/pi)^(1/2)).
//
// The workpiece, the metal attached to the substrate, for the peak
// temperature that ends a run after cooling ('Time stepping/Stop when peak
// temperature below', doc/cases.md "Residual stress after cooling"). With
// the melt flow, droplets that the flow throws off the pool (spatter) can
// sit in the gas as single metal cells; surrounded by gas they lose heat
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
#ifndef femp_metal_bodies_h
#define femp_metal_bodies_h

#include <femp/grid/background_grid.h>

#include <cstdint>
#include <vector>

namespace femp
{
  template <int dim>
  class MetalBodies
  {
  public:
    /// An owned cell of a detached drop.
    struct DropCell
    {
      std::uint32_t index;
      /// Metal volume of the whole drop, m^3 (2D: m^2).
      double volume;
      /// Diameter of the sphere (2D: cylinder) of that volume, m.
      double diameter;
    };

    /// @p max_drop_cells: K above; 0: no drops are looked for.
    MetalBodies(const BackgroundGrid<dim> &grid,
                const unsigned int         max_drop_cells);

    /// alpha changed (owned cells and ghosts): find the detached drops now;
    /// the workpiece when it is first asked for. Collective.
    void
    update(const std::vector<double> &alpha);

    /// The owned cells of the detached drops, in increasing local index
    /// (empty when no drops are looked for).
    const std::vector<DropCell> &
    detached_drops() const
    {
      return drops;
    }
    /// Their indices.
    std::vector<std::uint32_t>
    detached_cells() const;

    /// Per cell of the local box, 1 for the counted cells of the workpiece
    /// (above), 0 else; valid on owned cells. Collective at its first call
    /// after update().
    const std::vector<std::uint8_t> &
    workpiece_cells();

    /// Global maximum of @p T over the counted cells of the workpiece; the
    /// maximum over all metal cells (alpha > 0) when there is none.
    /// Collective.
    double
    workpiece_max_temperature(const std::vector<double> &T);

  private:
    const BackgroundGrid<dim> &grid;
    const unsigned int         max_drop_cells;
    /// The alpha of the last update().
    std::vector<double>       alpha;
    std::vector<DropCell>     drops;
    std::vector<std::uint8_t> workpiece;
    bool                      workpiece_current = false;
    /// Scratch of the drop search: the metal face neighbours per cell, and
    /// per cell of the local box the global indices of the drop found so
    /// far (max_drop_cells fields) and their number (the last field; more
    /// than max_drop_cells: a larger body). Read only at cells with few
    /// metal neighbours.
    std::vector<double>              neighbour_count;
    std::vector<std::vector<double>> drop_sets;

    void
    find_detached_drops();
  };

  /// The counted cells of the workpiece (MetalBodies, above) of @p alpha:
  /// per cell of the local box, 1 for the counted cells, 0 else; valid on
  /// owned cells. @p sweeps, if given, receives the number of exchange
  /// rounds. Collective.
  template <int dim>
  std::vector<std::uint8_t>
  attached_metal_cells(const BackgroundGrid<dim> &grid,
                       const std::vector<double> &alpha,
                       unsigned int              *sweeps = nullptr);

  /// Global maximum of @p T over the cells @p counted of attached_metal_
  /// cells(); the maximum over all metal cells (alpha > 0) when there is
  /// none. Collective.
  template <int dim>
  double
  attached_metal_max_temperature(const BackgroundGrid<dim>       &grid,
                                 const std::vector<double>       &T,
                                 const std::vector<double>       &alpha,
                                 const std::vector<std::uint8_t> &counted);

  /// The same with the counted cells found from @p alpha. Collective.
  template <int dim>
  double
  attached_metal_max_temperature(const BackgroundGrid<dim> &grid,
                                 const std::vector<double> &T,
                                 const std::vector<double> &alpha);
} // namespace femp

#endif
