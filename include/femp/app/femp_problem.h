// femp: the top-level problem, a sequencer. It reads the scene (Scene),
// builds the modules, registers what they write (ResultsOutput) and what
// state they carry (ModuleStates), and runs the macro time step of the
// paper's sec. 2.6:
//   1. tag cells from the points, update alpha, gamma and properties;
//   2. temperature in fluid, solid and powder (HeatTransfer, eq. 1), then
//      the cell temperatures to the points (eq. 2);
//   3. flow in the melt pool (IncompressibleFlow::advance_over, eqs. 3-4),
//      sub-cycled, the heat carried by points that changed cells
//      (PointHeatExchange); with the solid, the fluid forces on the solid's
//      nodes (eq. 13, FluidSolidForces);
//   4. solid by MPM + FE with transition-node coupling (SolidSubCycle,
//      eqs. 5-17), sub-cycled to the macro time, loaded by those fluid
//      forces held constant over its sub-steps;
//   5. output (ResultsOutput, RunReport) when the SimulationControl says so.
// The step and the early ends are the TimeStepPolicy's.
#ifndef femp_femp_problem_h
#define femp_femp_problem_h

#include <deal.II/base/conditional_ostream.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/timer.h>

#include <femp/app/build_steps.h>
#include <femp/app/module_states.h>
#include <femp/app/results_output.h>
#include <femp/app/run_checks.h>
#include <femp/app/run_report.h>
#include <femp/app/scene.h>
#include <femp/app/simulation_control.h>
#include <femp/app/time_step_policy.h>
#include <femp/coupling/fluid_solid_forces.h>
#include <femp/coupling/point_heat_exchange.h>
#include <femp/flow/incompressible_flow.h>
#include <femp/grid/background_grid.h>
#include <femp/grid/cell_fields.h>
#include <femp/grid/material_points.h>
#include <femp/heat/heat_transfer.h>
#include <femp/heat/laser.h>
#include <femp/solid/solid_sub_cycle.h>

#include <chrono>
#include <memory>
#include <string>

namespace femp
{
  using namespace dealii;

  template <int dim>
  class FempProblem
  {
  public:
    /// Subsection 'Time stepping' (SimulationControl).
    using TimeParameters = SimulationControl::Parameters;
    /// Summary numbers of the finished run (for tests and benchmarks).
    using Summary = RunSummary<dim>;

    /// Read and check all parameters; throws InputError before any work.
    FempProblem(ParameterHandler &prm, MPI_Comm comm);

    /// How run() ended: at the end of the run, or after a layer's first
    /// step with a checkpoint for a rebalance ('Build/Rebalance above
    /// imbalance'), which a fresh FempProblem resumes (run_to_end()).
    struct End
    {
      bool rebalance = false;
      /// The rebalance's checkpoint directory.
      std::string checkpoint;
      /// When this rank decided on the rebalance (before the checkpoint).
      std::chrono::steady_clock::time_point since;
      /// The wall clock of the run so far (the progress line goes on).
      SimulationControl::Clock clock;
      /// The layer's window of layer_cost.csv so far (BuildSteps).
      typename BuildSteps<dim>::CostCarry cost;
      /// The timer's sections of the run so far, every part before the
      /// rebalance (the cost report at the end adds them).
      TimerSums timer_sums;
    };

    End
    run();

    /// Before run(), on a problem that resumes the checkpoint of the
    /// rebalance @p end of the run before (in this process): the wall from
    /// its decision to the restore's end is the rebalance's cost (printed,
    /// and counted in the layer's row of layer_cost.csv, which goes on
    /// from the layer's start).
    void
    continue_rebalance(const End &end)
    {
      rebalance = std::make_unique<End>(end);
    }

    const Summary &
    summary() const
    {
      return report->summary();
    }
    /// The material points after run() (tests read their stresses).
    const MaterialPoints<dim> &
    material_points() const
    {
      return *points;
    }
    /// The heat module after run() (tests read its cell fields).
    const HeatTransfer<dim> &
    heat_transfer() const
    {
      return *heat;
    }
    /// Write a checkpoint of @p kind of the present state now (collective;
    /// after run(), tests compare the final states of two runs by it);
    /// returns its directory.
    std::string
    write_checkpoint(const CheckpointKind kind = CheckpointKind::user);

  private:
    MPI_Comm           comm;
    ConditionalOStream pcout;
    /// Every module's parameters, checked.
    Scene<dim> scene;

    // The modules; flow and solid exist only when switched on.
    std::unique_ptr<BackgroundGrid<dim>>     grid;
    std::unique_ptr<Laser<dim>>              laser;
    std::unique_ptr<MaterialPoints<dim>>     points;
    std::unique_ptr<HeatTransfer<dim>>       heat;
    std::unique_ptr<IncompressibleFlow<dim>> flow;
    std::unique_ptr<SolidSubCycle<dim>>      solid;
    // Builds of several layers and pores (doc/builds.md).
    std::unique_ptr<BuildSteps<dim>> builds;
    // What joins them: alpha's keeper, with the bodies of metal of alpha
    // (detached drops, workpiece) that heat, solid, stop test and melt
    // pool read, and the free surface of alpha that the heat reads.
    std::unique_ptr<PointHeatExchange<dim>> point_heat;
    std::unique_ptr<FluidSolidForces<dim>>  fluid_solid;
    // Clock, step policy, output, report, state and its checkpoint.
    std::unique_ptr<SimulationControl>   control;
    std::unique_ptr<TimeStepPolicy<dim>> time_steps;
    std::unique_ptr<ResultsOutput<dim>>  results;
    std::unique_ptr<RunReport<dim>>      report;
    ModuleStates<dim>                    states;
    TimerOutput                          timer;
    /// Set by continue_rebalance().
    std::unique_ptr<End> rebalance;

    void
    setup();
    void
    setup_flow();
    void
    setup_solid();
    /// Every module with state, in checkpoint order.
    void
    register_states();

    /// The shared cell fields of the present state (cell_fields.h), for
    /// the modules that read them: T, gamma and alpha of the heat, the
    /// cell velocity of the flow (when on).
    CellFields<dim>
    cell_fields() const;

    // The steps of the macro time step (paper sec. 2.6), in run() order.
    /// 2. Temperature in fluid, solid and powder (eq. 1).
    void
    temperature_step(const double dt);
    /// The cell temperatures to the points (eq. 2); their states follow.
    void
    cells_to_points();
    /// The mass evaporated in the temperature step leaves the points of
    /// the surface cells; alpha follows (PointHeatExchange).
    void
    remove_evaporated_mass();
    /// 3. The flow over the step of @p dt; then alpha and the heat of
    /// points that changed cells (PointHeatExchange).
    void
    flow_step(const double dt);
    /// 3. With the solid: the fluid forces on the solid's nodes.
    void
    fluid_forces_on_solid();
    /// 4. The solid to the end of the step, loaded by those forces.
    void
    solid_step();
    /// 5. Time series, field output and progress line when due.
    void
    output_results();
    /// The busiest rank's MPM points over their mean over the ranks (0
    /// without the solid or its MPM points). Collective.
    double
    mpm_imbalance() const;
    /// After the step [@p t, @p t + @p dt) (5.): whether the run ends here
    /// for a rebalance (a layer started in the step, the run goes on, and
    /// the MPM points' imbalance exceeds 'Build/Rebalance above
    /// imbalance' on several ranks with 'Background grid/Partition =
    /// cost'). Collective.
    bool
    rebalance_due(const double t, const double dt) const;
  };

  /// Run @p problem, made from @p prm, to the end of its scene: whenever its
  /// run() ends for a rebalance, a fresh FempProblem resumes that
  /// checkpoint with 'Checkpoint/Partition on resume = checkpoint' (both
  /// set in @p prm, as 'femp --resume' does) and takes its place. Returns
  /// the number of rebalances. Collective.
  template <int dim>
  unsigned int
  run_to_end(std::unique_ptr<FempProblem<dim>> &problem,
             ParameterHandler                  &prm,
             MPI_Comm                           comm);
} // namespace femp

#endif
