// femp: FeZoneHandover<dim>, which cell rows of cooled metal a build hands
// from material points to finite elements at each layer start (doc/builds.md,
// "Handing cooled metal to finite elements"). The hand-over itself is
// SolidSubCycle::hand_over_rows(); this class chooses the new top of the FE
// zone and keeps what the choice needs.
//
//   - the fusion depth of a layer: its powder top less the bottom of the
//     lowest cell that held molten metal (alpha >= 1/2 at or above the
//     solidus) between its start and the next layer's start (observed after
//     every temperature step); D: the deepest over the finished layers;
//   - at the start of layer n, after its recoat: the rows may reach up to
//     the grid line at or below top_n - D - margin (top_n: the new
//     powder's top), so that the new layer's melt, as deep as the deepest
//     so far, stays a margin above them;
//   - from the zone's top upwards, every row whose cells inside the zone's
//     horizontal extent are all full of metal (alpha = 1), hold points, and
//     whose points are all solid (no powder, no fluid) and below the
//     hand-over temperature is taken, up to the first row that is not.
// Every rank takes the same decision (reductions over the ranks).
#ifndef femp_fe_zone_handover_h
#define femp_fe_zone_handover_h

#include <deal.II/base/parameter_handler.h>

#include <femp/base/parameter_table.h>
#include <femp/base/state_stream.h>
#include <femp/grid/background_grid.h>
#include <femp/grid/material_points.h>

#include <cstdint>
#include <limits>
#include <vector>

namespace femp
{
  using namespace dealii;

  template <int dim>
  class FeZoneHandover
  {
  public:
    /// Subsection 'Build'.
    struct Parameters
    {
      /// 'Hand over cooled metal'.
      bool enabled = false;
      /// 'Hand-over temperature', K: every point of a handed row is below
      /// it; range (0, Material/Solidus).
      double temperature = 1000;
      /// 'Hand-over margin', m: the rows stay this far below the deepest
      /// melt expected of the new layer; range [0, inf).
      double margin = 1e-5;

      /// Declare (the members' values are the defaults) or read the
      /// entries, each listed once.
      void
      add_parameters(ParameterTable &table);
      static void
      declare_parameters(ParameterHandler &prm);
      void
      parse_parameters(ParameterHandler &prm);
      /// With the hand-over on, refuse what cannot work (InputError naming
      /// the parameter): no heat, no solid, no FE zone, no layer schedule,
      /// a temperature not below @p solidus.
      void
      check(const double solidus,
            const bool   heat,
            const bool   solid,
            const bool   fe_zone,
            const bool   layers) const;
    };

    /// @p first_top: the first layer's powder top, m.
    FeZoneHandover(const Parameters          &prm,
                   const BackgroundGrid<dim> &grid,
                   const double               solidus,
                   const double               first_top);

    /// After a temperature step: the lowest molten metal of the layer
    /// (cells of the local box owned by this rank; local).
    void
    observe(const std::vector<double> &T, const std::vector<double> &alpha);

    /// At the start of a layer whose powder reaches @p new_top (m), after
    /// its recoat: close the fusion depth of the layer before and return
    /// the grid line the FE zone may rise to (m), or a value at or below
    /// the zone's top when no row may be handed over. @p zone: the FE
    /// zone's cells of the local box (SolidSubCycle::fe_zone_cells());
    /// @p alpha: the metal fraction. Collective.
    double
    choose_top(const double                     new_top,
               const MaterialPoints<dim>       &points,
               const std::vector<std::uint8_t> &zone,
               const std::vector<double>       &alpha);

    /// The FE zone's top found by the last choose_top(), m.
    double
    zone_top() const
    {
      return current_top;
    }
    /// The deepest fusion depth of the finished layers, m (0: none yet).
    double
    deepest_fusion() const
    {
      return depth;
    }
    /// The limit of the last choice, top_n - D - margin, m.
    double
    limit() const
    {
      return last_limit;
    }
    /// The row that stopped the last choice below the limit (m, its
    /// bottom) and why ("" when the limit stopped it).
    const std::string &
    stop_reason() const
    {
      return reason;
    }

    /// Checkpoint: the fusion depths so far (the deepest, the powder top
    /// of the layer observed, its lowest molten cell over all ranks) and
    /// what the last choice found (the zone's top, the limit). Collective.
    void
    save_state(StateWriter &out) const;
    /// Restore it (@p parts: one per saved rank; every rank takes the
    /// lowest molten cell of all, which is what the next choice reduces
    /// the ranks' values to).
    void
    load_state(std::vector<StateReader> &parts);

  private:
    const Parameters           prm;
    const BackgroundGrid<dim> &grid;
    const double               solidus;
    /// The powder top of the layer being observed, m.
    double layer_top;
    /// Lowest cell bottom with molten metal in the layer (local), m.
    double      lowest = std::numeric_limits<double>::infinity();
    double      depth = 0, current_top = 0, last_limit = 0;
    std::string reason;
  };
} // namespace femp

#endif
