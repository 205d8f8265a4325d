// femp: the material points (doc/method.md, "Zones and discretizations") on the
// background grid, carried by deal.II's Particles::ParticleHandler.
//
// A scene builds a substrate block and a powder layer of randomly packed
// spherical grains; each region is filled with points on a global lattice of
// the given spacing, inserted cell by cell. The metal fraction alpha of a
// cell is the fraction of its n^dim sub-cells that hold at least one point
// (ref. [11]), and in cells holding melt (fluid points) the volume of its
// points, kept where fluid points bunch (see metal_fraction()); temperatures
// pass from cells to points after each thermal step, and from points to cells
// that just gained points.
//
// Property layout of each point (index: quantity, unit):
//   0 mass (kg; 2D: kg/m)        1 volume (m^3; 2D: m^2)
//   2 temperature (K)            3 state (0 powder, 1 solid, 2 fluid)
//   4 peak temperature (K), the melt history
//   5 .. 5+dim-1 velocity (m/s)
//   then dim(dim+1)/2 Cauchy stress components (Pa; xx, yy, [zz], xy, [xz, yz])
//   then the equivalent plastic strain (-)
//   2D only: then the out-of-plane stress sigma_zz (Pa; plane strain)
//   then the solid's artificial viscous pressure q (Pa; see SolidMPM)
//   then the dim x dim affine velocity matrix C_p of the APIC transfer of
//   the solid or of the melt flow (1/s, row-major: C_xx, C_xy, [C_xz,]
//   C_yx, ...; see SolidMPM and IncompressibleFlow)
#ifndef femp_material_points_h
#define femp_material_points_h

#include <deal.II/base/parameter_handler.h>
#include <deal.II/fe/mapping_q1.h>
#include <deal.II/particles/particle_handler.h>

#include <femp/base/material.h>
#include <femp/base/parameter_table.h>
#include <femp/grid/background_grid.h>

#include <functional>
#include <vector>

namespace femp
{
  using namespace dealii;
  class StateWriter;
  class StateReader;

  template <int dim>
  class MaterialPoints
  {
  public:
    enum State
    {
      powder = 0,
      solid  = 1,
      fluid  = 2
    };

    struct PropertyIndex
    {
      static constexpr unsigned int mass             = 0;
      static constexpr unsigned int volume           = 1;
      static constexpr unsigned int temperature      = 2;
      static constexpr unsigned int state            = 3;
      static constexpr unsigned int peak_temperature = 4;
      static constexpr unsigned int velocity         = 5;
      static constexpr unsigned int stress           = 5 + dim;
      static constexpr unsigned int plastic_strain =
        5 + dim + dim * (dim + 1) / 2;
      /// 2D only (plane strain): out-of-plane stress sigma_zz.
      static constexpr unsigned int stress_zz = plastic_strain + 1;
      /// Artificial bulk-viscosity pressure of the solid (SolidMPM).
      static constexpr unsigned int viscous_pressure =
        plastic_strain + 1 + (dim == 2 ? 1 : 0);
      /// APIC affine velocity matrix C_p, dim x dim row-major (SolidMPM, or
      /// IncompressibleFlow with Melt flow/Velocity transfer = APIC; zero
      /// with the FLIP transfers).
      static constexpr unsigned int affine_velocity = viscous_pressure + 1;
      static constexpr unsigned int n_properties = affine_velocity + dim * dim;
      /// Number of properties of the layout blocks a scene uses: the base
      /// block (up to the velocity), the solid block (stress, plastic
      /// strain, [sigma_zz,] viscous pressure) and the APIC block (needs
      /// the solid block). Points carry only these, so physics a scene
      /// switches off costs no memory, bandwidth or output.
      static constexpr unsigned int
      n_used(const bool solid, const bool affine)
      {
        return affine ? n_properties :
                        (solid ? affine_velocity : velocity + dim);
      }
    };

    struct Parameters
    {
      double       point_spacing    = 4e-6;
      double       substrate_top    = 1.5e-4;
      unsigned int subcells         = 2;
      double       layer_thickness  = 5e-5;
      double       mean_diameter    = 30e-6;
      double       std_diameter     = 8e-6;
      double       min_diameter     = 15e-6;
      double       max_diameter     = 45e-6;
      double       packing_fraction = 0.45;
      unsigned int seed             = 1;
      /// Material points/Carry points: auto (automatic) or always (on).
      AutoSwitch carry = AutoSwitch::automatic;
      /// Whether the scene carries points at all (resolve_carry()); false:
      /// create() makes none, alpha comes from the substrate's lattice
      /// geometry and the per-step transfer to points does nothing.
      bool carry_points = true;

      /// An initial body (Material points/Initial bodies): a box from
      /// @p a (lower corner) to @p b (upper corner), or an ellipsoid
      /// (ellipse in 2D) with centre @p a and semi-axes @p b; its points
      /// have state @p state and temperature @p T.
      struct Body
      {
        State       state = fluid;
        bool        box   = true;
        Point<dim>  a, b;
        double      T = 300;
        std::string text; ///< as written, for messages
        bool
        inside(const Point<dim> &p) const;
      };
      std::vector<Body> bodies;

      /// Declare (the members' values are the defaults) or read the

      /// entries, each listed once.

      void

      add_parameters(ParameterTable &table);

      static void
      declare_parameters(ParameterHandler &prm);
      void
      parse_parameters(ParameterHandler &prm);
      /// Checks against the grid that need both parameter sets.
      void
      check(const typename BackgroundGrid<dim>::Parameters &grid) const;
      /// Set carry_points: with 'Carry points = auto' points are carried
      /// only where something needs them: a powder layer, initial bodies,
      /// the melt flow (@p melt_flow), the solid (@p solid) or the track
      /// shape's melt history (@p track_shape). A bare plate under a laser
      /// needs none: its points would never move nor hold anything the
      /// cells do not.
      void
      resolve_carry(const bool melt_flow,
                    const bool solid,
                    const bool track_shape);
    };

    /// @p n_properties: how many properties each point carries
    /// (PropertyIndex::n_used(); by default the whole layout).
    MaterialPoints(
      const Parameters          &prm,
      const Material            &material,
      const BackgroundGrid<dim> &grid,
      const unsigned int         n_properties = PropertyIndex::n_properties);

    /// Number of properties each point carries.
    unsigned int
    n_properties() const
    {
      return n_props;
    }

    /// Melt flow/Velocity transfer = APIC: a point that melts or solidifies
    /// in cells_to_points() drops its affine velocity C_p, so that it
    /// enters the flow (or leaves it) with C_p = 0. Needs the affine block
    /// of the layout.
    void
    set_phase_change_drops_affine(const bool b)
    {
      AssertThrow(!b || n_props >= PropertyIndex::n_properties,
                  ExcMessage("MaterialPoints: the points do not carry the "
                             "affine velocity"));
      drop_affine = b;
    }

    /// Fill the substrate block and the powder layer with points at the
    /// initial temperature @p T0, then the initial bodies: lattice points
    /// inside a body (added above the substrate top, re-stated below it)
    /// take its state and temperature (a later body overrides an earlier).
    /// Without carried points (Parameters::carry_points false) none.
    void
    create(const double T0);

    /// Fill the owned cells with points on the lattice of the given spacing
    /// where @p inside is true, all in state @p state at temperature @p T0
    /// (flow test bodies: a water column, a droplet, a pool). Replaces any
    /// points created before.
    void
    create_region(const std::function<bool(const Point<dim> &)> &inside,
                  const double                                   T0,
                  const State                                    state);

    /// After point positions changed so that some point left its cell:
    /// move points to their new cells and ranks and refresh the list of
    /// occupied cells (deal.II's sort costs ~0.5 us per point, so call it
    /// only when needed).
    void
    points_moved();

    /// Cheaper alternative to points_moved() when every point moved at most
    /// into the ghost layer: moves each point that left its cell into its
    /// new owned cell (remove + insert, cost per moved point), or sends it
    /// to the rank that owns its new (ghost) cell, and refreshes the list
    /// of occupied cells. Collective; returns false, changing nothing, when
    /// on some rank a point went beyond the ghost layer (then call
    /// points_moved()).
    /// With @p from (local flat indices of owned occupied cells, increasing)
    /// only the points of these cells are checked: the cells where the
    /// caller saw a point leave (the flow's fluid cells, not every point).
    /// The list of occupied cells and the property cache are refreshed for
    /// the cells that lost or gained points only (same order of points as a
    /// full rebuild, so results do not change).
    bool
    relocate_points(const std::vector<std::uint32_t> *from = nullptr);

    /// Mass to take from the fluid points of an owned cell, kg (2D: kg/m),
    /// outermost along @p outward first (a unit vector; zero: the topmost,
    /// along +x_dim, first).
    struct MassToRemove
    {
      std::uint32_t  index;
      double         mass;
      Tensor<1, dim> outward;
    };
    /// What remove_mass() did, summed over the ranks.
    struct RemovedMass
    {
      double mass = 0; ///< taken from points, kg (2D: kg/m)
      /// Sum over the removed pieces of their mass times
      /// @p per_mass(T) of remove_mass() at the point's temperature.
      double        weighted    = 0;
      double        not_removed = 0; ///< asked but no fluid point had it
      unsigned long deleted     = 0; ///< points deleted
    };
    /// Take the listed masses (evaporation, HeatTransfer::evaporated_mass())
    /// from the fluid points of each cell: the points ordered by their
    /// position along the cell's outward direction, outermost first (ties by
    /// position), each gives all its mass until the rest is taken from the
    /// next one, whose mass and volume shrink by the same factor (its
    /// density, temperature and specific enthalpy stay). A point left with
    /// less than 1 % of a lattice point's mass (rho_m s^dim, s the point
    /// spacing) is deleted; its rest counts as removed. Mass a cell cannot
    /// give (no fluid point, or less fluid mass than asked) is returned as
    /// not removed. Cells that lost a point count as changed for the layout
    /// marks, and point_moves() moves on when any rank changed a point, so
    /// that alpha's keeper renews alpha. Collective.
    /// @p per_mass (J/kg, a function of the point's temperature, K) is
    /// summed over the removed mass into RemovedMass::weighted.
    RemovedMass
    remove_mass(const std::vector<MassToRemove>     &cells,
                const std::function<double(double)> &per_mass);

    /// Property arrays of the points of occupied_cells()[@p c], in the
    /// order of the handler's particles_in_cell() (valid until points are
    /// inserted, removed or re-sorted): a pointer loop instead of deal.II's
    /// iterator range (~20 ns per point) where only properties are read.
    ArrayView<double *const>
    cell_point_properties(const std::size_t c) const
    {
      return {point_properties.data() + cell_begin[c],
              cell_begin[c + 1] - cell_begin[c]};
    }

    /// Pool handles of the points of occupied_cells()[@p c] (same order
    /// and validity as cell_point_properties()): for the property pool's
    /// ids and for writers that keep handles between steps.
    ArrayView<const unsigned int>
    cell_point_handles(const std::size_t c) const
    {
      return {point_handles.data() + cell_begin[c],
              cell_begin[c + 1] - cell_begin[c]};
    }

    /// How many times points were moved across cells so far: every
    /// relocate_points() that moved a point on some rank, every
    /// points_moved() and every filling (create(), create_region()) counts
    /// one, whoever called it (the flow, the solid, the recoater). The same
    /// on every rank: the mark by which the keeper of the metal fraction
    /// (PointHeatExchange::follow_points()) sees that alpha is stale. A
    /// checkpoint's restore does not count (alpha is restored with it).
    std::uint64_t
    point_moves() const
    {
      return moves_global;
    }

    /// Where the handler's points stand now, for a writer that keeps pool
    /// handles of some points between steps (the solid's gather): see
    /// layout_unchanged().
    struct LayoutMark
    {
      std::uint64_t generation = 0; ///< re-indexings (sorts, loads, inserts)
      std::uint64_t moves  = 0; ///< relocate_points() calls that moved points
      std::uint64_t states = 0; ///< cells_to_points() calls that changed states
    };
    LayoutMark
    layout_mark() const
    {
      return {layout_generation, relocations, state_events};
    }
    /// True when, since @p mark, the handler was not re-sorted, re-indexed
    /// or filled anew, and relocate_points() moved no point into or out of
    /// any of the local cells @p cells (increasing or not): the points of
    /// these cells keep their pool handles and their order in the handler.
    bool
    layout_unchanged(const LayoutMark                 &mark,
                     const std::vector<std::uint32_t> &cells) const
    {
      if (mark.generation != layout_generation)
        return false;
      if (mark.moves == relocations)
        return true;
      for (const auto c : cells)
        if (moved_since(mark, c))
          return false;
      return true;
    }

    /// True unless, since @p mark, the handler kept its layout (see
    /// layout_unchanged()), no point entered or left local cell @p c and
    /// cells_to_points() changed the state of none of its points. States
    /// change only there and points change cells only by relocate_points()
    /// or a re-index, so a false answer means: the cell holds the same
    /// points in the same states as at @p mark (their positions inside the
    /// cell and other properties may differ).
    bool
    cell_changed_since(const LayoutMark &mark, const std::uint32_t c) const
    {
      return mark.generation != layout_generation || moved_since(mark, c) ||
             (mark.states != state_events && cell_state_at[c] > mark.states);
    }

    /// Owned cells that hold points: (flat index, cell iterator).
    const std::vector<
      std::pair<std::uint32_t,
                typename Triangulation<dim>::active_cell_iterator>> &
    occupied_cells() const
    {
      return occupied;
    }

    /// Metal fraction alpha per cell of the local box (ghosts exchanged).
    /// Cells without a fluid point: sub-cell occupancy (the fraction of the
    /// n^dim sub-cells holding a point, doc/method.md, "Heat transfer"). Cells
    /// holding a fluid point: the volume of their points over the cell volume,
    /// with the excess of over-full cells (points bunched by the flow) passed
    /// on to fluid face neighbours that are not full, then min(1, .): the metal
    /// volume of the melt is kept as the points keep it, where occupancy
    /// lost it when points bunched (doc/flow.md, "One fluid step").
    /// On the point lattice with spacing h/n both rules give the same alpha.
    /// Without carried points: the occupancy the substrate's lattice points
    /// would give, from the lattice alone (lattice_fraction()).
    /// Collective.
    std::vector<double>
    metal_fraction() const;

    /// Mark the local cells whose points never move, melt or change their
    /// volume while the run goes on (@p fixed: 1 per such cell of the local
    /// box): the finite-element zone of the solid, whose points carry only
    /// temperatures (a point that enters the zone stops the run, and so
    /// does zone metal at the solidus). metal_fraction() bins the points of
    /// such a cell once and reuses its sub-cell bits afterwards, unless the
    /// cell's number of points changed (it does the same for the cells
    /// that hold only unmelted powder, until a point comes, goes or melts
    /// there). An empty @p fixed: none.
    void
    set_fixed_cells(const std::vector<std::uint8_t> &fixed);

    /// Points take the temperature of their cell; states and melt history
    /// follow (powder or solid -> fluid above the solidus, fluid -> solid at
    /// or below it). With @p metal (the metal fraction the heat equation
    /// solves, from the last alpha pass): the points of a cell where it is
    /// 0 keep their temperature. Such a cell was gas at that pass, and its
    /// temperature is stale: points entered it since (a caller that moved
    /// points and did not renew alpha yet), and the next pass gives it
    /// their enthalpy.
    /// In the cells marked by set_fixed_cells() (the FE zone, whose points
    /// never move or melt) at or below the solidus, only the cell's
    /// temperature and its highest value are recorded; the points get them
    /// from flush_point_temperatures().
    void
    cells_to_points(const std::vector<double> &T,
                    const std::vector<double> *metal = nullptr);

    /// Give the points of the fixed cells the temperature and the peak that
    /// cells_to_points() recorded for them since the last flush (the
    /// values the points would hold had they been written at every call).
    /// Call before reading the temperatures or peaks of all points (output,
    /// checkpoint, report); volume_mean_over_points() and save_state() do
    /// it for the cells they read.
    void
    flush_point_temperatures() const;

    /// Heat carried by the points (Heat transfer/Advection by melt flow =
    /// points): for each owned cell holding a point whose temperature
    /// differs from the cell's @p T, the pair (cell index, volume-weighted
    /// mean of @p e over the cell's points), e evaluated at each point's
    /// temperature (the temperature of the cell it came from). Cells whose
    /// points all have the cell's temperature are left out: their mean is
    /// e(T) of the cell.
    std::vector<std::pair<std::uint32_t, double>>
    volume_mean_over_points(const std::vector<double>           &T,
                            const std::function<double(double)> &e) const;

    /// Zone tag per cell of the local box, from the states of its points:
    /// 0 gas (no points), 1 powder, 2 solid, 3 fluid (any fluid point).
    /// Without carried points from the cell's metal fraction @p alpha and
    /// temperature @p T: what the substrate's points would hold (solid,
    /// fluid above the solidus once temperatures passed to points).
    std::vector<double>
    zone_tags(const std::vector<double> &alpha,
              const std::vector<double> &T) const;

    /// The lattice spacing of the points ('Material points/Point
    /// spacing'), m.
    double
    point_spacing() const
    {
      return prm.point_spacing;
    }

    /// True if this scene carries points (Parameters::resolve_carry()).
    bool
    carried() const
    {
      return prm.carry_points;
    }

    const Particles::ParticleHandler<dim> &
    particle_handler() const
    {
      return handler;
    }
    /// Write access for the writers of the points' state: the flow and
    /// solid solvers, which update velocities, positions and stresses
    /// (call points_moved() after a point left its cell), and
    /// PointHeatExchange (their temperatures). Readers use
    /// particle_handler().
    Particles::ParticleHandler<dim> &
    particle_handler_for_update()
    {
      return handler;
    }
    types::particle_index
    n_global_points() const
    {
      return handler.n_global_particles();
    }
    unsigned int
    n_powder_grains() const
    {
      return n_grains;
    }
    double
    achieved_packing_fraction() const
    {
      return packing;
    }
    /// Checkpoint: every point with its id, cell, position, reference
    /// position and all properties, in the handler's order.
    void
    save_state(StateWriter &out) const;
    /// Replace the points by those saved (all saved ranks' parts): each
    /// rank keeps the points of its owned cells, in the saved order, so
    /// that sums over points repeat bit for bit. Collective.
    void
    load_state(std::vector<StateReader> &parts);

    /// Names of the first @p n properties, for output.
    static std::vector<std::string>
    property_names(const unsigned int n = PropertyIndex::n_properties);
    /// Names of the properties the points of this object carry.
    std::vector<std::string>
    used_property_names() const
    {
      return property_names(n_props);
    }

  private:
    Parameters   prm;
    unsigned int n_props;
    // See set_phase_change_drops_affine().
    bool                            drop_affine = false;
    const Material                 &mat;
    const BackgroundGrid<dim>      &grid;
    MappingQ1<dim>                  mapping;
    Particles::ParticleHandler<dim> handler;
    // Owned cells that hold points: flat index and iterator.
    std::vector<std::pair<std::uint32_t,
                          typename Triangulation<dim>::active_cell_iterator>>
      occupied;
    // Property arrays of the points in the pool, grouped by occupied cell:
    // points of occupied[c] are point_properties[cell_begin[c] ..
    // cell_begin[c+1]).
    std::vector<double *>      point_properties;
    std::vector<std::uint32_t> cell_begin;
    // Where the positions of the same points live in the pool (valid and
    // refreshed together with point_properties).
    std::vector<const Point<dim> *> point_locations;
    // Their pool handles (same order).
    std::vector<unsigned int> point_handles;
    // See layout_mark(): bumped by every full re-index of the cache; the
    // count of relocate_points() calls that moved points, and per local
    // cell the last such call that moved a point into or out of it.
    std::uint64_t layout_generation = 0;
    std::uint64_t relocations       = 0;
    // See point_moves() (collective, unlike the two above).
    std::uint64_t              moves_global = 0;
    std::vector<std::uint64_t> cell_moved_at;
    // Whether relocate_points() moved a point into or out of local cell
    // @p c since @p mark (same generation assumed).
    bool
    moved_since(const LayoutMark &mark, const std::uint32_t c) const
    {
      return mark.moves != relocations && cell_moved_at[c] > mark.moves;
    }
    // The count of cells_to_points() calls that changed a point's state,
    // and per local cell the last such call that did so there.
    std::uint64_t              state_events = 0;
    std::vector<std::uint64_t> cell_state_at;
    // Per local cell, the temperature cells_to_points() last gave its
    // points (NaN: not given since the cell's points changed).
    std::vector<double> pushed_temperature;
    // set_fixed_cells(), and metal_fraction()'s record of the cells whose
    // points stay put (the fixed cells, and cells of unmelted powder only):
    // the sub-cell bits and summed volume of their points and how many
    // points gave them (max: not binned yet, or not reusable because a
    // point lies outside the cell's box or may move), and the layout at
    // the end of the last binning (a powder cell's record holds while the
    // cell did not change since, cell_changed_since()).
    std::vector<std::uint8_t>          fixed_cell;
    mutable std::vector<std::uint64_t> binned_bits;
    mutable std::vector<double>        binned_volume;
    mutable std::vector<std::uint32_t> binned_count;
    mutable LayoutMark                 binned_mark;
    // cells_to_points()'s record for the fixed cells: per local cell the
    // temperature last passed and the highest one passed since the last
    // flush (NaN: nothing pending), and whether any cell has one.
    mutable std::vector<double> pending_temperature;
    mutable std::vector<double> pending_peak;
    // Fixed cells that went above the solidus (written at once since).
    std::vector<std::uint8_t> melted_fixed_cell;
    mutable bool              any_pending = false;
    // Flush the record of occupied_cells()[c] (if any) into its points.
    void
    flush_cell(const std::size_t c) const;
    // Without carried points: true once cells_to_points() was called (the
    // points' states would follow the cell temperatures from then on).
    bool temperatures_passed = false;
    void
    cache_point_handles();
    /// metal_fraction() without carried points: per direction, the
    /// sub-cells that the lattice points of the substrate (below its top)
    /// fall in, binned as metal_fraction() bins points; alpha of a cell is
    /// the product of the counts over n^dim.
    std::vector<double>
    lattice_fraction() const;
    /// Rebuild occupied (and the pointer cache) from the handler.
    void
    index_occupied_cells();
    /// After points moved between owned cells by remove and insert (no
    /// property-pool growth): refresh occupied and the pointer cache for
    /// the cells in @p changed (increasing) only, keeping the cached
    /// pointers of the other cells; a full rebuild if the pool moved.
    void
    refresh_occupied_cells(const std::vector<std::uint32_t> &changed);
    /// Append the lattice points of owned cell @p idx below
    /// @p vertical_limit that @p keep accepts (all if empty).
    void
    add_lattice_points(
      const std::uint32_t                                idx,
      const double                                       vertical_limit,
      const std::function<bool(const Point<dim> &)>     &keep,
      std::vector<std::pair<std::uint32_t, Point<dim>>> &points) const;
    /// metal_fraction() in cells with a fluid point: @p v the point volume
    /// per owned cell (turned into a fraction, excess spread), @p is_fluid
    /// 1 there (ghosts exchanged here); writes min(1, v) into @p alpha.
    void
    volume_fraction_of_fluid_cells(std::vector<double> &v,
                                   std::vector<double> &is_fluid,
                                   std::vector<double> &alpha) const;
    /// Insert (cell, position) pairs cell by cell at temperature @p T0.
    void
    insert_points(std::vector<std::pair<std::uint32_t, Point<dim>>> &points,
                  const double                                       T0,
                  const std::function<State(const Point<dim> &)>    &state_of);
    unsigned int n_grains = 0;
    double       packing  = 0;
  };
} // namespace femp

#endif
