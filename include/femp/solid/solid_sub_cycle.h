// femp: SolidSubCycle<dim>, the solid of the macro step (doc/method.md,
// "Solid" and "Macro time step", paper eqs. 5-17): material points (SolidMPM)
// and finite elements (SolidFEM) coupled through the background-grid nodes,
// sub-cycled against the temperature step, with its energy balance and
// mass scaling.
//
// Coupling (eqs. 14-17). The FE mesh is its own triangulation, aligned
// with the grid (solid_fem.h), so a transition node i coincides with a grid
// node I and N_Ii = 1. The two meshes are partitioned independently: the
// rank owning an FE element need not own the grid cells around its
// transition nodes. Each step:
//   1. point mass, momentum and forces to the grid (eqs. 11-13), partial
//      sums of this rank, on the grid nodes of MPM cells only;
//   2. one MPI_Allreduce of a buffer over all transition nodes (numbered
//      globally from geometry): this rank's partial grid mass, momentum and
//      force there (before the grid's shared-node sum), its FE elements'
//      internal force without hourglass part (eq. 9, gravity included) and
//      its hourglass force. Every rank then has the totals and computes the
//      same grid velocity and acceleration at every transition node
//      (m = m_grid + m_FE, p = p_grid + m_FE v_i + dt f, eq. 14-16) and the
//      new FE velocity v_i = v_I + dt f_i^HG / m_i (eq. 17, hourglass force
//      added back locally);
//   3. grid momentum update elsewhere (MPM nodes), FE central-difference
//      update elsewhere (FE nodes, eq. 10; nodal sums over ranks through
//      deal.II's distributed vector); points: FLIP velocity and position;
//   4. MUSL re-map of the point momenta; at transition nodes the FE momentum
//      m_FE v_i (known on every rank) is added;
//   5. stresses at points (grid velocities) and, in one fused element loop,
//      at Gauss points (FE node velocities) together with the element forces
//      of the next step; eq. 5 with the cell temperatures of eq. 2.
// Interior FE nodes never touch the grid: the FE costs no per-step work on
// grid nodes. Without material points the grid work of a step is empty.
// Time stepping. The solid keeps its own time t_s and step
//   dt_s = C h / (sqrt(dim) c),  c = sqrt(M_max / (s rho)),
// (C: safety factor; M_max: largest P-wave modulus of the E(T) table;
// s: mass-scaling factor; fixed, or with Solid/Mass scaling = adaptive
// set after each advance from the ratio of the mean kinetic energy of its
// steps to the stored elastic energy, velocities kept and the kinetic
// energy jump booked: doc/speed_accuracy.md, section 3). advance(t) is called
// after every temperature step and takes whole solid steps up to t; the cell
// temperatures of each sub-step are interpolated linearly between the
// temperature fields of the last two calls, so both orders work: several solid
// steps inside one temperature step, or (case 3.1) one solid step spanning many
// temperature steps. The last call of a run ends the solid exactly at the end
// time.
//
// Energies (global, J or J/m in 2D): external work (gravity, fluid forces),
// stress work int sigma : D (internal), kinetic, hourglass, the kinetic
// energy lost in the MPM transfers (measured per step on the grid), and
// the kinetic energy of points that melted (left the solid) or solidified
// (entered it), found at each gather by particle id; the balance
// W_ext - (K - K_0) - W_int - E_HG - D_transfer - K_melted + K_solidified
// and the ratio K / |W_int| (how far from quasi-static a mass-scaled run
// is) go to a CSV file. Every gather and re-sort also counts the solid
// points globally and stops the run if one was lost.
#ifndef femp_solid_sub_cycle_h
#define femp_solid_sub_cycle_h

#include <deal.II/base/parameter_handler.h>

#include <femp/base/parameter_table.h>
#include <femp/grid/background_grid.h>
#include <femp/grid/material_points.h>
#include <femp/solid/constitutive.h>
#include <femp/solid/mass_scaling.h>
#include <femp/solid/solid_active_region.h>
#include <femp/solid/solid_energy_ledger.h>
#include <femp/solid/solid_fem.h>
#include <femp/solid/solid_mpm.h>

#include <fstream>
#include <memory>
#include <string>
#include <vector>

namespace femp
{
  using namespace dealii;

  class StateWriter;
  class StateReader;

  template <int dim>
  class SolidSubCycle
  {
  public:
    struct Parameters
    {
      double time_step     = 0;
      double safety_factor = 0.5;
      /// With the melt flow: the Courant number once the melt has
      /// solidified after the laser's path (0: keep safety_factor).
      double safety_factor_solidified = 0;
      /// Mass-scaling factor s: the fixed value, or the starting value of
      /// the adaptive controller.
      double mass_scaling = 1;
      /// Adaptive mass scaling (doc/speed_accuracy.md, section 3): between
      /// two temperature steps the factor follows the ratio of the kinetic
      /// to the stored elastic energy.
      bool adaptive_scaling = false;
      /// Target ratio K / U_el, and the factor's range.
      double max_kinetic_ratio = 1e-3;
      double min_factor = 1, max_factor = 1e4;
      /// With the melt flow: once the workpiece has solidified after the
      /// laser's path, the adaptive controller takes over from the factor
      /// in use (quasi-static cooling, doc/solid.md "Quasi-static cooling"),
      /// within [that factor, max_factor_solidified].
      bool   adaptive_after_solidification = false;
      double max_factor_solidified         = 1e8;
      /// With adaptive_after_solidification: the fraction of their
      /// velocity that the finite-element nodes lose at every solid step
      /// after the switch (doc/solid.md "Quasi-static cooling"), -.
      double fe_damping_solidified = 0;
      /// With adaptive_after_solidification: at a raise of the factor
      /// after the switch the finite-element nodes keep their momentum
      /// (velocities divided by s_new / s_old) instead of their
      /// velocities (doc/solid.md "Quasi-static cooling").
      bool fe_momentum_at_raise = false;
      /// The switch after solidification does something.
      bool
      cools_after_solidification() const
      {
        return safety_factor_solidified > safety_factor ||
               adaptive_after_solidification;
      }
      /// With the melt flow only: nodes whose inertial mass is below this
      /// fraction of a full cell's node take no force (doc/solid.md "Small
      /// node masses"), -.
      /// With the melt flow only: how nodes of small mass are updated,
      /// by a mass floor (set_mass_floor()) or with no force (the cutoff
      /// below).
      enum class LightNodes
      {
        mass_floor,
        no_force
      };
      LightNodes light_nodes       = LightNodes::mass_floor;
      double     small_mass_cutoff = 0.05;
      /// m/s^2 (default: none); not an input of Solid: FempProblem sets
      /// it from Physics/Gravity.
      Tensor<1, dim>           gravity;
      std::vector<std::string> fixed_faces, roller_faces;
      std::string              energy_file = "solid_energy.csv";
      std::string              probe_file  = "solid_probes.csv";
      /// Simulated time between two rows of the energy and probe files, s
      /// (0: every solid step).
      double                  row_interval = 0;
      std::vector<Point<dim>> probes;

      /// Declare (the members' values are the defaults) or read the

      /// entries, each listed once.

      void

      add_parameters(ParameterTable &table);

      static void
      declare_parameters(ParameterHandler &prm);
      void
      parse_parameters(ParameterHandler &prm);
      /// Checks that need the material and the grid: the prescribed step
      /// against the elastic limit.
      void
      check(const SolidMaterial                            &m,
            const typename BackgroundGrid<dim>::Parameters &g) const;
      /// Largest stable step h / (sqrt(dim) c), s, with the mass-scaling
      /// factor @p s (0: mass_scaling).
      double
      stable_limit(const SolidMaterial &m,
                   const double         h,
                   const double         s = 0) const;
    };

    /// The energies of the solid (solid_energy_ledger.h).
    using Energies = SolidEnergies;

    SolidSubCycle(const Parameters                         &prm,
                  const typename SolidFEM<dim>::Parameters &fem_prm,
                  const SolidMaterial                      &material,
                  const BackgroundGrid<dim>                &grid,
                  MaterialPoints<dim>                      &points);

    /// Set up the FE zone, boundary flags and the temperature history from
    /// the cell temperatures @p T at time 0. @p directory receives the CSV
    /// files (empty: none written).
    void
    initialize(const std::vector<double> &T, const std::string &directory);

    /// External forces on the background grid nodes (one array per
    /// direction over the local node box; partial contributions of this
    /// rank, summed over ranks with the solid's own), N (2D: N/m); the
    /// melt flow's (FluidSolidForces::nodal_forces()).
    using NodalForces = std::array<std::vector<double>, dim>;

    /// Advance the solid to @p t (see header comment) given the cell
    /// temperatures @p T at @p t; @p final ends exactly at @p t. The
    /// @p external_forces (nullptr: none) are held constant over the
    /// solid sub-steps.
    void
    advance(const double               t,
            const std::vector<double> &T,
            const bool                 final,
            const NodalForces         *external_forces = nullptr);

    /// The melt flow runs beside the solid (doc/solid.md, "Flow and solid
    /// together"): the flow owns the fluid points' velocities
    /// (set_flow_owns_fluid_points()), and fragments that solidify where
    /// the flow left them meet the light-node rule of the parameters
    /// ('Light nodes': set_mass_floor() or set_small_mass_cutoff() with
    /// 'Small mass cutoff'). @p flow_affine: the flow carries the fluid
    /// points' affine velocity (Melt flow/Velocity transfer = APIC). Call
    /// before initialize().
    void
    share_points_with_flow(const bool flow_affine);

    /// The melt flow runs beside the solid: fluid points keep their
    /// velocity at the gather (SolidMPM::set_flow_owns_fluid_points()).
    void
    set_flow_owns_fluid_points(const bool b, const bool affine = false)
    {
      mpm.set_flow_owns_fluid_points(b, affine);
    }
    /// With the melt flow: grid nodes whose (inertial) mass is below
    /// @p fraction of that of a node of a full cell, s rho h^dim / 2^dim,
    /// take no force in the grid update (their velocity is their momentum
    /// over their mass; the work the force would have done is booked,
    /// Energies::withheld). Such nodes appear round solid fragments that
    /// solidified at the positions where the flow left them (a point near
    /// a cell face gives the opposite face's nodes a tiny mass but a full
    /// shape-function gradient: the explicit update of those nodes is
    /// unstable). 0 (default): off, the update is unchanged.
    void
    set_small_mass_cutoff(const double fraction);
    /// With the melt flow, instead of the cutoff: every grid node is
    /// accelerated as if its mass were at least the mass floor
    /// m_floor = C^2 / (4 dim) sum_p m_p h |grad N_Ip| h sum_J |grad N_Jp|
    /// (C the safety factor in use), the mass at which the row sum of the
    /// node's stiffness allows the solid step; the work of the part of the
    /// force that a node below its floor does not take is booked
    /// (Energies::withheld). Full nodes lie below their floor only for
    /// C above about 0.92 (doc/solid.md "Small node masses").
    void
    set_mass_floor(const bool on);
    /// With the melt flow: find the points that melted or solidified since
    /// the last gather now, right after the temperature step changed their
    /// states and before the flow changes the velocities of the melted
    /// ones, so that `removed_by_melting` books the kinetic energy they had
    /// in the solid; the next gather uses this instead of looking again
    /// (local, no communication).
    void
    find_state_changes();
    /// The owned cells of the heat transfer's detached drops ('Heat
    /// transfer/Detached drops = sphere'; empty when off): their solid
    /// points are set aside, out of the solid, until the cell is no longer
    /// detached (SolidMPM::set_aside_cells()). Call before
    /// find_state_changes() and advance(); local.
    void
    set_detached_cells(const std::vector<std::uint32_t> &cells)
    {
      if (!region.mpm_cells().empty())
        mpm.set_aside_cells(cells);
    }
    /// Points that leave the run outside the solid (the recoater's blade
    /// deletes the detached metal it sweeps, builds/recoater.h): call
    /// before_points_removed() with this rank's ids of the points about to
    /// be deleted, then, once they are, points_removed(). The first
    /// gathers the points (books what melted or solidified since, as the
    /// next advance would) and counts the members among the ids; the
    /// second gathers again and checks that the solid lost exactly those
    /// members (else stops as a lost point does), and books their kinetic
    /// energy with what melting removes (Energies::melted). Returns the
    /// members removed (all ranks). Both collective; points_removed()
    /// without a before_points_removed() returns 0.
    void
    before_points_removed(const std::vector<types::particle_index> &ids);
    double
    points_removed();
    /// Solid points that left with points_removed() so far (global; not
    /// saved in checkpoints).
    double
    n_points_removed() const
    {
      return n_removed;
    }
    /// The largest speed with which a point entered the solid by
    /// solidifying (the velocity the melt flow last gave it) since the
    /// setup or the resume, and the P-wave speed of the mass-scaled solid,
    /// sqrt(M_max / (s rho)) with the factor s in use, m/s (all ranks;
    /// collective). A point faster than that wave moves C / sqrt(dim) cells
    /// or more in one automatic solid step (C the safety factor): far more
    /// than the explicit update follows (doc/solid.md "Flow and solid
    /// together").
    std::array<double, 2>
    solidification_speed() const;
    /// Solid points set aside in detached drops so far (global count of
    /// the set-aside events; a point that rejoins and leaves again counts
    /// twice).
    double
    n_points_set_aside() const
    {
      return n_set_aside;
    }

    /// After the melt has solidified at the end of the laser's path:
    /// switch the automatic step to 'Safety factor after solidification'
    /// with the mass-scaling factor times (C_after / C)^2, so that
    /// sqrt(s) / C, and with it the stresses, stay as they were, and the
    /// step (C sqrt(s)) grows by (C_after / C)^2 (velocities kept, the kinetic
    /// energy jump booked); with 'Mass scaling after solidification =
    /// adaptive' the adaptive controller then takes over from the factor in
    /// use. Once per run (a resumed run knows it from its checkpoint).
    /// Returns what changed, for the log, or "" if nothing did (no such
    /// switch set, or switched before). Local: every rank takes the same
    /// decision.
    std::string
    use_cooling_step();
    bool
    uses_cooling_step() const
    {
      return cooling_step;
    }

    /// Solid step size in use, s.
    double
    time_step() const
    {
      return dt_solid;
    }
    double
    time() const
    {
      return t_solid;
    }
    unsigned int
    n_steps() const
    {
      return steps;
    }
    /// Largest hourglass distortion of a finite element so far (since setup
    /// or the resume; SolidFEM::hourglass_distortion()), all ranks, and the
    /// limit; {-1, 0} without an FE zone. Collective.
    std::array<double, 2>
    largest_hourglass_distortion() const
    {
      if (!fem)
        return {{-1., 0.}};
      return {{fem->largest_distortion(),
               fem->parameters().hourglass_distortion_limit}};
    }
    /// Material points held at the domain's faces so far, all ranks
    /// (melt-flow scenes; collective).
    unsigned long
    n_points_held() const
    {
      return Utilities::MPI::sum(mpm.n_held(), comm);
    }
    /// Times a material point crossed the FE zone's top face from outside
    /// and was held on it since the setup or the resume, all ranks
    /// (SolidMPM::n_held_at_zone_top(); collective).
    unsigned long
    n_points_held_at_zone_top() const
    {
      return Utilities::MPI::sum(mpm.n_held_at_zone_top(), comm);
    }
    /// Times a material point crossed a lateral face of the FE zone (of a
    /// zone narrower than the domain) from outside and was held on it since
    /// the setup or the resume, all ranks
    /// (SolidMPM::n_held_at_zone_lateral(); collective).
    unsigned long
    n_points_held_at_zone_lateral() const
    {
      return Utilities::MPI::sum(mpm.n_held_at_zone_lateral(), comm);
    }
    /// When false, a material point that enters the FE zone stops the run
    /// however shallow (SolidMPM::set_hold_on_zone_faces(); tests).
    void
    set_hold_on_zone_faces(const bool hold)
    {
      mpm.set_hold_on_zone_faces(hold);
    }
    /// Kinetic energy those holds removed, all ranks, J (2D: J/m;
    /// SolidMPM::held_at_zone_kinetic(); collective).
    double
    kinetic_held_at_zone() const
    {
      return Utilities::MPI::sum(mpm.held_at_zone_kinetic(), comm);
    }
    /// Gathers of the MPM points at the temperature steps, summed over the
    /// ranks: those that kept the arrays of the last one (nothing melted,
    /// solidified or moved in or out of the members' cells there), those
    /// that read again only the cells whose points changed, and all
    /// (collective).
    std::array<double, 3>
    gathers_kept() const
    {
      const auto c = mpm.gather_counts();
      return {{Utilities::MPI::sum(double(c[0]), comm),
               Utilities::MPI::sum(double(c[1]), comm),
               Utilities::MPI::sum(double(c[2]), comm)}};
    }
    /// State of the mass scaling (the adaptive controller's; constant with
    /// a fixed factor; mass_scaling.h).
    using MassScalingState = MassScalingController::State;
    const MassScalingState &
    mass_scaling_state() const
    {
      return scaling.state();
    }
    /// Global energies (collective). Without @p with_hourglass_mode the
    /// reference hourglass energy (a diagnostic of the output, not of the
    /// balance) is left 0: one pass over the elements less.
    Energies
    energies(const bool with_hourglass_mode = true) const;
    /// What the energy check read at the end of the last solid advance
    /// (doc/stability.md, "Energy check"): {the energy created, the stored
    /// elastic, kinetic and external energies and the booked exchanges it
    /// is measured against}, J (2D: J/m); the run stops where the first
    /// exceeds energy_created_limit times the second. {0, 0} before the
    /// first advance. The same on every rank.
    std::array<double, 2>
    energy_check_balance() const
    {
      return last_check;
    }
    /// sigma_xx (Pa) and temperature (K) at the cell holding each probe
    /// point (element stress, or the mean over the cell's points; collective).
    std::vector<std::array<double, 2>>
    probe(const std::vector<Point<dim>> &x) const;
    /// Cell fields over the local box for output: sigma_xx and the von
    /// Mises stress (Pa) of the element of a cell, or the mean over its
    /// solid points; 0 in cells without solid.
    void
    cell_stress_fields(std::vector<double> &sigma_xx,
                       std::vector<double> &von_mises) const;
    /// Names of the cell fields of cell_fields(): sigma_xx, sigma_yy,
    /// sigma_zz, von_mises (Pa) and plastic_strain (equivalent, -).
    static std::vector<std::string>
    cell_field_names();
    /// Cell fields over the local box (output, probe lines), in the order of
    /// cell_field_names(): in a cell of the FE zone the values of its
    /// element, elsewhere the mean over the cell's solid points; 0 in cells
    /// without solid (fluid, powder, gas). Collective.
    void
    cell_fields(std::vector<std::vector<double>> &fields) const;
    /// 1 for the cells of the local box in the FE zone, 0 elsewhere (all 0
    /// without the zone): their points carry only temperatures.
    const std::vector<std::uint8_t> &
    fe_zone_cells() const
    {
      return zone_mask();
    }
    /// The vertical displacement (m) of the FE zone's top-face nodes since
    /// the zone was last set (initialize() or the last hand-over): per
    /// column of the zone's bounding box (its cells across the last
    /// direction, lexicographic, x fastest, from the box's first cell) the
    /// 2^(dim-1) nodes of the top face of the column's highest zone cell
    /// (bit d of the node: upper side in direction d); 0 for a column
    /// without zone cells; the same on every rank; empty without a zone or
    /// when a column's top is the domain's. The hand-over's fill reads it
    /// (FeZoneHandover::choose_top()).
    std::vector<double>
    zone_top_lift() const;
    /// FE elements whose grid cell is owned by another rank (global; the
    /// two meshes are partitioned independently).
    double
    fe_elements_off_rank() const;
    /// Number of material points and finite elements in the solid (global).
    std::array<double, 2>
    sizes() const;
    /// The FE zone's mass, kg (2D: kg/m; SolidFEM::mass()), 0 without a
    /// zone. Collective.
    double
    fe_zone_mass() const;
    /// The most material points of the solid on one rank (collective).
    double
    largest_rank_points() const;

    /// Hand the cell rows between the FE zone's top and the grid line
    /// @p new_top (m) over from material points to finite elements
    /// (fe_zone_handover.h), after an advance() and before the next: each
    /// new element takes the mean stress and plastic strain of its cell's
    /// solid points (the mean of the cell fields, cell_fields()), the
    /// points there leave the solid (they carry temperature only, as in
    /// the zone's other cells) and their kinetic energy is booked as
    /// removed (Energies::melted). Every cell of the new rows must hold
    /// solid points (an error names the first that does not); whether the
    /// rows may be handed over (cooled, below the melt) is the caller's
    /// choice (FeZoneHandover). Collective; returns the elements added and
    /// the points handed over (global).
    std::array<double, 2>
    hand_over_rows(const double new_top);
    /// The same for the grid cells @p cells (structured indices, the same
    /// list on every rank, none in the zone; FeZoneHandover::
    /// chosen_cells()): the zone becomes any set of cells.
    std::array<double, 2>
    hand_over_cells(const std::vector<std::array<int, dim>> &cells);

    /// Checkpoint (doc/checkpoint.md), after an advance(): the sub-step
    /// clock, the temperatures it interpolates between, the energy
    /// accounts, the lengths of the CSV files (flushed here), then
    /// SolidMPM's and SolidFEM's state. The pending state-change exchange
    /// is not saved: the next find_state_changes() finds it before the
    /// next advance().
    void
    save_state(StateWriter &out) const;
    /// Restore it after initialize() (collective; any number of saved
    /// ranks): cut the CSV files in @p directory back to their length at
    /// the checkpoint and append to them (initialize() with an empty
    /// directory opened none).
    void
    load_state(std::vector<StateReader> &parts, const std::string &directory);
    /// Checkpoint section "fe zone": the FE zone's top (m), the
    /// mass-scaling factor its masses were built at (0 and 0 without a
    /// zone), and its cells (the bounding box's first cell and cells per
    /// direction, the mask; none without a zone). A hand-over adds cells;
    /// the section lets a resumed run build the same zone before it reads
    /// the elements.
    void
    save_fe_zone(StateWriter &out) const;
    /// Before initialize(), when resuming: read that section (@p parts, one
    /// per saved rank), so that initialize() builds the zone up to the
    /// saved top with the masses of the saved factor, as the run that
    /// wrote the checkpoint held it (its cells, where the section has
    /// them); load_state() then finds every element
    /// and node of the checkpoint. Without this call the zone is the
    /// scene's.
    void
    resume_fe_zone(std::vector<StateReader> &parts);
    /// Before initialize(): the FE zone is the set of grid cells @p zone
    /// (the same on every rank; it need not be a box: SolidFEM::
    /// set_cells()) instead of the parameters' box. Needs the FE zone on.
    void
    set_fe_zone(const FeZone<dim> &zone);
    /// The FE zone as it is now (it rises with hand_over_rows()); null
    /// without one.
    const FeZone<dim> *
    fe_zone() const
    {
      return fem ? &fem->fe_zone() : nullptr;
    }

  private:
    Parameters                 prm;
    const SolidMaterial       &mat;
    const BackgroundGrid<dim> &grid;
    MPI_Comm                   comm;
    SolidMPM<dim>              mpm;
    /// The FE zone; null when 'Solid FEM/Use finite elements' is false (all
    /// the solid is then material points).
    std::unique_ptr<SolidFEM<dim>> fem;
    /// 1 for the grid's local cells in the FE zone (all 0 without one).
    std::vector<std::uint8_t> no_fe_zone;
    const std::vector<std::uint8_t> &
    zone_mask() const
    {
      return fem ? fem->zone_mask() : no_fe_zone;
    }
    /// Transition nodes of the FE zone (0 without one).
    std::size_t
    n_transition() const
    {
      return fem ? fem->n_transition() : 0;
    }

    SolidNodeFields<dim> nodes;
    /// The grid nodes and cells a step visits (solid_active_region.h).
    SolidActiveRegion<dim> region;
    /// (transition index, local grid node) for transition nodes among the
    /// nodes of this rank's owned cells.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> grid_transition;
    std::vector<double>                                  tr_buffer, tr_v, tr_a;
    /// Per transition node: FE velocity before the merge and the grid
    /// (point) force, for the re-map work there.
    std::vector<double>       tr_u, tr_fgrid;
    std::vector<std::uint8_t> constrained; ///< bit d: velocity d fixed
    std::vector<double>       T_solid, T_prev, T_next;
    double                    t_solid = 0, t_prev = 0, dt_solid = 0;
    unsigned int              steps = 0;
    /// The energy accounts (global).
    SolidEnergyLedger ledger;
    /// Points set aside in detached drops (n_points_set_aside()); not
    /// saved in checkpoints (a resumed run counts from there).
    double n_set_aside = 0;
    /// points_removed(): the total, and between before_points_removed()
    /// and points_removed() the members to remove (-1: none announced)
    /// and the points' kinetic energy before, J (2D: J/m).
    double n_removed = 0, removing = -1, removing_K0 = 0;
    double n_points_global = 0; ///< solid points after the last step
    /// Largest speed of a point that solidified, this rank, m/s
    /// (solidification_speed()).
    double fastest_solidified = 0;
    bool   regathered         = false; ///< a re-sort gathered the points
    double last_w             = -1;    ///< w of the last step of an advance
    std::unique_ptr<std::ofstream> energy_out, probe_out;
    std::string                    csv_directory; ///< of energy_out, probe_out
    /// State changes found by find_state_changes() for the next gather.
    typename SolidMPM<dim>::Exchange pending_exchange;
    bool                             have_pending_exchange = false;
    /// Node mass below which the grid update applies no force (kg, 2D
    /// kg/m; 0: off).
    double small_mass = 0;
    /// set_mass_floor(): the light-node mass floor is on.
    bool   mass_floor          = false;
    double small_mass_fraction = 0; ///< the cutoff it was set from
    MassScalingController scaling;
    /// Courant number of the automatic step in use: safety_factor, or
    /// safety_factor_solidified after use_cooling_step().
    double safety       = 0.5;
    bool   cooling_step = false;
    /// With 'Mass scaling after solidification = adaptive', after the
    /// switch: the factor the controller took over from (its lower bound);
    /// 0 before.
    double adaptive_from = 0;
    /// The mass-scaling factor initialize() builds the FE zone's masses
    /// at: that of the checkpoint resumed (resume_fe_zone()), else 0 (the
    /// factor of 'Solid/Mass scaling factor').
    double fe_setup_factor = 0;

    /// One solid step of size @p dt; @p w: weight of the step's end time
    /// between the last two temperature fields; @p external_forces as in
    /// advance().
    void
    step(const double dt, const double w, const NodalForces *external_forces);
    /// Guard of the FE zone (fe_zone_depth.h): throws FeZoneMelted on every
    /// rank if a cell of the zone is at or above the solidus in @p T at
    /// time @p t, naming the element and the zone top to use (collective).
    void
    check_fe_zone_solid(const std::vector<double> &T, const double t) const;
    /// The parts of initialize(): boundary flags of the nodes of owned
    /// cells (returns the constrained components per domain face for the
    /// FE zone), the grid nodes a step touches, the output files.
    std::array<std::uint8_t, 2 * dim>
    set_boundary_flags();
    void
    find_active_nodes();
    /// The live nodes and cells anew after a gather; nodes that leave the
    /// set are zeroed. With @p T (after a re-sort within a step of weight
    /// @p w), the new cells get the step's temperature in T_next.
    void
    rebuild_live(const std::vector<double> *T, const double w);
    /// After a step: the nodes and cells that points reached in it become
    /// live (their cells get the step's temperature in T_next).
    void
    extend_live(const std::vector<double> &T, const double w);
    void
    open_output_files(const std::string &directory);
    /// The parts of step(), in this order: 1. P2G (partial sums of this
    /// rank); 2. the merge at the transition nodes (returns its kinetic
    /// energy loss, counted on the first rank); the sums over ranks; 3. the
    /// grid momentum update; the transition-node velocities; the power of
    /// the external forces; 3.-4. G2P and the FE nodes (returns the FE
    /// {kinetic energy, external power}); the re-map work; the grid
    /// velocities of the re-mapped momenta; after the stresses, the energy
    /// balance and the blow-up check.
    void
    particles_to_grid(const NodalForces *external_forces);
    double
    merge_transition_nodes(const double dt);
    void
    sum_grid_partials();
    /// Returns Energies::withheld of the step (the light nodes this rank
    /// counts).
    double
    update_grid_momentum(const double dt);
    void
    set_transition_velocities();
    double
    external_power(const NodalForces *external_forces) const;
    /// Returns the FE nodes' {kinetic energy, external power, sums for
    /// the half-step term} (SolidFEM::update_nodes()).
    std::array<double, 4>
    grid_to_points(const double dt);
    /// Returns {the re-map work, sum m v_old . dv, sum m dv . dv} of the
    /// step over this rank's counted grid nodes (the last two for the
    /// half-step term, SolidEnergies::half_step).
    std::array<double, 3>
    remap_work_of_step(const double dt) const;
    void
    set_grid_velocities();
    void
    book_energies(const double                 dt,
                  const double                 ext_power,
                  const std::array<double, 4> &fe_energy,
                  const double                 transfer,
                  const double                 work,
                  const double                 remap_work,
                  const double                 withheld,
                  const std::array<double, 2> &half_step);
    /// Whether the step from @p t_old to @p t_new ends with a row of the
    /// energy and probe files ('Row interval').
    bool
    row_due(const double t_old, const double t_new) const;
    void
    write_rows();
    /// At the end of a solid advance (points still gathered, collective):
    /// the ratio K / U_el, and with the adaptive mass scaling the new
    /// factor (kinetic energy jump booked, masses and step updated).
    void
    measure_and_adapt_scaling(const bool adapt);
    /// Stops the run (CollectiveError, on every rank) when the energy
    /// balance shows more energy created than energy_created_limit times
    /// the stored elastic energy @p elastic_energy (global), the kinetic
    /// energy, the external work and the booked exchanges together: an
    /// unstable solid step that stayed finite (doc/stability.md).
    void
    check_energy_created(const double elastic_energy);
    /// What the last check_energy_created() compared: {the balance with
    /// the kinetic energy at the whole step, the energy it is measured
    /// against}, J (global).
    std::array<double, 2> last_check{{0., 0.}};
    /// Fraction of that energy that a positive balance may reach before
    /// check_energy_created() stops the run, -.
    static constexpr double energy_created_limit = 0.25;
    /// Change the mass-scaling factor to @p s at kept velocities; with
    /// @p keep_fe_momentum the finite-element nodes (not the transition
    /// nodes) keep their momentum instead, the kinetic energy that this
    /// takes out booked with the transfer dissipation.
    void
    set_mass_scaling(const double s, const bool keep_fe_momentum = false);
    /// Gather the points for a solid advance: book the kinetic energy of
    /// melted and solidified points, and stop if a point was lost
    /// (collective).
    void
    gather_points();
    /// Kinetic energy of the points' share of the grid nodes (point-only
    /// mass), from the momenta after P2G (@p updated false; components
    /// with a boundary condition left out) or from the velocities after
    /// the grid update (true); this rank's counted nodes.
    double
    grid_point_kinetic(const bool updated) const;
    /// Stop with a diagnostic (step, time, position, what to change): a
    /// point volume or an element's corner Jacobian became <= 0 in the
    /// step of @p dt (the reduced flag of book_energies() was set).
    /// Collective.
    [[noreturn]] void
    stop_inverted(const double dt) const;
    /// Stop with a diagnostic (@p where, step, @p time) if @p n_now
    /// differs from @p n_expected.
    void
    check_point_count(const double       n_now,
                      const double       n_expected,
                      const std::string &where,
                      const double       time) const;
  };
} // namespace femp

#endif
