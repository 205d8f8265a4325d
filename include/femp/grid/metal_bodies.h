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
// temperature below', doc/cases.md "Residual stress after cooling"), the
// cooling step, the melt pool and the recoater (builds/recoater.h: the
// surface the new powder rests on, and the detached metal its blade
// sweeps, whose bodies label_metal_bodies() finds by the same fill): the
// metal cells (alpha > 0) connected to
// a metal cell of the bottom row of the domain through a chain of face
// neighbours that are metal cells (a flood fill: within each rank, then
// across the ghost layer, repeated until no rank finds a new cell; the set
// is a property of the field, so it does not depend on the partition).
// These are exactly the cells that the heat equation (eq. 1) joins to the
// substrate by conduction: a cell's conductivity alpha k_m + (1 - alpha)
// k_g is zero in gas cells, so heat passes between cells only across faces
// of two metal cells. All other metal is detached: droplets that the flow
// throws off the pool (spatter), surrounded by gas, lose heat only through
// their surface and stay near the liquidus long after the track has
// cooled; powder not touching the workpiece. Its peak temperature is
// reported apart from the workpiece's (MetalPeakTemperatures).
#ifndef femp_metal_bodies_h
#define femp_metal_bodies_h

#include <femp/grid/background_grid.h>

#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

namespace femp
{
  /// Peak temperatures of the metal (alpha > 0) of a field, K: of the cells
  /// attached to the substrate (the workpiece) and of the other metal
  /// cells (detached); empty where there are none.
  struct MetalPeakTemperatures
  {
    std::optional<double> attached;
    std::optional<double> detached;

    /// The temperature that the stop test and the cooling step compare:
    /// the attached metal's peak; the detached metal's when nothing is
    /// attached (a scene without metal in the bottom row); the lowest
    /// double without metal.
    double
    workpiece() const
    {
      return attached ?
               *attached :
               detached.value_or(std::numeric_limits<double>::lowest());
    }
  };

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

    /// Per cell of the local box, 1 for the cells of the workpiece
    /// (above), 0 else; valid on owned cells. Collective at its first call
    /// after update().
    const std::vector<std::uint8_t> &
    workpiece_cells();

    /// Global peak temperatures of @p T over the workpiece and over the
    /// detached metal. Collective.
    MetalPeakTemperatures
    peak_temperatures(const std::vector<double> &T);

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

  /// The cells of the workpiece (MetalBodies, above) of @p alpha: per
  /// cell of the local box, 1 for the attached metal cells, 0 else; valid
  /// on owned cells. @p sweeps, if given, receives the number of exchange
  /// rounds. Collective.
  template <int dim>
  std::vector<std::uint8_t>
  attached_metal_cells(const BackgroundGrid<dim> &grid,
                       const std::vector<double> &alpha,
                       unsigned int              *sweeps = nullptr);

  /// The bodies of metal (face-connected metal cells, alpha > 0) that
  /// hold the seeds: @p seeds holds a label > 0 at the owned cells that
  /// start a body, 0 elsewhere (a field of the local box); per cell of the
  /// local box, the least seed label that reaches the cell through a chain
  /// of face neighbours that are metal cells, 0 where none does (and at
  /// the cells that are not owned). The same flood fill as the workpiece's
  /// (attached_metal_cells(): one label, the bottom row's metal cells),
  /// with labels that only fall: with distinct labels (a global cell index
  /// + 1) each body is named by its least seed. A property of the field,
  /// independent of the partition. @p sweeps, if given, receives the
  /// number of exchange rounds. Collective.
  template <int dim>
  std::vector<double>
  label_metal_bodies(const BackgroundGrid<dim> &grid,
                     const std::vector<double> &alpha,
                     const std::vector<double> &seeds,
                     unsigned int              *sweeps = nullptr);

  /// Global peak temperatures of @p T over the metal cells of @p alpha,
  /// split by @p attached (attached_metal_cells()). Collective.
  template <int dim>
  MetalPeakTemperatures
  metal_peak_temperatures(const BackgroundGrid<dim>       &grid,
                          const std::vector<double>       &T,
                          const std::vector<double>       &alpha,
                          const std::vector<std::uint8_t> &attached);

  /// The same with the attached cells found from @p alpha. Collective.
  template <int dim>
  MetalPeakTemperatures
  metal_peak_temperatures(const BackgroundGrid<dim> &grid,
                          const std::vector<double> &T,
                          const std::vector<double> &alpha);
} // namespace femp

#endif
