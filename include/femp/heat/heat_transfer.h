// femp: HeatTransfer<dim>, the temperature equation (1) of the paper on the
// cell centres of the background grid:
//
//   rho c DT/Dt = div(lambda grad T) - alpha rho_m L_m Dgamma/Dt
//     - [q_evap(T) + h (T - T_ref) + sigma_SB eps (T^4 - T_ref^4)]
//       * 2 rho c / (rho_m c_m + rho_g c_g) |grad alpha| + q_laser
//
// Forward Euler in time, except the surface losses, which are taken fully
// implicitly in the cells that carry them (a local Newton iteration per
// surface cell); 5/7-point central differences with harmonic-mean
// face conductivities; first-order upwind convection with a cell-centred
// velocity (none unless a flow solver or a prescribed field provides one;
// in partly filled cells at the rate 1/alpha, the part above 1 implicit);
// latent heat by a local iteration per cell over the solid, mushy and liquid
// branches of the enthalpy relation (doc/method.md, "Heat transfer"); surface
// losses and the laser deposited through |grad alpha| with the density
// weighting above (the default 'first surface' laser only into the cells where
// the vertical beam first meets metal, shared in proportion to that weight).
// Cells without metal (alpha = 0) are not solved and carry no flux. The
// metal's heat capacity (and the metal share of the conductivity, at most
// alpha) is alpha's, or, where its keeper gives one (set_metal_fraction(),
// 'Metal of melt cells = points'), the metal mass of the cell's points.
#ifndef femp_heat_transfer_h
#define femp_heat_transfer_h

#include <deal.II/base/function_parser.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/tensor.h>

#include <femp/base/material.h>
#include <femp/base/parameter_table.h>
#include <femp/base/recoil_law.h>
#include <femp/grid/background_grid.h>
#include <femp/grid/cell_fields.h>
#include <femp/grid/metal_bodies.h>
#include <femp/heat/front_wall_piston.h>
#include <femp/heat/laser.h>
#include <femp/heat/metal_surface.h>
#include <femp/heat/ray_traced_absorption.h>

#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <utility>
#include <vector>

namespace femp
{
  using namespace dealii;
  class StateWriter;
  class StateReader;

  template <int dim>
  class HeatTransfer
  {
  public:
    struct Parameters
    {
      /// Uniform initial temperature, K; with a function expression its
      /// value at the lower corner of the domain (see check()).
      double initial_temperature = 300.;
      /// 'Initial temperature' given as a function of x, y (, z) (m);
      /// empty when it is a plain number.
      std::string initial_temperature_expression;
      double      reference_temperature  = 300.;
      double      convection_coefficient = 10.;
      /// 'Detached drops = sphere': a drop of at most detached_drop_cells
      /// metal cells (face-connected, no other metal face neighbour inside
      /// the domain) loses heat as a sphere of its metal volume (diameter
      /// d) in still gas: over the sphere's surface, the losses q(T) plus
      /// conduction with the coefficient Nu k_g/d, Nu = 2, k_g =
      /// Material/Gas thermal conductivity. false: off.
      bool detached_drops = false;
      /// 'Detached drop cells': the largest drop (in cells) that counts as
      /// detached; 1 to 4.
      unsigned int detached_drop_cells = 4;
      double       emissivity          = 0.4;
      /// zeta_q of eq. (1); the evaporation data are the Material's.
      double evaporation_coefficient = 0.82;
      /// 'Remove evaporated mass': the mass that evaporates from each
      /// surface cell (evaporated_mass()) is taken from the material
      /// points of that cell (PointHeatExchange::remove_evaporated_mass()),
      /// so that the surface recedes by m_dot/rho_m.
      bool remove_evaporated_mass = false;
      /// 'Front wall piston': the sub-cell film between a boiling surface
      /// and the melting front (FrontWallPiston); needs the recoil
      /// pressure, see enable_front_wall_piston().
      bool                          front_wall_piston = false;
      std::map<std::string, double> fixed_temperatures;
      /// How the laser's surface flux enters the cells.
      enum class Deposition
      {
        first_surface,
        gradient
      };
      Deposition  laser_deposition = Deposition::first_surface;
      std::string prescribed_velocity;
      /// points: the metal carries its enthalpy on the points; upwind:
      /// upwind convection of T with the flow's cell velocity.
      enum class Advection
      {
        points,
        upwind
      };
      Advection advection_by_melt_flow = Advection::points;
      /// With 'points': the metal whose heat a cell holding melt keeps
      /// (heat capacity, and the metal share of its conductivity): alpha,
      /// or the volume of its own points (alpha counts the excess volume
      /// of over-full neighbours, which their points carry).
      enum class MeltMetal
      {
        alpha,
        points
      };
      MeltMetal metal_of_melt_cells = MeltMetal::alpha;

      /// Declare (the members' values are the defaults) or read the

      /// entries, each listed once.

      void

      add_parameters(ParameterTable &table);

      static void
      declare_parameters(ParameterHandler &prm);
      void
      parse_parameters(ParameterHandler &prm);
      /// With a function expression for the initial temperature: evaluate
      /// it at every cell centre of the box [lower, upper] with cells of
      /// size h and refuse (InputError naming Heat transfer/Initial
      /// temperature) a value that is not finite and positive; sets
      /// initial_temperature to its value at the first cell.
      void
      check(const Point<dim> &lower, const Point<dim> &upper, const double h);
      /// The initial temperature at @p x, K.
      double
      initial_temperature_at(const Point<dim> &x) const;

    private:
      std::shared_ptr<FunctionParser<dim>> initial_function;
    };

    /// Cumulative energies since initialize(), J (2D: J/m).
    struct EnergyBudget
    {
      double laser       = 0; ///< deposited by the laser
      double evaporation = 0; ///< lost by evaporation
      double convection  = 0; ///< lost by surface convection
      double radiation   = 0; ///< lost by radiation
      double boundary    = 0; ///< entered through fixed-temperature faces
      /// Created by the upwind convection term (sum of rho c dT V over the
      /// cells): zero for a conservative scheme; not a loss, reported apart.
      double advection = 0;
      /// 'ray traced' only: beam energy sent (P dt summed over the steps
      /// with the laser on) and the part that left the domain after its
      /// reflections; laser + laser_escaped = laser_incident. Zero with
      /// the fixed absorptivity.
      double laser_incident = 0, laser_escaped = 0;
    };

    /// Total surface losses so far (global, collective), J (2D: J/m).
    double
    total_losses() const;

    HeatTransfer(const Parameters          &prm,
                 const Material            &material,
                 const Laser<dim>          &laser,
                 const BackgroundGrid<dim> &grid);

    /// Allocate the fields, set T to the initial temperature (a constant
    /// or a function of the cell centre), gamma from T.
    void
    initialize();

    /// Give the (owned) cell @p idx the temperature @p T_cell and the
    /// liquid fraction gamma(T_cell) of the enthalpy relation: for cells that
    /// gain metal from points (initial bodies, moved points), whose stored
    /// gamma is stale. Call update_ghosts() after the last one.
    void
    set_cell_temperature(const std::size_t idx, const double T_cell)
    {
      T[idx]     = T_cell;
      gamma[idx] = mat.liquid_fraction(T_cell);
    }
    /// Ghost values of T and gamma (collective).
    void
    update_ghosts()
    {
      grid.update_ghosts(T);
      grid.update_ghosts(gamma);
    }

    /// Freeze the temperature: advance() must not be called any more
    /// (Physics/Heat transfer = false), and set_metal_fraction() only stores
    /// alpha (no surface lists, no properties: no cost for heat).
    void
    freeze()
    {
      frozen = true;
    }
    bool
    is_frozen() const
    {
      return frozen;
    }

    /// New metal fraction (owned cells and ghosts) and its free surface
    /// @p surface, found from the same alpha (MetalSurface::update(), once
    /// per change, by alpha's keeper): the heat takes its lists of surface,
    /// first-surface and detached cells and renews the properties. With
    /// @p metal_mass (owned cells and ghosts, nonzero where alpha is), the
    /// metal's mass per cell over rho_m h^dim, which may differ from alpha
    /// (and exceed 1): the heat capacity and stored enthalpy of the metal
    /// take it, the metal share of the conductivity min(alpha, it);
    /// without it, alpha.
    void
    set_metal_fraction(const std::vector<double> &alpha,
                       const MetalSurface<dim>   &surface,
                       const std::vector<double> *metal_mass = nullptr);
    /// The same for a heat transfer used on its own (tests, studies): finds
    /// the free surface of @p alpha itself, with the detached drops of
    /// @p bodies (none when nullptr). Collective.
    void
    set_metal_fraction(const std::vector<double> &alpha,
                       const MetalBodies<dim>    *bodies     = nullptr,
                       const std::vector<double> *metal_mass = nullptr);

    /// The evaporative mass flux per unit surface at the surface
    /// temperature @p T_surface, kg/(m^2 s):
    ///   m_dot(T) = zeta_q p_0 sqrt(M/(2 pi R T)) exp[L_v M (T - T_v)/(R T
    ///   T_v)],
    /// so that the evaporation loss of eq. (1) is q_evap(T) = L_v m_dot(T)
    /// (0 with zeta_q = 0 or L_v = 0, and where the exponent is below -40).
    double
    evaporative_mass_flux(const double T_surface) const;

    /// The mass that left the surface by evaporation in the last advance(),
    /// per owned cell that gives it, kg (2D: kg/m). Each surface cell loses
    /// m_dot(T^{n+1}) W V dt with its loss weight W = w |grad alpha| (1/m),
    /// the same weight and temperature as the evaporation loss booked
    /// (energy = L_v times this mass); it passes that mass on to its outward
    /// face neighbour (along the dominant direction of its normal) when that
    /// one holds metal, up to 1/(2 dim + 1) of the neighbour's metal mass,
    /// so that the mass leaves the outermost metal. With the mass, the
    /// mass-weighted outward unit normal -grad alpha/|grad alpha| of the
    /// cells that gave it (zero where alpha's central difference vanishes,
    /// in detached drops).
    struct EvaporatedMass
    {
      std::uint32_t  index;
      double         mass;
      Tensor<1, dim> outward;
    };
    /// The cells of the last advance() that lost mass by evaporation, in
    /// increasing index; empty unless 'Remove evaporated mass' is on and
    /// the scene evaporates (zeta_q > 0, L_v > 0).
    const std::vector<EvaporatedMass> &
    evaporated_mass() const
    {
      return evaporated;
    }
    /// Whether advance() lists the evaporated mass (see evaporated_mass()).
    bool
    lists_evaporated_mass() const
    {
      return prm.remove_evaporated_mass && evap_pref > 0 &&
             mat.latent_heat_evaporation > 0;
    }

    /// Specific enthalpy of the metal at @p T_cell, J/kg: C(T) + L_m
    /// gamma(T), C the antiderivative of c_m (the relation of the
    /// phase-change iteration).
    double
    specific_enthalpy(const double T_cell) const;

    /// Heat carried by the points: each listed (owned) cell's metal takes
    /// the given mean specific enthalpy (J/kg) of the points now in it
    /// (MaterialPoints::volume_mean_over_points()); T and gamma follow from
    /// the enthalpy relation. Call after set_metal_fraction() with the new
    /// alpha. Ghosts are updated (collective).
    void
    take_point_enthalpy(
      const std::vector<std::pair<std::uint32_t, double>> &mean_e);

    /// Absorption model of the laser (subsection Laser): with 'ray traced'
    /// the laser's power is traced into the current metal surface
    /// (RayTracedAbsorption) instead of 'Absorptivity' times the flux on
    /// the first surface. Call after initialize(); 'fixed' changes nothing.
    void
    set_absorption_model(
      const typename RayTracedAbsorption<dim>::Parameters &absorption);
    /// 'Front wall piston = true': the film between a boiling surface and
    /// the melting front conducts with its own thickness
    /// (FrontWallPiston), with the recoil pressure of the melt flow
    /// (its coefficient zeta_p > 0, else an InputError naming Heat
    /// transfer/Front wall piston) and the laser's beam radius. Call after
    /// initialize(); does nothing when the option is off.
    void
    enable_front_wall_piston(const RecoilLaw &recoil);
    /// The piston model (nullptr when off).
    const FrontWallPiston<dim> *
    front_wall_piston() const
    {
      return piston.get();
    }
    /// True with 'Laser/Absorption model = ray traced'.
    bool
    ray_traced() const
    {
      return tracer != nullptr;
    }
    /// Ray traced: trace the beam at @p time into the current metal
    /// fraction; the next advance() from this time deposits the result
    /// (advance() traces itself if this was not called). Collective.
    void
    trace_laser(const double time);
    /// Ray traced: the outcome of the last trace (global, W or W/m).
    const typename RayTracedAbsorption<dim>::Result &
    last_trace() const
    {
      return trace_result;
    }

    /// Largest stable step for the current state (global), s: diffusion and
    /// convection (with the velocity of @p fields, see advance()), without
    /// safety factor.
    double
    stable_time_step(const CellFields<dim> &fields = CellFields<dim>());

    /// Advance T and gamma by one forward-Euler step of size @p dt from time
    /// @p time. Of @p fields only the cell velocity is read: with 'Advection
    /// by melt flow = upwind' it convects T (ghost values needed); without
    /// it (nullptr, or 'points') the 'Prescribed velocity' if given, else
    /// no convection. Throws if the state turns non-finite.
    void
    advance(const double           dt,
            const double           time,
            const CellFields<dim> &fields = CellFields<dim>());

    /// Cell temperature, K (its only writers are advance(),
    /// set_cell_temperature(), take_point_enthalpy() and load_state()).
    const std::vector<double> &
    temperature() const
    {
      return T;
    }
    const std::vector<double> &
    liquid_fraction() const
    {
      return gamma;
    }
    const std::vector<double> &
    metal_fraction() const
    {
      return alpha;
    }
    /// Laser flux density deposited per volume in the last step, W/m^3.
    const std::vector<double> &
    laser_source() const
    {
      return laser_density;
    }
    /// Cumulative energies, summed over all ranks (collective call).
    EnergyBudget
    energy_budget() const;
    /// Global stored enthalpy relative to T_ref (J, or J/m in 2D):
    /// sum V [alpha rho_m (int c_m dT + L_m gamma) + (1-alpha) rho_g c_g dT].
    double
    stored_enthalpy() const;
    /// Global maximum temperature over metal cells after the last step.
    double
    max_temperature() const
    {
      return T_max;
    }
    /// Stable step found during the last advance() (before safety factor).
    double
    last_stable_time_step() const
    {
      return dt_stable_next;
    }
    const Material &
    material() const
    {
      return mat;
    }
    /// T_ref of the stored enthalpy and the losses, K.
    double
    reference_temperature() const
    {
      return prm.reference_temperature;
    }

    /// Checkpoint: T (and the previous T, which gas cells keep), gamma and
    /// alpha of the owned cells, the energy accounts, the peak temperature
    /// and the stable step found in the last step.
    void
    save_state(StateWriter &out) const;
    /// Restore what save_state() wrote (all saved ranks' parts; collective):
    /// the surface lists and properties follow from alpha.
    void
    load_state(std::vector<StateReader> &parts);

    /// Number of cells that needed the phase-change iteration in the last
    /// step (local), for timing reports.
    std::size_t
    n_phase_change_cells() const
    {
      return n_phase_cells;
    }

  private:
    Parameters                 prm;
    const Material            &mat;
    const Laser<dim>          &laser;
    const BackgroundGrid<dim> &grid;
    /// Evaporation flux constants: q_evap = evap_pref / sqrt(T)
    /// exp(evap_exp (T - T_v) / T).
    const double evap_pref, evap_exp;

    std::vector<double> T, T_new, gamma, alpha, conductance, capacity, source;
    // The metal's mass per cell over rho_m h^dim (set_metal_fraction()):
    // alpha, or the volume of the points that carry the heat.
    std::vector<double>        mass;
    std::vector<std::uint8_t>  is_source;
    std::vector<std::uint32_t> source_cells;
    /// See evaporated_mass().
    std::vector<EvaporatedMass> evaporated;
    std::vector<std::size_t>    flagged_rows;
    /// Per x-row of the local box: 1 if any cell of the row holds metal.
    std::vector<std::uint8_t> row_has_metal;
    /// Laser density of the last step, W/m^3; surface-loss weight
    /// w |grad alpha| of the surface cells (0 elsewhere), 1/m.
    std::vector<double> laser_density, loss_weight;
    /// The lists of the last MetalSurface handed to set_metal_fraction():
    /// surface cells, first-surface cells, cells of detached drops.
    std::vector<typename MetalSurface<dim>::SurfaceCell>  surface;
    std::vector<typename MetalSurface<dim>::LaserCell>    first_surface;
    std::vector<typename MetalSurface<dim>::DetachedCell> detached;
    /// gas_h of the detached cells per cell of the local box, 0 elsewhere
    /// (empty when Detached drops = off).
    std::vector<double> gas_coefficient;
    /// 'Prescribed velocity' (empty arrays when none).
    std::array<std::vector<double>, dim> prescribed;
    /// The velocity that convects T in a step with @p fields (see
    /// advance()); nullptr: none.
    const std::array<std::vector<double>, dim> *
    convection_velocity(const CellFields<dim> &fields) const;

    struct FixedFace
    {
      std::uint32_t index;
      double        value;
    };
    std::vector<FixedFace> fixed_faces;

    /// Ray-traced absorption (nullptr: the fixed model), its deposits
    /// (owned cell, W) for the time traced_time, the cells that took the
    /// last step's deposits, the outcome of the last trace.
    std::unique_ptr<RayTracedAbsorption<dim>>     tracer;
    std::vector<std::pair<std::uint32_t, double>> ray_deposits;
    std::vector<std::uint32_t>                    ray_cells;
    double                                        traced_time = -1;
    bool                                          traced      = false;
    typename RayTracedAbsorption<dim>::Result     trace_result;
    /// Ray traced: the deposits of the trace at @p time into the sources
    /// of this step; returns their sum over the owned cells, W/m^3 summed.
    double
    deposit_traced_laser(const double time, const double dt);

    /// Front wall piston (nullptr: off).
    std::unique_ptr<FrontWallPiston<dim>> piston;

    bool         frozen = false;
    EnergyBudget budget;
    double       T_max          = 0;
    double       dt_stable_next = 0;
    std::size_t  n_phase_cells  = 0;
    /// The lowest temperature a stable step can produce: the lowest metal
    /// temperature when the first step starts, the reference (ambient)
    /// temperature and the fixed-face temperatures (NaN before the first
    /// step). Conduction, the implicit surface losses and the mixing of
    /// moved points are convex in T, so no metal cell may fall below it.
    double T_floor = std::numeric_limits<double>::quiet_NaN();
    /// Set T_floor from the current state (collective).
    void
    set_temperature_floor();
    /// Stop the run (CollectiveError) if the lowest metal temperature
    /// @p T_min after the step is below T_floor: the explicit step broke the
    /// discrete maximum principle, which the latent heat can otherwise
    /// hide as a bounded, wrong checkerboard. Collective.
    void
    check_temperature_floor(const double T_min,
                            const double dt,
                            const double time) const;
    /// What the passes of advance() hand on to each other.
    struct StepSums
    {
      double      rate_max    = 0; ///< largest rate (1/stable step), 1/s
      double      box_max     = 0; ///< pass B: peak new T over metal cells, K
      double      box_min     = 0; ///< pass B: lowest new T over metal cells, K
      double      box_bad     = 0; ///< pass B: NaN when a new T is not finite
      double      e_boundary  = 0; ///< through fixed faces in the step, J
      double      e_advection = 0; ///< convection, W/m^3 summed over cells
      double      e_evap = 0, e_conv = 0, e_rad = 0; ///< losses, W/m^3 sums
      std::size_t nphase = 0; ///< cells of the local enthalpy iteration
    };
    /// The passes of advance(), in this order.
    /// Properties of the x-rows [first_row, first_row + n_rows) with metal.
    void
    properties_of_rows(const std::size_t first_row, const std::size_t n_rows);
    /// Pass B: explicit conduction of all metal rows into T_new; flags the
    /// rows for pass D.
    void
    conduction_pass(const double dt, StepSums &sums);
    /// Fixed-temperature faces: their flux into the sources.
    void
    fixed_face_pass(const double dt, StepSums &sums);
    /// Upwind convection with the velocity field @p u (nullptr: none).
    void
    convection_pass(const double                                dt,
                    const std::array<std::vector<double>, dim> *u,
                    StepSums                                   &sums);
    /// Pass C: the cells with sparse sources (laser, surface losses, fixed
    /// faces), surface losses implicit.
    void
    source_pass(const double dt, StepSums &sums);
    /// Pass D: the local enthalpy iteration in the flagged rows.
    void
    phase_change_pass(StepSums &sums);
    /// Reset the sources, book the energies, T_max, swap and exchange T,
    /// the next stable step; diagnostic when T is not finite.
    void
    finish_step(const double dt, const double time, const StepSums &sums);

    void
    compute_properties();
    /// Properties of the flat index range [begin, end) of the box.
    void
    compute_properties(const std::size_t begin, const std::size_t end);
    /// True if a cell going from @p Tc to @p Tn needs the local enthalpy
    /// iteration: it may change phase, or c(T) varies over a large step.
    bool
    needs_local_solve(const double Tc,
                      const double Tn,
                      const double g,
                      const double rhoL,
                      const bool   variable_c) const
    {
      const bool phase = rhoL > 0 && !((Tn < mat.solidus && g == 0.) ||
                                       (Tn > mat.liquidus && g == 1.));
      return phase || (variable_c && std::abs(Tn - Tc) > 1.);
    }
    void
    compute_surface_sources(const double dt, const double time);
    /// Enthalpy per volume of a cell with metal mass fraction @p m (the
    /// metal's mass over rho_m h^dim) and gas fraction @p g at @p T.
    double
    enthalpy_density(const double m, const double g, const double T) const;
    /// Surface loss flux q_evap + q_conv + q_rad at @p T (W/m^2), its parts
    /// and its derivative dq/dT; @p gas_h (W/(m^2 K)) is added to the
    /// convection coefficient (the gas conduction of a detached cell).
    void
    surface_loss(const double T,
                 double      &q_evap,
                 double      &q_conv,
                 double      &q_rad,
                 double      &dq_dT,
                 const double gas_h = 0) const;
    /// Pass each cell's evaporated mass on to its outward metal neighbour
    /// (see the source); collective.
    void
    evaporated_mass_outward();
    /// Outward unit normal -grad alpha/|grad alpha| of owned cell @p idx
    /// (central differences; zero where the difference vanishes).
    Tensor<1, dim>
    outward_normal(const std::size_t idx) const;
    /// New temperature of a cell with metal fraction @p a that starts from
    /// @p Tc, gamma @p gc and receives the explicit enthalpy change @p dH
    /// (J/m^3) and loses dtW q(T) with the loss q at the new temperature
    /// (fully implicit; dtW = dt w |grad alpha|): solves
    ///   H(T) - H(Tc) + dtW q(T) = dH,
    /// with the enthalpy H of the tables (latent heat included) if
    /// @p enthalpy, else H(T) - H(Tc) = rc (T - Tc).
    double
    solve_cell(const double m,
               const double g,
               const double Tc,
               const double gc,
               const double rc,
               const double dH,
               const double dtW,
               const bool   enthalpy,
               const double guess,
               const double gas_h = 0) const;
    double
    heat_capacity(const double T, const double a) const
    {
      return a * mat.density * mat.specific_heat.value(T) +
             (1 - a) * mat.gas_density * mat.gas_specific_heat;
    }
  };
} // namespace femp

#endif
