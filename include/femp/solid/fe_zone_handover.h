// femp: FeZoneHandover<dim>, which cells of cooled metal a build hands from
// material points to finite elements at each layer start (doc/builds.md,
// "Handing cooled metal to finite elements"). The hand-over itself is
// SolidSubCycle::hand_over_cells(); this class chooses the cells and keeps
// what the choice needs.
//
//   - the fusion depth of a layer: its powder top less the bottom of the
//     lowest cell that held molten metal (alpha >= 1/2 at or above the
//     solidus) between its start and the next layer's start (observed after
//     every temperature step); D: the deepest over the finished layers;
//   - at the start of layer n, after its recoat: the cells may reach up to
//     the grid line at or below top_n - D - margin (top_n: the new
//     powder's top), so that the new layer's melt, as deep as the deepest
//     so far, stays a margin above them;
//   - and, with 'Hand-over surface limit' (the default), a cell of column
//     c may reach up to the grid line at or below S_w(c) - P - margin:
//     S(c) the column's metal surface, the top of its highest cell of
//     metal (a zone cell, an open cell of a pore, or alpha >= 1/2 with no
//     powder point: a cell of powder, or of metal with a powder grain in
//     it, is no metal); counted from the top down, gas and powder
//     enclosed below the surface (a lack-of-fusion void that the pore
//     detector does not close) do not lower it; S_w(c)
//     the lowest S over the columns whose centres lie within 'Hand-over
//     surface window' of c's (the same array on every rank: a reduction
//     over the ranks); P the penetration depth, the deepest that a
//     finished layer's melt reached below the surface it met: the largest
//     over the columns of S_w(c) at the layer's start less the bottom of
//     the column's lowest molten cell in the layer (the first layer's
//     surface: the substrate top; where a layer's surface is unknown, its
//     fusion depth counts). The melt of a powder layer sinks onto the
//     metal below it, which a ragged bead leaves deeper than top_n - D in
//     some columns; the second line keeps the cells there under the
//     powder as points;
//   - a cell inside the zone's horizontal extent, below that line and
//     outside the zone is a candidate when it is dense, its points are
//     all solid (no powder, no fluid) and it is cool enough by the
//     'Hand-over rule': with 'temperature' its points are below the
//     hand-over temperature; with 're-heating' its predicted peak in the
//     new layer, its hottest point plus R(k), is below the solidus less
//     'Re-heating margin', R(k) being the largest rise of a metal cell's
//     temperature (alpha >= 1/2) over its temperature at its layer's first
//     step, among the cells k whole cells below their layer's powder top
//     (to the cell's centre), over the latest 'Re-heating layers'
//     finished layers (observed after every temperature step with the
//     lowest molten cell);
//     the candidates connected to the zone through faces of candidates
//     (a flood fill from the zone's cells over face neighbours) are
//     taken (with 'Hand-over checks per layer' n > 1 also at n - 1
//     times within each layer from the second on, the limit then
//     top_n - max(D, the layer's own depth so far) - margin). A cell
//     that is not dense (the open cells of a lack-of-fusion pore, the
//     porous metal around them) stays material points, an island inside
//     the zone once the columns around it rise past it; a row of
//     candidates only is taken whole, as a row of cells.
// Every rank takes the same decision (reductions over the ranks: every
// rank holds the candidates' flags and the zone's cells over the
// candidate box).
//
// A cell is dense when it holds points, is no open cell of a pore
// (PoreDetector: gas enclosed in the fused metal), and
//   - the metal fraction alpha (sub-cell occupancy) is at least
//     dense_alpha = 0.99 on every cell of its 3^dim neighbourhood (the
//     cell and its face, edge and corner neighbours inside the grid)
//     that is no pore cell, or
//   - its fill (below) is at least full_fill = 0.9.
// The pore's own cells are left out of the neighbourhood: they stay
// points (an island inside the zone), the detector counts their gas as
// the pore's, and a neighbour whose own sub-cells are all occupied holds
// at least a full cell of points (2 x 2 points and sub-cells per cell:
// one point per sub-cell at least), which the element carries as the
// full density. A neighbour into which the pore's gas reaches by a
// sub-cell reads alpha below 0.99 itself and stays points.
// The two read dense metal in different states of its points. Metal that
// melted and re-solidified keeps every sub-cell occupied (alpha = 1), but
// the melt flow has moved its points apart in some cells and together in
// others, so that its fill scatters from a sixth to twice the lattice's
// (doc/builds.md, "Dense metal"): the fill cannot
// tell it from a pore, alpha can. Metal that never melted keeps its
// lattice, which thermal strain may move rigidly by about half a spacing
// so that alpha reads 1/2 (two point rows in one sub-cell row) while its
// fill reads 1: alpha cannot tell it from a void, the fill can. Gas of a
// sub-cell's size or more lowers alpha below 0.99 in the cells around it
// and the fill below 0.9 (a missing point costs its cell 9/64 in 2D); the
// open cells of a pore of the detector (alpha below its threshold,
// enclosed) stay points whatever their alpha and fill; a cell of unfused
// powder holds powder points. A dense cell directly under a free surface
// has a neighbour of alpha < 0.99 above it and a fill of about 7/8.
//
// The fill of a cell is the volume fraction of the points under a linear
// hat centred at the cell's centre, of half-width h in each direction:
//   f_c = sum_p V_p prod_d N((x_p,d - c_d) / h) / V_hat,
//   N(u) = max(0, 1 - |u|),
// V_hat = h^dim, less an eighth of h per direction at a face of the domain
// (the part of the hat beyond it). The hats of the cell centres are a
// partition of unity, and a lattice of spacing h/n (n whole) samples each
// one to exactly n^dim points whatever its shift against the grid: dense
// metal reads 1 on any rigid shift of its lattice, where the sub-cell
// occupancy alpha drops to 1/2 once two point rows share one sub-cell row
// (a lattice moved by half a spacing). The hat is continuous, so a point
// that moves a little changes the fill a little (a point on a cell face
// counts half on each side), where a count of points per cell jumps.
// A void reads below 1. On the unmoved lattice of two points per cell and
// direction (points h/4 from the cell's centre), one missing point (an
// empty sub-cell) costs its cell (1/2)^dim (3/4)^dim: 9/64 in 2D (the cell
// reads 0.86), 27/512 in 3D (0.95); a neighbour cell loses at most 3/64
// (2D). An empty cell reads 7/16 (2D), a dense cell under gas (a free
// surface in the row above) 7/8. full_fill = 0.9 takes dense metal (1, up
// to the points' thermal volume change and the jitter of a strained
// lattice) and leaves as points a cell with an empty sub-cell (2D; in 3D
// two), a cell into which a pore's gas reaches and the row under a free
// surface.
// The zone's points stay where the hand-over left them, while the zone's
// top face moves with its nodes (thermal expansion) and the points above
// with it: a lift u of the face would read as a gap of about u/h in the
// row above. The points of each column's top zone cell are therefore taken
// u higher (u interpolated between the nodes of the cell's top face,
// SolidSubCycle::zone_top_lift()), so that zone and metal above form one
// lattice again: dense metal over an expanded zone reads 1. The whole top
// cell moves by the face's lift, which
// overstates its lower points' displacement by the row's own strain times
// their depth (below 1 % of h). A negative lift (a contracted zone) is
// taken as 0: the points above are held on the grid line (below), where the
// zone's unmoved points meet them.
//
// The points at the new top. Where the lattice has moved by about half a
// spacing, points of the row above lie on the new top. The coupling puts
// the zone's top face on the grid line (the elements are the grid's
// cells, their top nodes the transition nodes that the points above share
// with the zone), and those points move with the transition nodes, so
// thermal contraction carries them across the line by a fraction of a
// spacing. They stay in the solid: SolidMPM holds a point that crosses a
// face of the zone (its top, or a lateral face of a zone narrower than the
// domain, beside which the plate and the build stand) by less than half a
// point spacing on the face (the face is a wall for the points, as the
// domain's faces are for spatter), its velocity into the zone removed;
// mass, stress and plastic strain stay with the point, the kinetic energy
// removed is booked by the next transfer. A deeper entry still stops the
// run.
#ifndef femp_fe_zone_handover_h
#define femp_fe_zone_handover_h

#include <deal.II/base/parameter_handler.h>

#include <femp/base/parameter_table.h>
#include <femp/base/state_stream.h>
#include <femp/grid/background_grid.h>
#include <femp/grid/material_points.h>

#include <array>
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
      /// 'Hand-over surface limit': the cells stay P + margin below the
      /// lowest metal surface near their column as well (see the file's
      /// comment).
      bool surface_limit = true;
      /// 'Hand-over surface window', m: the horizontal distance from a
      /// column's centre within which the lowest metal surface counts;
      /// range [0, inf).
      double surface_window = 2e-5;
      /// 'Hand-over checks per layer': the choices per layer, the first at
      /// its start, the others equally spaced over its window
      /// (choose_in_layer()); range [1, 100].
      int checks = 1;
      /// 'Hand-over rule': what keeps a dense, solid cell below the limit
      /// line as points.
      enum class Rule
      {
        /// a point at or above 'Hand-over temperature';
        temperature,
        /// a predicted peak of the new layer at or above the solidus less
        /// 'Re-heating margin' (the cell's hottest point plus the largest
        /// rise seen at its depth below the top in the finished layers).
        reheating
      };
      Rule rule = Rule::temperature;
      /// 'Re-heating margin', K: with the re-heating rule a handed cell's
      /// predicted peak stays this far below the solidus; range
      /// [0, Material/Solidus).
      double reheat_margin = 100;
      /// 'Re-heating layers': the envelope of the rises is taken over
      /// this many finished layers, the latest; range [1, 1000] (1000:
      /// all of a build's layers in practice).
      int reheat_layers = 1000;
      /// The input names of the rules.
      static const Choices<Rule> &
      rule_names();

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

    /// @p first_top: the first layer's powder top, m; @p first_surface:
    /// the metal surface under it (the substrate top), m (NaN: unknown, the
    /// first layer's penetration is its fusion depth).
    FeZoneHandover(
      const Parameters          &prm,
      const BackgroundGrid<dim> &grid,
      const double               solidus,
      const double               first_top,
      const double first_surface = std::numeric_limits<double>::quiet_NaN());

    /// After a temperature step: the lowest molten metal of the layer
    /// (cells of the local box owned by this rank; local) and, per depth
    /// below the layer's top, the largest rise of a metal cell's
    /// temperature (alpha >= 1/2) over its temperature at the layer's
    /// first step (layer_rise()).
    void
    observe(const std::vector<double> &T, const std::vector<double> &alpha);

    /// At the start of a layer whose powder reaches @p new_top (m), after
    /// its recoat: close the fusion depth of the layer before, choose the
    /// cells to hand over (chosen_cells()) and return the top of the zone's
    /// bounding box with them (m; the zone's top when none is taken).
    /// @p zone: the FE zone's cells of the local box
    /// (SolidSubCycle::fe_zone_cells());
    /// @p top_lift: the vertical displacement of the zone's top-face nodes
    /// since its top was set (SolidSubCycle::zone_top_lift(); empty: 0).
    /// @p alpha: the metal fraction per cell of the local box (owned values
    /// used); @p pore: per cell of the local box, > 0 on the open cells of
    /// a pore (PoreDetector::Result::pore_number; empty: no pores).
    /// Collective.
    double
    choose_top(const double                     new_top,
               const MaterialPoints<dim>       &points,
               const std::vector<std::uint8_t> &zone,
               const std::vector<double>       &top_lift,
               const std::vector<double>       &alpha,
               const std::vector<double>       &pore);

    /// Within a layer (Parameters::checks > 1), after choose_top() closed
    /// the layer before: choose the cells as choose_top() does, the layer
    /// staying open and the limit top_n - max(D, the layer's own fusion
    /// depth so far) - margin. Returns the top of the zone's bounding box
    /// with them. Collective.
    double
    choose_in_layer(const MaterialPoints<dim>       &points,
                    const std::vector<std::uint8_t> &zone,
                    const std::vector<double>       &top_lift,
                    const std::vector<double>       &alpha,
                    const std::vector<double>       &pore);

    /// The fusion depth the last choice kept clear, m (D at a layer
    /// start; within a layer the larger of D and the layer's own so far).
    double
    kept_depth() const
    {
      return used_depth;
    }

    /// The penetration depth the last choice kept clear below the metal
    /// surface, m (P at a layer start; within a layer the larger of P and
    /// the layer's own so far).
    double
    kept_penetration() const
    {
      return used_penetration;
    }
    /// The metal surface per column of the grid at the last choice, the
    /// lowest within the window (S_w; m; columns lexicographic, x
    /// fastest; the same on every rank).
    const std::vector<double> &
    metal_surface() const
    {
      return surface;
    }
    /// The lowest S_w(c) - P - margin over the zone's columns at the last
    /// choice, m (+inf: no zone or the surface limit off).
    double
    surface_limit() const
    {
      return least_surface_limit;
    }

    /// The largest temperature rise per depth below the top over the
    /// latest 'Re-heating layers' finished layers, K (entry k: the cells
    /// whose centre lies k to k + 1 cells below the layer's powder top; 0
    /// where none rose), as the last choose_top() closed them (the same on
    /// every rank).
    const std::vector<double> &
    rise_envelope() const
    {
      return envelope;
    }
    /// The rises per depth of each finished layer, K (the same on every
    /// rank; the last: the layer the last choose_top() closed).
    const std::vector<std::vector<double>> &
    layer_rises() const
    {
      return history;
    }
    /// The predicted peak of the hottest candidate cell the re-heating rule
    /// kept as points in the last choice, K (-inf: none).
    double
    hottest_prediction() const
    {
      return kept_prediction;
    }
    /// The largest predicted peak of the cells the last choice took, K
    /// (re-heating rule; -inf: none taken or the temperature rule).
    double
    handed_peak_prediction() const
    {
      return handed_prediction;
    }

    /// The least fill (see the file's comment) of a dense cell whose
    /// neighbourhood's alpha is below dense_alpha.
    static constexpr double full_fill = 0.9;
    /// The least metal fraction on a dense cell's neighbourhood (see the
    /// file's comment) that makes it dense whatever its fill.
    static constexpr double dense_alpha = 0.99;

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
    /// The bottom of the lowest cell that held molten metal in the layer
    /// closed by the last choice (within a layer: in that layer so far),
    /// m (over all ranks; +inf: none melted).
    double
    last_lowest_molten() const
    {
      return closed_lowest;
    }
    /// The limit of the last choice, top_n - D - margin, m (the surface
    /// limit below it per column: surface_limit()).
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

    /// The cells the last choice took (structured indices, lexicographic
    /// order, x fastest; the same on every rank; empty: none).
    const std::vector<std::array<int, dim>> &
    chosen_cells() const
    {
      return chosen;
    }
    /// The mass of the points of the cells the last choice took (kg; 2D:
    /// kg/m; over the ranks).
    double
    chosen_point_mass() const
    {
      return chosen_mass;
    }

    /// Why the solid's points of the zone's columns stay material points
    /// after the last choice (doc/builds.md, "What stays material
    /// points"): each cell outside the zone, inside the zone's horizontal
    /// extent, that holds solid points is counted once, with its solid
    /// points, in the first class that holds:
    enum Kept : unsigned int
    {
      /// at or above the limit line (limit());
      above_limit,
      /// below it, with a point of powder or fluid as well (unfused
      /// powder, metal still molten);
      powder,
      /// below it, all points solid, an open cell of a pore, or a cell
      /// next to one (among its 3^dim neighbours) that is not dense;
      pore,
      /// below it, all points solid, no pore near, not dense (alpha below
      /// dense_alpha around it and a fill below full_fill: porous
      /// re-solidified metal, spatter, the row under a free surface);
      not_dense,
      /// below it, dense and solid, a point at or above the hand-over
      /// temperature (temperature rule) or a predicted peak at or above the
      /// solidus less the re-heating margin (re-heating rule);
      too_hot,
      /// a candidate (dense, solid, cool, below it) that the flood fill
      /// does not reach from the zone;
      not_connected,
      n_kept
    };
    /// The name of class @p k (a word for the log and layer_cost.csv).
    static const char *
    kept_name(const unsigned int k);
    /// The cells of each class after the last choice (over the ranks).
    const std::array<double, n_kept> &
    kept_cells() const
    {
      return kept_n_cells;
    }
    /// The solid points of those cells per class (over the ranks; their
    /// sum is about the solid's MPM points inside the zone's horizontal
    /// extent: solid-state points that the solid does not step count
    /// too).
    const std::array<double, n_kept> &
    kept_points() const
    {
      return kept_n_points;
    }

    /// The least fill of each row the last choice looked at, from the
    /// zone's top upwards (over the cells inside the zone's horizontal
    /// extent; empty when no row was looked at).
    const std::vector<double> &
    least_fill() const
    {
      return row_fill;
    }

    /// Checkpoint: the fusion depths so far (the deepest, the powder top
    /// of the layer observed, its lowest molten cell over all ranks), the
    /// temperature rises per depth (the layer's over all ranks, the
    /// envelope) with the cells' temperatures at the layer's start, and
    /// what the last choice found (the zone's top, the limit, the cells
    /// and points of each class kept as points). Collective.
    void
    save_state(StateWriter &out) const;
    /// Restore it (@p parts: one per saved rank; every rank takes the
    /// lowest molten cell of all, which is what the next choice reduces
    /// the ranks' values to).
    void
    load_state(std::vector<StateReader> &parts);
    /// Checkpoint, re-heating rule only (its own section): each owned
    /// cell's temperature at the layer's first step, from which the
    /// layer's rises count. Collective.
    void
    save_layer_start(StateWriter &out) const;
    void
    load_layer_start(std::vector<StateReader> &parts);

    /// The mass of the points of each row the last choice looked at, from
    /// the zone's top upwards, inside the zone's horizontal extent (kg;
    /// 2D: kg/m; summed over the ranks).
    const std::vector<double> &
    row_point_mass() const
    {
      return row_mass;
    }
    /// The number of points of each of those rows (summed over the ranks).
    const std::vector<double> &
    row_point_count() const
    {
      return row_points;
    }

  private:
    const Parameters           prm;
    const BackgroundGrid<dim> &grid;
    const double               solidus;
    /// The powder top of the layer being observed, m.
    double layer_top;
    /// Lowest cell bottom with molten metal in the layer (local), m.
    double lowest = std::numeric_limits<double>::infinity();
    /// The temperature of each cell of the local box at the layer's first
    /// observe() (owned values), K, under the re-heating rule (empty under
    /// the temperature rule); whether the next observe() takes it.
    std::vector<double> T_start;
    bool                start_pending = true;
    /// The largest rise per depth row in the layer being observed (local)
    /// and over the finished layers (all ranks), K.
    std::vector<double>              rise, envelope;
    std::vector<std::vector<double>> history;
    double kept_prediction   = -std::numeric_limits<double>::infinity();
    double handed_prediction = -std::numeric_limits<double>::infinity();
    double depth = 0, current_top = 0, last_limit = 0, used_depth = 0;
    /// Per column of the grid: the bottom of the lowest molten cell of the
    /// layer (local), m; the windowed metal surface at the layer's start
    /// (all ranks; empty: unknown) and at the last choice, m.
    std::vector<double> col_lowest, start_surface, surface;
    /// The penetration depth P of the finished layers and the one the
    /// last choice used, m; the lowest surface line of the last choice.
    double penetration = 0, used_penetration = 0,
           least_surface_limit = std::numeric_limits<double>::infinity();
    /// The number of columns of the grid and a cell's column.
    std::size_t
    n_columns() const;
    template <typename Index>
    std::size_t
    column(const Index &ijk) const
    {
      std::size_t c = 0;
      for (int d = dim - 2; d >= 0; --d)
        c = c * grid.n_cells()[d] + std::size_t(ijk[d]);
      return c;
    }
    /// The windowed metal surface S_w per column (see the file's comment).
    /// Collective.
    std::vector<double>
    find_surface(const MaterialPoints<dim>       &points,
                 const std::vector<std::uint8_t> &zone,
                 const std::vector<double>       &alpha,
                 const std::vector<double>       &pore) const;
    /// The layer's lowest molten cell per column over the ranks (m; +inf:
    /// none). Collective.
    std::vector<double>
    all_col_lowest() const;
    /// The largest S_w at the layer's start less the lowest molten cell's
    /// bottom over the columns of the layer so far (over the ranks; -inf:
    /// none melted). Collective.
    double
    layer_penetration() const;
    /// The choice below the line @p limit (m) of choose_top() and
    /// choose_in_layer().
    double
    choose(const double                     limit,
           const MaterialPoints<dim>       &points,
           const std::vector<std::uint8_t> &zone,
           const std::vector<double>       &top_lift,
           const std::vector<double>       &alpha,
           const std::vector<double>       &pore);
    /// The lowest molten cell of the layer the last choice closed (log).
    double              closed_lowest = std::numeric_limits<double>::infinity();
    std::string         reason;
    std::vector<double> row_fill, row_mass, row_points;
    std::vector<std::array<int, dim>> chosen;
    double                            chosen_mass = 0;
    std::array<double, n_kept>        kept_n_cells{}, kept_n_points{};
  };
} // namespace femp

#endif
