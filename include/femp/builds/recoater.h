// femp: layer-by-layer builds (doc/builds.md, "Recoating"): the layer
// schedule (when each layer after the first starts and how high its powder
// reaches) and the recoater that spreads a new powder layer over the current
// surface at that time.
//
// Schedule ('Build' subsection): from the scan path (each rise of the
// segments' height, heat/scan_path.h, starts a layer at the beginning of
// that segment: the jump to the new layer; a dwell with the laser off before
// it cools the last layer; a path at one height is one layer; a segment with
// the laser on that starts or ends below the layer in progress, the last
// layer begun before it, is refused) or from
// listed start times and one layer thickness. Layer k's powder reaches the
// height
//   top_k = substrate top + first powder layer + (z_k - z_1)
// (z_k: its height in the scan path; with listed times z_k - z_1 = (k - 1)
// x thickness).
//
// Recoating a layer (the blade passes at top_k):
//  1. the blade: the metal not attached to the build (MetalBodies: the
//     metal cells that no chain of face-connected metal cells joins to the
//     bottom row, attached_metal_cells()) that reaches above top_k (a
//     point whose top, position + half the spacing, lies above it) is
//     swept away with the whole detached body it belongs to
//     (label_metal_bodies() from the cells holding such points): its
//     points are deleted, their number, mass and stored heat reported.
//     Attached metal above top_k stays (the blade passes over the part),
//     and so does detached metal below it (drops lying on the bed);
//  2. the surface: per lattice column (spacing: Material points/Point
//     spacing) of the domain, the top of the highest attached point; the
//     height a grain rests on: the higher of that and the top of the
//     detached metal left in the column (a grain falling on a drop that
//     stayed rests on it; the space under a drop that does not touch the
//     surface stays gas), collected over the ranks;
//  3. grains of the first layer's size distribution are dropped by the
//     same ballistic packing (grid/powder_bed.h), each resting on that
//     height or on a grain already placed, the blade at top_k rejecting
//     those that would stick out; the packing fraction refers to the
//     volume between the resting height and top_k. The lattice points
//     inside each grain and above the resting height of their column
//     become powder points at 'Build/Powder temperature'.
// Everything depends only on the points' positions, alpha and the seed
// (the first layer's seed + 7919 x the layer number), so every rank sweeps
// the same drops and builds the same bed.
#ifndef femp_recoater_h
#define femp_recoater_h

#include <deal.II/base/parameter_handler.h>

#include <femp/base/parameter_table.h>
#include <femp/grid/background_grid.h>
#include <femp/grid/material_points.h>
#include <femp/heat/laser.h>

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace femp
{
  using namespace dealii;

  /// Where the layer start times come from: none (one layer), the scan
  /// path's heights, or a list of times.
  enum class LayerSource
  {
    none,
    scan_path,
    times
  };

  /// The input names of LayerSource (Build/Layer schedule).
  const Choices<LayerSource> &
  layer_source_names();

  /// When each layer after the first starts, and where its powder ends.
  template <int dim>
  class LayerSchedule
  {
  public:
    struct Parameters
    {
      /// Build/Layer schedule: when a new powder layer is spread.
      LayerSource source = LayerSource::none;
      /// Build/Layer thickness (m), with "times".
      double thickness = 30e-6;
      /// Build/Layer start times (s), with "times".
      std::vector<double> start_times;
      /// Build/Powder temperature (K); 0: the ambient temperature.
      double powder_temperature = 0;
      /// Build/Rebalance above imbalance: at a layer start, the busiest
      /// rank's MPM points over their mean over the ranks above which the
      /// run re-cuts its grid by its state; 0: never.
      double rebalance_above = 0;

      /// Declare (the members' values are the defaults) or read the

      /// entries, each listed once.

      void

      add_parameters(ParameterTable &table);

      static void
      declare_parameters(ParameterHandler &prm);
      void
      parse_parameters(ParameterHandler &prm);
      bool
      enabled() const
      {
        return source != LayerSource::none;
      }
    };

    struct Layer
    {
      unsigned int number;     ///< 2, 3, ... (the first layer is the scene's)
      double       start_time; ///< s
      double       top;        ///< height reached by its powder, m
      double       thickness;  ///< nominal: top minus the last top, m
    };

    /// Build the schedule from @p prm and the laser's @p segments; the
    /// first layer's powder ends at @p first_top (substrate top + powder
    /// layer thickness). Throws InputError when a layer does not fit below
    /// the domain's top @p domain_top less two cells of @p cell_size (the
    /// free surface needs gas above it), the times are not increasing or
    /// the scan path goes down with the laser on.
    LayerSchedule(const Parameters                                &prm,
                  const std::vector<typename Laser<dim>::Segment> &segments,
                  const double                                     first_top,
                  const double                                     domain_top,
                  const double                                     cell_size);

    const std::vector<Layer> &
    layers() const
    {
      return list;
    }
    /// The layers whose start time lies in (t0, t1] (t1 rounded up by a
    /// relative 1e-12): those to recoat in the step that starts at t0
    /// (with t0 < 0: from the start).
    std::vector<Layer>
    starting_in(const double t0, const double t1) const;

  private:
    std::vector<Layer> list;
  };

  /// Spreads a powder layer over the current surface (see above).
  template <int dim>
  class Recoater
  {
  public:
    /// What one recoat did (the same on every rank).
    struct Report
    {
      unsigned int  layer        = 0;
      unsigned int  grains       = 0;
      std::uint64_t points       = 0; ///< points added
      double        fill_volume  = 0; ///< between rest height and blade, m^3
      double        packing      = 0; ///< grains' volume / fill volume
      double        point_volume = 0; ///< of the points added, m^3
      /// The attached surface's lowest and highest column top, m.
      double surface_min = 0, surface_max = 0;
      /// Columns whose resting height is a detached drop's top (above the
      /// attached surface, below the blade).
      unsigned int columns_on_drops = 0;
      /// The blade: detached bodies swept, their points, their mass, kg
      /// (2D: kg/m), and the sum over their points of mass x
      /// per_mass(T) of recoat() (their stored heat, J; 2D: J/m).
      unsigned int  swept_bodies   = 0;
      std::uint64_t swept_points   = 0;
      double        swept_mass     = 0;
      double        swept_enthalpy = 0;
    };

    /// Per lattice column (spacing: the point spacing; x fastest): the top
    /// of the highest attached point (position + half the spacing), and
    /// the height a grain rests on (the higher of that and the top of the
    /// detached metal); the domain's bottom where there is none.
    /// See recoat(): told the ids of this rank's swept points.
    using RemovalHook =
      std::function<void(const std::vector<types::particle_index> &)>;

    struct Surface
    {
      std::vector<double> attached;
      std::vector<double> rest;
    };

    /// @p powder: the first layer's grain sizes, packing fraction and seed
    /// (Material points/Powder layer); @p density: the metal's, kg/m^3.
    Recoater(const typename MaterialPoints<dim>::Parameters &powder,
             const double                                    density,
             const BackgroundGrid<dim>                      &grid);

    /// The surface of the points now (see Surface), with @p attached the
    /// workpiece's cells (attached_metal_cells() of the points' alpha; 1
    /// per attached metal cell of the local box, valid on owned cells).
    /// Collective.
    Surface
    surface(const MaterialPoints<dim>       &points,
            const std::vector<std::uint8_t> &attached) const;

    /// Spread layer @p layer (its number and top) at temperature @p T:
    /// sweep the detached metal above the blade, then new powder points in
    /// @p points on the surface left. @p alpha: the points' metal fraction
    /// (ghosts exchanged), @p attached: its workpiece cells (as above);
    /// @p per_mass: the stored heat per kilogram of a swept point at its
    /// temperature, J/kg (empty: 0). @p before_removal (may be empty):
    /// called on every rank when the blade sweeps any point, before the
    /// swept points are deleted, with the particle ids of this rank's
    /// swept points, so that a module that counts points (the solid,
    /// SolidSubCycle::before_points_removed()) can account for them.
    /// Collective.
    Report
    recoat(MaterialPoints<dim>                      &points,
           const typename LayerSchedule<dim>::Layer &layer,
           const double                              T,
           const std::vector<double>                &alpha,
           const std::vector<std::uint8_t>          &attached,
           const std::function<double(double)>      &per_mass       = {},
           const RemovalHook                        &before_removal = {}) const;

  private:
    const typename MaterialPoints<dim>::Parameters powder;
    const double                                   density;
    const BackgroundGrid<dim>                     &grid;
    /// Insert the (owned cell, position) pairs @p added as powder points
    /// at @p T, with ids after every existing one and from @p first_free
    /// on (the next free id before the blade deleted points: no id is
    /// used twice). Collective.
    void
    insert_powder(MaterialPoints<dim>                               &points,
                  std::vector<std::pair<std::uint32_t, Point<dim>>> &added,
                  const double                                       T,
                  const types::particle_index first_free) const;
    /// The lattice column of position @p x (clamped to the domain).
    std::size_t
    column_of(const Point<dim> &x) const;
    /// Per column the attached and the detached metal's tops (not
    /// gathered), skipping the points of the owned cells marked in
    /// @p skip (may be null).
    std::array<std::vector<double>, 2>
    column_tops(const MaterialPoints<dim>       &points,
                const std::vector<std::uint8_t> &attached,
                const std::vector<double>       *skip) const;
    /// Lattice columns per horizontal direction (1 in 2D for y).
    std::array<unsigned int, 2> n_columns{{1, 1}};
  };
} // namespace femp

#endif
