// femp: melt-pool flow by the improved incompressible material point method
// (paper sec. 2.3, eqs. 3-4; doc/method.md, "Melt flow"; ref. [11]).
//
// Fluid material points carry mass and velocity; each fluid step maps them
// to the nodes of the background grid (P2G, bilinear/trilinear tent
// weights), predicts the nodal velocity with gravity, viscosity (explicit)
// and the Darcy damping of the mushy zone (implicit),
//   u* = (u + dt f/rho) / (1 + dt K_c (1-gamma)^2 / ((gamma^3 + eps0) rho)),
// solves the pressure Poisson equation div(dt/rho grad p) = div u* on the
// centres of the fluid cells (5-point/7-point stencil, CG + Trilinos ML
// AMG; rows over a band of cells round the fluid, so that the graph and the
// hierarchy are reused while the fluid stays inside the band), corrects the
// nodal velocity u = u* - dt/rho grad p, and updates the points with a FLIP/PIC
// blend before moving them with the nodal velocity (explicit advection).
// With Melt flow/Velocity transfer = APIC (affine particle-in-cell, Jiang et
// al. 2015, with the D_p of multilinear weights) each fluid point
// carries the affine velocity C_p instead: P2G scatters
// m_p (v_p + C_p (x_i - x_p)), G2P sets v_p = sum w u_i and
// C_p = sum u_i (grad w_ip)^T, which equals B_p D_p^-1 for tent weights.
// Optionally (Melt flow/Volume correction) the points are also moved by
// grad(psi), lap(psi) = c (V_c/h^dim - 1) with psi = 0 at the free surface, so
// that bunched points spread again and the fluid volume of the cells is kept
// (doc/flow.md, "Volume correction").
//
// Surface tension enters through the free-surface condition: the Dirichlet
// pressure on the faces between fluid and gas cells is the capillary
// pressure p_s = sigma div(n) (n the outward normal of the smoothed metal
// fraction alpha, doc/method.md, "Melt flow"), the sharp-interface form of the
// CSF term sigma kappa n |grad alpha| of eq. (3); the recoil pressure p_r =
// zeta_p p0 exp[L_v M (T - T_v)/(R T T_v)] adds to it. The Marangoni stress
// dsigma/dT (grad T - (n.grad T) n) is a traction on the faces between fluid
// and gas cells, each face weighted by |n_d| so that the staircase of faces
// carries the area of the smoothed interface; it is spread to the face's nodes.
//
// The step reads P2G -> free surface -> predictor -> pressure -> correction
// -> G2P; the free-surface terms are computed by FreeSurface
// (free_surface.h), the pressure system is assembled and solved by
// PressureSolver (pressure_solver.h).
#ifndef femp_incompressible_flow_h
#define femp_incompressible_flow_h

#include <deal.II/base/conditional_ostream.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/tensor.h>
#include <deal.II/base/timer.h>

#include <femp/base/material.h>
#include <femp/base/parameter_table.h>
#include <femp/flow/flow_cells.h>
#include <femp/flow/free_surface.h>
#include <femp/flow/front_wall_expulsion.h>
#include <femp/flow/front_wall_film.h>
#include <femp/flow/pressure_solver.h>
#include <femp/flow/surface_tension.h>
#include <femp/grid/background_grid.h>
#include <femp/grid/cell_fields.h>
#include <femp/grid/material_points.h>

#include <array>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

namespace femp
{
  using namespace dealii;
  class StateWriter;
  class StateReader;

  template <int dim>
  class IncompressibleFlow
  {
  public:
    struct Parameters
    {
      double viscosity = 6e-3; ///< mu, Pa s
      /// g, m/s^2 (default: -9.81 vertical); not an input of Melt flow:
      /// FempProblem sets it from Physics/Gravity.
      Tensor<1, dim> gravity;
      double         darcy_constant = 1e8;  ///< K_c, kg/(m^3 s)
      double         darcy_epsilon  = 1e-3; ///< eps0, -
      double         flip_fraction  = 0.95; ///< beta of the FLIP/PIC blend
      /// How the fluid points exchange velocities with the grid nodes
      /// (Melt flow/Velocity transfer).
      enum class VelocityTransfer
      {
        flip_pic, ///< v_p <- beta (v_p + sum w du) + (1 - beta) sum w u
        apic      ///< affine particle-in-cell: v_p and C_p from the nodes
      };
      VelocityTransfer velocity_transfer = VelocityTransfer::flip_pic;
      /// Whether the points carry the affine velocity C_p (APIC).
      bool
      affine() const
      {
        return velocity_transfer == VelocityTransfer::apic;
      }
      double cfl = 0.25; ///< convective Courant number
      /// Fraction of the capillary limit used by the automatic step (the
      /// surface tension is explicit; see doc/flow.md, oscillating droplet).
      double capillary_fraction = 0.5;
      /// Prescribed fluid step, s (0: automatic, the smallest limit).
      double time_step = 0;
      /// A of the point shifting delta x = -A h |u| dt grad(alpha) (Skillen
      /// et al. form; 0: off; tangential only near the free surface).
      double point_shifting = 0;
      /// Passes of the curvature smoothing along the surface (0: none).
      unsigned int curvature_smoothing = 0;
      /// How the curvature is computed (Melt flow/Curvature).
      typename FreeSurface<dim>::Parameters::Curvature curvature =
        FreeSurface<dim>::Parameters::Curvature::alpha_gradient;
      /// Relaxation c of the volume correction (0: off): the points move,
      /// besides their advection, by grad(psi) with lap(psi) = c (V_c/h^dim
      /// - 1), V_c the point volume in the cell (doc/flow.md).
      double volume_correction = 0;
      /// Sub-cell slip of the recoil-driven melt film on solid walls
      /// (Melt flow/Front wall film; FrontWallFilm, doc/flow.md).
      bool front_wall_film = false;
      /// Sub-cell expulsion of the melt from boiling surface cells at the
      /// Bernoulli speed of their recoil (Melt flow/Front wall expulsion;
      /// FrontWallExpulsion, doc/flow.md); needs
      /// enable_front_wall_expulsion().
      bool   front_wall_expulsion     = false;
      double surface_tension          = 0; ///< sigma, N/m (0: off)
      double surface_tension_gradient = 0; ///< dsigma/dT, N/(m K)
      /// The law of dsigma/dT (Melt flow/Surface tension model) and the
      /// constants of its surfactant model (Melt flow/Surfactant).
      SurfaceTension::Model surface_tension_model =
        SurfaceTension::Model::linear;
      SurfaceTension::Surfactant surfactant;
      /// zeta_p (0: no recoil); the evaporation data are the Material's.
      double recoil_coefficient = 0;
      /// The surface temperature of the recoil (Melt flow/Recoil
      /// temperature).
      typename FreeSurface<dim>::Parameters::RecoilTemperature
        recoil_temperature =
          FreeSurface<dim>::Parameters::RecoilTemperature::limited;
      /// The recoil net of the ambient pressure (Melt flow/Recoil above
      /// ambient; the default).
      bool recoil_above_ambient = true;
      /// Tolerance, iteration limit and preconditioner of the pressure
      /// solve.
      typename PressureSolver<dim>::Parameters pressure;

      Parameters();
      /// Declare (the members' values are the defaults) or read the
      /// entries, each listed once.
      void
      add_parameters(ParameterTable &table);
      static void
      declare_parameters(ParameterHandler &prm);
      void
      parse_parameters(ParameterHandler &prm);
      /// Refuse (InputError naming Melt flow/Time step) a prescribed step
      /// above the viscous or the capillary limit of cells of size @p h
      /// and density @p rho; called before any work.
      void
      check_time_step(const double h, const double rho) const;
      /// The parameters of the free surface (surface tension, Marangoni,
      /// recoil, curvature smoothing).
      typename FreeSurface<dim>::Parameters
      surface_parameters() const;
    };

    /// Cell classes used by the flow (cell_type()).
    enum CellType : int
    {
      gas = flow_cells::gas, ///< no metal point: free surface beyond, p = 0
      solid =
        flow_cells::solid, ///< metal points but none fluid: rigid, no-slip
      fluid = flow_cells::fluid, ///< at least one fluid point: pressure unknown
      outside = flow_cells::outside ///< beyond the domain: free-slip wall
    };

    /// Stable step limits, s (each is reported by the caller).
    struct StepLimits
    {
      double convective;             ///< cfl h / max(u_max, sqrt(|g| h))
      double viscous;                ///< h^2 rho / (2 dim mu)
      double capillary;              ///< sqrt(rho h^3 / (2 pi sigma))
      double capillary_fraction = 1; ///< of the capillary limit, automatic step
      /// The automatic step: min(convective, viscous, fraction x capillary).
      double
      min() const
      {
        return std::min(std::min(convective, viscous),
                        capillary_fraction * capillary);
      }
      /// Which limit gives min(): 0 convective, 1 viscous, 2 capillary.
      unsigned int
      governing() const
      {
        const double m = min();
        return m == convective ? 0 : (m == viscous ? 1 : 2);
      }
    };

    /// The viscous and capillary limits of cells of size @p h (no
    /// convective limit: infinity).
    static StepLimits
    material_limits(const Parameters &prm, const double h, const double rho);

    struct Statistics
    {
      unsigned int steps = 0;
      unsigned int matrix_rebuilds =
        0; ///< band numbering + matrix graph builds
      unsigned int  amg_setups      = 0; ///< AMG hierarchy builds
      unsigned long cg_iterations   = 0; ///< total over all steps
      unsigned int  last_iterations = 0;
      unsigned int  max_iterations  = 0;
      unsigned int  resorts         = 0; ///< steps in which points changed cell
      /// of these, steps that needed deal.II's sort of all points (~0.5 us
      /// per point): a point beyond the ghost layer
      unsigned int  global_sorts      = 0;
      unsigned int  halvings          = 0; ///< steps redone as two halves
      double        max_point_speed   = 0; ///< m/s, after the last step
      unsigned long n_fluid_cells     = 0; ///< global, last step
      unsigned long volume_iterations = 0; ///< CG, volume correction, total
      unsigned int  volume_skipped    = 0; ///< volume solves not converged
      /// Melt flow/Front wall expulsion: expelling cells summed over the
      /// fluid steps (global), fluid steps with at least one, and the
      /// largest Bernoulli speed imposed, m/s.
      unsigned long expelling_cell_steps = 0;
      unsigned int  expelling_steps      = 0;
      double        max_expulsion_speed  = 0;
    };

    /// The fluid step limits over the run: the smallest of each, how
    /// many sub-steps each governed (convective, viscous, capillary,
    /// prescribed), the sub-steps per temperature step and the idle
    /// temperature steps (advance_over()).
    struct SubcycleRecord
    {
      double convective         = std::numeric_limits<double>::infinity();
      double viscous            = std::numeric_limits<double>::infinity();
      double capillary          = std::numeric_limits<double>::infinity();
      double capillary_fraction = 1;
      std::array<unsigned long, 4> governed{};
      unsigned int min_substeps = std::numeric_limits<unsigned int>::max();
      unsigned int max_substeps = 0;
      /// Temperature steps without a flow step: no fluid cell at the last
      /// flow step and no metal above the solidus.
      unsigned long idle_steps = 0;

      /// Book the limits @p l of one fluid sub-step; @p prescribed: the
      /// step was Melt flow/Time step.
      void
      record(const StepLimits &l, const bool prescribed)
      {
        convective         = std::min(convective, l.convective);
        viscous            = std::min(viscous, l.viscous);
        capillary          = std::min(capillary, l.capillary);
        capillary_fraction = l.capillary_fraction;
        ++governed[prescribed ? 3 : l.governing()];
      }
      /// Book the number of sub-steps of one temperature step.
      void
      record_substeps(const unsigned int n)
      {
        min_substeps = std::min(min_substeps, n);
        max_substeps = std::max(max_substeps, n);
      }
    };

    /// What the sub-cycle of advance_over() takes from the run.
    struct SubcycleControl
    {
      /// 'Run limits/Maximum flow sub-steps' per temperature step.
      unsigned int max_substeps = 100000;
      /// The run's wall clock, s (a long sub-cycle reports every 30 s).
      std::function<double()> wall_time;
      /// Where a long sub-cycle reports (null: nowhere).
      ConditionalOStream *log = nullptr;
    };

    IncompressibleFlow(const Parameters          &prm,
                       const Material            &material,
                       const BackgroundGrid<dim> &grid,
                       MaterialPoints<dim>       &points,
                       TimerOutput               *timer = nullptr);

    /// Limits from the current point velocities (collective).
    StepLimits
    stable_time_step() const;

    /// One fluid step of length @p dt. Refuses a step above the viscous or
    /// capillary limit; a step whose new nodal speed would move points more
    /// than a cell is redone as two halves (at most 2^20 pieces); stops with
    /// a diagnostic when the solution becomes non-finite. Of @p fields it
    /// reads (ghost values needed):
    ///  - the liquid fraction gamma for the Darcy term; nullptr: gamma = 1
    ///    everywhere (no damping);
    ///  - the temperature for the Marangoni stress and the recoil pressure;
    ///    required when either is switched on.
    void
    step(const double dt, const CellFields<dim> &fields = CellFields<dim>());
    /// The flow over the temperature step [@p time, @p time + @p dt]:
    /// sub-cycled in equal pieces, each at most the current stable step
    /// (or 'Melt flow/Time step'), the last one ending with the
    /// temperature step; the limits are booked in subcycle_record().
    /// Skipped (an idle step) when the last flow step had no fluid cell and
    /// @p may_melt says that no metal is above the solidus (empty: always
    /// flow). Stops (collective InputError) after more than
    /// @p control.max_substeps sub-steps. Returns true if points changed
    /// cells.
    bool
    advance_over(const double                 time,
                 const double                 dt,
                 const CellFields<dim>       &fields,
                 const std::function<bool()> &may_melt,
                 const SubcycleControl       &control);
    /// The sub-cycle bookkeeping over the run (checkpoint: set it back).
    const SubcycleRecord &
    subcycle_record() const
    {
      return subcycles;
    }
    void
    set_subcycle_record(const SubcycleRecord &r)
    {
      subcycles = r;
    }

    /// step() without the refusal of a step above the viscous or capillary
    /// limit (the step rejection and the non-finite check remain): for the
    /// forced-step experiments of doc/stability.md only.
    void
    forced_step(const double           dt,
                const CellFields<dim> &fields = CellFields<dim>())
    {
      advance(dt, 0, fields);
    }

    /// Pressure per cell of the local box (ghosts exchanged), Pa; zero
    /// outside fluid cells.
    const std::vector<double> &
    pressure() const
    {
      return p_cell;
    }
    /// Capillary pressure p_s = sigma div(n) of the free-surface cells
    /// (ghosts exchanged), Pa; zero elsewhere or when sigma = 0.
    const std::vector<double> &
    surface_pressure() const
    {
      return surface.surface_pressure();
    }
    /// Cell type per cell of the local box (as double, ghosts exchanged).
    const std::vector<double> &
    cell_type() const
    {
      return type;
    }
    /// Cell-centred fluid velocity (mean of the nodes of fluid cells, zero
    /// elsewhere, ghosts exchanged): CellFields::velocity.
    const std::array<std::vector<double>, dim> &
    cell_velocity() const
    {
      return u_cell;
    }
    const Statistics &
    statistics() const
    {
      return stats;
    }
    /// The fluid cells of the pressure systems (one per fluid sub-step, a
    /// halved step two) summed since this object was made (not saved in
    /// checkpoints): over all ranks (@p all), of the rank that owns the
    /// most in each system (@p busiest) and of this rank (@p own). Their
    /// ratios over a window are the flow's balance over the ranks
    /// (layer_cost.csv, doc/performance.md "Balancing the ranks").
    struct FluidLoad
    {
      double all = 0, busiest = 0, own = 0;
    };
    const FluidLoad &
    fluid_load() const
    {
      return load;
    }
    /// Recoil-driven surface cells of the last fluid step (Melt
    /// flow/Front wall film or Front wall expulsion; 0 when both are off),
    /// over all ranks. Collective.
    unsigned long
    recoil_driven_cells() const;
    /// 'Front wall expulsion = true': set up FrontWallExpulsion with the
    /// laser's beam radius @p spot_radius (m) and the temperature of the
    /// solid far ahead @p T_far (K), which its film thickness needs. Does
    /// nothing when the option is off; refuses a zero recoil coefficient.
    void
    enable_front_wall_expulsion(const double spot_radius, const double T_far);
    /// Whether Front wall expulsion is set up.
    bool
    expels() const
    {
      return expulsion != nullptr;
    }

    /// Forces of the fluid on the faces of the solid cells (eq. 13, "fluid
    /// forces"; doc/solid.md "Flow and solid together") from the state of
    /// the last step: for every owned cell of type solid and each of its
    /// faces to a fluid cell (owned or ghost),
    ///  - pressure: the face pressure p_n - s (h/2) rho g_d (the centre
    ///    pressure of the fluid neighbour extrapolated with the
    ///    wall-normal gradient rho g of a rigid wall; d the face direction,
    ///    s = +-1 the side of the fluid) times the face area, pushing into
    ///    the solid;
    ///  - viscous shear: mu u_t / (h/2) times the face area, u_t the
    ///    tangential part of the neighbour's cell-centre velocity (no-slip
    ///    wall, linear profile).
    /// @p F[dim * (2 d + side) + e]: component e of the force through face
    /// (d, side) (side 1: the upper face), one cell field over the local box
    /// each, N (2D: N/m); zero elsewhere. @p cells: on entry the cells
    /// where @p F may be non-zero (those of the last call: only they are
    /// reset, unless @p F is resized), on return the owned cells written
    /// now, increasing (a few cells at the melt's edge, not the grid).
    void
    fluid_forces_on_solid(std::array<std::vector<double>, 2 * dim * dim> &F,
                          std::vector<std::uint32_t> &cells) const;

    /// Checkpoint: the cell pressure, velocity and types of the last step
    /// (the temperature step and the fluid forces read them) and the
    /// statistics (the largest point speed sets the next step). Saving
    /// also restarts the pressure solver: the next step numbers the system
    /// and builds the preconditioner afresh, as a resumed run does, so
    /// that both continue bit for bit.
    void
    save_state(StateWriter &out);
    void
    load_state(std::vector<StateReader> &parts);

  private:
    /// The step proper (P2G, free surface, predictor, pressure,
    /// correction, G2P); redone as two halves (recursively, @p depth) when
    /// the new nodal speed would move a point more than a cell.
    void
    advance(const double           dt,
            const unsigned int     depth,
            const CellFields<dim> &fields);
    /// P2G: classify_cells() and transfer_to_grid().
    void
    particles_to_grid();
    void
    classify_cells();
    void
    transfer_to_grid();
    /// FreeSurface::update() for the current cells and temperature @p T.
    void
    update_free_surface(const std::vector<double> *T);
    /// u*; @p gamma: the liquid fraction of the Darcy term (nullptr: 1).
    void
    predictor(const double dt, const std::vector<double> *gamma);
    /// Stop the run (CollectiveError) if the explicit viscous update of
    /// the step @p dt would raise the kinetic energy (beyond round-off): the
    /// step is above the stable limit. Collective; after the viscous
    /// forces are summed.
    void
    check_viscous_energy(const double dt) const;
    /// The fluid cells as the pressure solver sees them.
    typename PressureSolver<dim>::FluidCells
    fluid_cell_set() const;
    /// div u* per owned fluid cell (divergence).
    void
    velocity_divergence();
    void
    pressure_solve(const double dt);
    /// The solver's counters into stats.
    void
    copy_solver_statistics();
    void
    correction(const double dt);
    /// Largest nodal speed |u| over the active nodes (collective), m/s;
    /// infinite where any rank has a non-finite nodal velocity.
    double
    max_nodal_speed() const;
    /// Stop the run (CollectiveError) naming a grid node with a
    /// non-finite velocity after the step @p dt. Collective.
    [[noreturn]] void
    stop_non_finite_velocity(const double dt) const;
    /// u_cell: mean of the nodes of the fluid cells.
    void
    update_cell_velocity();
    /// Volume correction (Melt flow/Volume correction; nothing when off):
    /// solve lap(psi) = c (V_c/h^dim - 1) on the fluid cells with psi = 0
    /// at the free surface (same matrix and preconditioner as the
    /// pressure), so that grid_to_points() can move the points by
    /// grad(psi).
    void
    volume_solve();
    /// Displacement grad(psi) normal to the 2 dim faces of @p cell (face
    /// 2d+side, m): zero on walls and solid faces, the ghost-fluid value on
    /// gas faces.
    void
    volume_faces(const std::size_t cell, double *G) const;
    /// G2P: FLIP/PIC (or APIC) update of the point velocities and
    /// advection.
    void
    grid_to_points(const double dt);

    /// Point shifting (doc/flow.md, "Point shifting"): the data of one
    /// fluid cell for shift_of_point().
    struct ShiftCell
    {
      std::array<double, (1u << dim)> alpha; ///< nodal alpha, mirrored at walls
      bool                            near_surface = false;
      std::array<double, dim>         normal{}; ///< unit, when near_surface
    };
    ShiftCell
    shift_cell(const std::size_t cell) const;
    /// Displacement of a point at reference coordinates @p xi of the cell
    /// moving at @p speed during @p dt: -A h speed dt grad(alpha), its
    /// normal component removed near the free surface, at most h/4.
    void
    shift_of_point(const ShiftCell &sc,
                   const double    *xi,
                   const double     speed,
                   const double     dt,
                   double          *dx) const;

    /// Wall conditions on the active nodes: no-slip next to solid cells,
    /// free slip (zero normal component) on the domain boundary; with
    /// Melt flow/Front wall film, slip along the wall on the film nodes.
    void
    apply_boundary_conditions(std::array<std::vector<double>, dim> &u) const;

    Parameters                 prm;
    const Material            &mat;
    const double               rho;
    const BackgroundGrid<dim> &grid;
    MaterialPoints<dim>       &points;
    TimerOutput               *timer;

    static constexpr unsigned int         n_corners = 1u << dim;
    std::array<std::ptrdiff_t, n_corners> corner_offset; // node offsets
    std::array<std::ptrdiff_t, n_corners> around_offset; // cells round a node
    std::vector<std::ptrdiff_t> stencil; // 3^dim neighbourhood offsets
    std::array<std::array<double, n_corners>, n_corners>
      stiffness; // Q1 Laplace

    FreeSurface<dim>    surface;
    PressureSolver<dim> pressure_solver;

    std::vector<double> type, type_old, p_cell;
    std::vector<double> mass, volume;
    std::vector<double> occupancy, psi; // point volume per cell, m^dim; psi/h^2
    std::array<std::vector<double>, dim> mom, u_old, u_new, force, u_cell;
    std::vector<std::uint32_t>           active; // nodes of fluid cells
    std::vector<std::uint32_t> active_cell;      // cell whose corner 0 it is
    std::vector<std::uint8_t>  node_mark;        // in active
    std::vector<std::uint8_t>  node_fix;         // bit d: u_d = 0
    std::vector<std::uint32_t> fluid_cells;      // owned fluid cells
    // Where the points stood at the last classify_cells() (false: none
    // yet, or the points were loaded since): cells with no fluid point
    // then and no change of their points since are skipped.
    typename MaterialPoints<dim>::LayoutMark classified_at;
    bool                                     classified = false;
    std::vector<double>                      divergence; // per owned fluid cell
    std::vector<double>
      cell_dissipation; // mu u^T K u per owned fluid cell, W (W/m in 2D)
    std::vector<double> volume_source; // -c e per owned fluid cell
    /// Melt flow/Front wall film (only when on): the film nodes and the
    /// recoil-driven surface cells of this step.
    std::optional<FrontWallFilm<dim>> film;
    std::vector<double>               recoil_driven;
    /// Melt flow/Front wall expulsion (only when enabled).
    std::unique_ptr<FrontWallExpulsion<dim>> expulsion;

    Statistics     stats;
    FluidLoad      load;
    SubcycleRecord subcycles;
    /// Wall time (s) after which a long sub-cycle reports.
    double next_substep_report = 30;
  };
  /// The name of the flow's step limit with index @p governing (0
  /// convective, 1 viscous, 2 capillary) and the parameter that sets it,
  /// for messages.
  std::string
  flow_limit_name(const unsigned int governing);
} // namespace femp

#endif
