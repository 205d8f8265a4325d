// femp: what a run reports about itself: the summary numbers of a finished
// run (RunSummary, read by tests and benchmarks), the progress line, and
// the end-of-run report (solid energies, the energy balance of eq. 1 with
// the laser, surface losses, fixed faces and stored enthalpy, the melt-flow
// solver statistics and fluid step limits). It reads the modules; it
// changes nothing.
#ifndef femp_run_report_h
#define femp_run_report_h

#include <deal.II/base/conditional_ostream.h>

#include <femp/app/module_states.h>
#include <femp/app/simulation_control.h>
#include <femp/base/state_stream.h>
#include <femp/coupling/point_heat_exchange.h>
#include <femp/flow/incompressible_flow.h>
#include <femp/grid/material_points.h>
#include <femp/grid/metal_bodies.h>
#include <femp/heat/heat_transfer.h>
#include <femp/heat/laser.h>
#include <femp/heat/melt_pool.h>
#include <femp/solid/solid_sub_cycle.h>

#include <array>
#include <functional>
#include <limits>

namespace femp
{
  using namespace dealii;

  /// Summary numbers of a finished run (for tests and benchmarks).
  template <int dim>
  struct RunSummary
  {
    unsigned int steps = 0;
    double       time  = 0;
    double       T_max = 0;
    MeltPoolSize pool;
    /// Energies over the run, J (2D: J/m): laser input, surface losses,
    /// heat in through fixed faces, change of stored enthalpy.
    double laser = 0, losses = 0, boundary = 0, stored = 0;
    /// With melt flow: energy created by the upwind convection of T (not
    /// conservative) and by points moving between cells (change of the
    /// stored enthalpy when alpha and the new metal cells are updated),
    /// J (2D: J/m); both are zero for a conservative scheme.
    double advection = 0, moved_points = 0;
    /// Evaporation (with 'Heat transfer/Remove evaporated mass'): the mass
    /// that evaporated (the evaporation loss over L_v), the part taken from
    /// the points, and the stored heat (sensible and melting, relative to
    /// T_ref) that the removed metal took out of the grid, kg and J (2D:
    /// kg/m, J/m); all zero without it.
    double evaporated_mass = 0, removed_mass = 0, removed_enthalpy = 0;
    /// The recoater's blade (builds/recoater.h): the detached metal it
    /// swept over the run, its mass and the stored heat it took out of the
    /// grid, kg and J (2D: kg/m, J/m), its points and bodies; all zero
    /// when it swept none.
    double                swept_mass = 0, swept_enthalpy = 0;
    unsigned long         swept_points = 0, swept_bodies = 0;
    types::particle_index n_points     = 0;
    double                point_T_mean = 0; ///< mean point temperature, K
    // Melt flow (zero when Physics/Melt flow is false).
    unsigned int  flow_steps             = 0;
    unsigned int  pressure_matrix_builds = 0; ///< matrix + AMG setups
    unsigned long pressure_cg_iterations = 0; ///< total
    double        max_fluid_speed        = 0; ///< m/s, at the end
    /// Fluid step limits over the run (IncompressibleFlow::SubcycleRecord).
    using FlowLimits = typename IncompressibleFlow<dim>::SubcycleRecord;
    FlowLimits flow_limits;
    /// Solid (if Physics/Solid stress): steps and final energies.
    unsigned int                          solid_steps = 0;
    typename SolidSubCycle<dim>::Energies solid_energy;
  };

  template <int dim>
  class RunReport
  {
  public:
    RunReport(MPI_Comm comm, ConditionalOStream &out);

    /// Remember the stored enthalpy at the start (collective).
    void
    start(const HeatTransfer<dim> &heat);

    /// The summary numbers (complete after finish()).
    const RunSummary<dim> &
    summary() const
    {
      return s;
    }
    /// The melt pool of the last time-series row (kept in the summary and
    /// in a checkpoint).
    MeltPoolSize &
    series_pool()
    {
      return s.pool;
    }

    /// The run's accounts that no module keeps as the checkpoint section
    /// "run" of @p states: the stored enthalpy at the start, the energy of
    /// the points that moved (@p point_heat), the pool of the last series
    /// row, the flow's step limits (of @p flow, null without the melt
    /// flow). On restore the modules get theirs back.
    void
    add_state(ModuleStates<dim>       &states,
              PointHeatExchange<dim>  &point_heat,
              IncompressibleFlow<dim> *flow);

    /// Show the melt pool in the progress line when @p laser has power on
    /// some segment of its path.
    void
    watch_laser(const Laser<dim> &laser);

    /// The progress line of the step just taken, when @p control says it
    /// is due: @p T_max gives the hottest metal attached to the substrate
    /// and the hottest detached metal (MetalBodies), @p pool the melt pool
    /// (melt_pool.h), both at the end of the step; the pool only in a scene
    /// whose laser has power (watch_laser()).
    void
    progress_when_due(const SimulationControl                      &control,
                      const std::function<MetalPeakTemperatures()> &T_max,
                      const std::function<MeltPoolSize()>          &pool) const;

    /// Fill the end-of-run numbers of the summary from the modules
    /// (@p flow and @p solid may be null; @p point_heat: the energy
    /// account of the points that moved) and print the report. Collective.
    void
    finish(const SimulationControl       &control,
           const HeatTransfer<dim>       &heat,
           const MaterialPoints<dim>     &points,
           const IncompressibleFlow<dim> *flow,
           const SolidSubCycle<dim>      *solid,
           const PointHeatExchange<dim>  &point_heat);

  private:
    MPI_Comm            comm;
    ConditionalOStream &out;
    double              H0 = 0;
    RunSummary<dim>     s;
    /// Whether the laser has power on some segment (the progress line
    /// shows the melt pool then).
    bool with_laser = false;
    /// Whether the run removed evaporated mass (the energy lines book it),
    /// and its account at the end.
    bool                                                   removal = false;
    typename PointHeatExchange<dim>::EvaporatedMassAccount removal_account;

    /// The progress line (progress_when_due()).
    void
    progress(const SimulationControl     &control,
             const MetalPeakTemperatures &T_max,
             const MeltPoolSize          &pool) const;
    void
    print_energy(const typename HeatTransfer<dim>::EnergyBudget &e,
                 const bool                                      heat_enabled,
                 const bool with_flow) const;
    void
    print_flow(const IncompressibleFlow<dim> &flow) const;
  };
} // namespace femp

#endif
