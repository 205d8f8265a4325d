// femp: the top-level problem. It reads the scene, owns the modules and
// what joins them, and runs the macro time step of the paper's sec. 2.6:
//   1. tag cells from the points, update alpha, gamma and properties;
//   2. temperature in fluid, solid and powder (HeatTransfer, eq. 1), then
//      the cell temperatures to the points (eq. 2);
//   3. flow in the melt pool (IncompressibleFlow, eqs. 3-4), sub-cycled,
//      the heat carried by points that changed cells (PointHeatExchange);
//      with the solid, the fluid forces on the solid's nodes (eq. 13,
//      FluidSolidForces);
//   4. solid by MPM + FE with transition-node coupling (SolidStress,
//      eqs. 5-17), sub-cycled to the macro time, loaded by those fluid
//      forces held constant over its sub-steps;
//   5. output (Output, RunReport) when the SimulationControl says so.
#ifndef femp_femp_problem_h
#define femp_femp_problem_h

#include <deal.II/base/conditional_ostream.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/timer.h>

#include <femp/app/run_report.h>
#include <femp/app/simulation_control.h>
#include <femp/base/material.h>
#include <femp/coupling/fluid_solid_forces.h>
#include <femp/coupling/point_heat_exchange.h>
#include <femp/flow/incompressible_flow.h>
#include <femp/grid/background_grid.h>
#include <femp/grid/cell_fields.h>
#include <femp/grid/material_points.h>
#include <femp/heat/heat_transfer.h>
#include <femp/heat/laser.h>
#include <femp/heat/thermal_history.h>
#include <femp/io/checkpoint.h>
#include <femp/io/output.h>
#include <femp/io/track_shape.h>
#include <femp/solid/solid_stress.h>

#include <fstream>
#include <memory>
#include <optional>

namespace femp
{
  using namespace dealii;

  /// Declare every parameter of femp (all modules) in @p prm.
  void
  declare_all_parameters(ParameterHandler &prm);

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

    void
    run();

    const Summary &
    summary() const
    {
      return result;
    }
    /// The material points after run() (tests read their stresses).
    const MaterialPoints<dim> &
    material_points() const
    {
      return *points;
    }
    /// Write a checkpoint of the present state now (collective; after
    /// run(), tests compare the final states of two runs by it); returns
    /// its directory.
    std::string
    write_checkpoint();

  private:
    MPI_Comm           comm;
    ConditionalOStream pcout;
    /// Wall time (s) after which a long melt-flow sub-cycle reports.
    double next_substep_report = 30;
    /// workpiece_peak_temperature() of the current step (reset at its start).
    std::optional<double> workpiece_peak;
    /// 'Time stepping/Time step after solidification' in use at this step.
    bool           cooling_step = false;
    TimeParameters time_prm;
    /// The material, owner of the data that several modules read (density,
    /// solidus, liquidus, evaporation data), passed by const reference.
    Material material;
    /// Physics/Gravity, m/s^2: the one gravity of the flow and the solid.
    Tensor<1, dim>                           gravity;
    typename BackgroundGrid<dim>::Parameters grid_prm;
    typename MaterialPoints<dim>::Parameters points_prm;
    typename HeatTransfer<dim>::Parameters   heat_prm;
    typename Laser<dim>::Parameters          laser_prm;
    /// Laser/Absorption model and the ray tracer's parameters.
    typename RayTracedAbsorption<dim>::Parameters absorption_prm;
    /// Ray traced: absorption.csv of the output directory (rank 0).
    std::unique_ptr<std::ofstream>           absorption_csv;
    typename Output<dim>::Parameters         output_prm;
    typename ThermalHistory<dim>::Parameters history_prm;
    bool                                     melt_flow = false;
    /// Physics/Heat transfer: false freezes the temperature field.
    bool                                         heat_enabled = true;
    typename IncompressibleFlow<dim>::Parameters flow_prm;
    bool                                         solid_enabled = false;
    /// Reads the density and solidus of @ref material.
    SolidMaterial                         solid_material{material};
    typename SolidStress<dim>::Parameters solid_prm;
    typename SolidFEM<dim>::Parameters    fem_prm;
    typename TrackShape<dim>::Parameters  track_prm;
    typename Checkpoint<dim>::Parameters  checkpoint_prm;

    // The modules; flow and solid exist only when switched on.
    std::unique_ptr<BackgroundGrid<dim>>     grid;
    std::unique_ptr<Laser<dim>>              laser;
    std::unique_ptr<MaterialPoints<dim>>     points;
    std::unique_ptr<HeatTransfer<dim>>       heat;
    std::unique_ptr<IncompressibleFlow<dim>> flow;
    std::unique_ptr<SolidStress<dim>>        solid;
    std::unique_ptr<ThermalHistory<dim>>     history; ///< null unless enabled
    // What joins them.
    std::unique_ptr<PointHeatExchange<dim>> point_heat;
    std::unique_ptr<FluidSolidForces<dim>>  fluid_solid;
    // Clock, output and report.
    std::unique_ptr<SimulationControl> control;
    std::unique_ptr<Output<dim>>       output;
    std::unique_ptr<RunReport<dim>>    report;
    std::unique_ptr<TrackShape<dim>>   track_shape; ///< null unless on
    std::unique_ptr<Checkpoint<dim>>   checkpoint;
    TimerOutput                        timer;
    Summary                            result;

    /// 'Solid FEM/Zone upper corner = auto': the FE zone's top below a
    /// conservative melt depth of the scene's laser (fe_zone_depth.h).
    void
    place_fe_zone_automatically();
    /// Checks that need several modules' parameters (before any work).
    void
    check_across_modules();
    void
    setup();
    void
    setup_flow();
    void
    setup_solid();
    void
    print_scene() const;
    /// The melting regime of the scene's laser (normalized enthalpy).
    void
    print_melting_regime() const;

    /// The shared cell fields of the present state (cell_fields.h), for
    /// the modules that read them: T, gamma and alpha of the heat, the
    /// cell velocity of the flow (when on).
    CellFields<dim>
    cell_fields() const;

    // The steps of the macro time step (paper sec. 2.6), in run() order.
    /// The step chooser of the SimulationControl.
    double
    choose_time_step(const unsigned int step, const double time);
    /// Refuses (at the first step) a run that would need more than
    /// 'Time stepping/Maximum number of steps' steps of @p dt.
    void
    check_projected_steps(const unsigned int step, const double dt) const;
    /// Ray traced: one row of absorption.csv (time, incident, absorbed,
    /// escaped power, absorbed fraction, hits per ray).
    void
    write_absorption_series();
    /// 2. Temperature in fluid, solid and powder (eq. 1).
    void
    temperature_step(const double dt);
    /// The cell temperatures to the points (eq. 2); their states follow.
    void
    cells_to_points();
    /// 3. The flow sub-cycled over @p dt; then alpha and the heat of points
    /// that changed cells (PointHeatExchange).
    void
    flow_substeps(const double dt);
    /// 3. With the solid: the fluid forces on the solid's nodes.
    void
    fluid_forces_on_solid();
    /// 4. The solid to the end of the step, loaded by those forces.
    void
    solid_step();
    /// 'Time stepping/Stop when peak temperature below': once the laser's
    /// path has ended by the end of the step of @p dt and the hottest metal
    /// cell is below that temperature, make this step the last (the
    /// SimulationControl stops after it) and say so.
    void
    stop_if_cooled_down(const double dt);
    /// Peak temperature of the metal attached to the substrate
    /// (attached_metal.h), computed once per temperature step: the stop
    /// test and the solid's cooling switch read the same T and alpha.
    /// Collective.
    double
    workpiece_peak_temperature();
    /// 5. Time series, field output and progress line when due.
    void
    output_results();
    /// The checkpoint (doc/checkpoint.md): what the scene must share with
    /// a checkpoint; every module's state of the present step; the state
    /// of the checkpoint read, after setup().
    typename Checkpoint<dim>::Scene
    checkpoint_scene() const;
    void
    restore_checkpoint();

    void
    write_series();
    void
    write_output(const bool last);
    /// The track's surface and bead (TrackShape) for output number @p n.
    void
    write_track_shape(const unsigned int n, const double time);
    std::vector<typename Output<dim>::Field>
    output_fields() const;
  };
} // namespace femp

#endif
