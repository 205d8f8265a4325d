// femp: BuildSteps, what a build of several layers adds to the macro time
// step (doc/builds.md): the layer schedule (LayerSchedule, refused before
// any work when a layer does not fit the domain), the recoat of each layer
// in the step where it starts (Recoater; then the metal fraction and the
// heat of the cells that gained powder follow, PointHeatExchange), and the
// pores and unfused powder with every field output (PoreDetector), and the
// record of each finished track and layer (TrackRecord: tracks.csv,
// layers.csv, probe lines after each track), and the hand-over of cooled
// metal rows from material points to the solid's finite elements at each
// layer start (FeZoneHandover, SolidSubCycle::hand_over_rows()), and the
// cost of each layer (layer_cost.csv). Each part exists only when the scene
// asks for it.
#ifndef femp_build_steps_h
#define femp_build_steps_h

#include <deal.II/base/conditional_ostream.h>
#include <deal.II/base/timer.h>

#include <femp/app/module_states.h>
#include <femp/app/results_output.h>
#include <femp/app/scene.h>
#include <femp/app/simulation_control.h>
#include <femp/builds/pore_detector.h>
#include <femp/builds/recoater.h>
#include <femp/builds/track_record.h>
#include <femp/coupling/point_heat_exchange.h>
#include <femp/flow/incompressible_flow.h>
#include <femp/solid/fe_zone_handover.h>
#include <femp/solid/solid_sub_cycle.h>

#include <array>
#include <chrono>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace femp
{
  using namespace dealii;

  template <int dim>
  class BuildSteps
  {
  public:
    /// The layer schedule of the scene along the laser's path (none with
    /// one layer); throws InputError when a layer does not fit.
    BuildSteps(const Scene<dim> &scene, const Laser<dim> &laser);

    /// Once the grid, the points and the heat exist: the recoater (with
    /// layers) and the pore detector with its output fields and files
    /// (with 'Porosity' on and carried points).
    void
    setup(const BackgroundGrid<dim> &grid,
          const MaterialPoints<dim> &points,
          const HeatTransfer<dim>   &heat,
          const SimulationControl   &control,
          ResultsOutput<dim>        &results);

    /// Step 0 of the macro step: spread the powder of each layer whose
    /// start time lies in [@p t, @p t + @p dt) (the same steps after a
    /// resume: no state to keep); then alpha and the heat of the cells
    /// that gained powder (@p point_heat); with 'Build/Hand over cooled
    /// metal' the rows of cooled metal the new layer leaves below its melt
    /// pass from the points to the finite elements of @p solid (null: no
    /// solid). Collective.
    void
    recoat(const double              t,
           const double              dt,
           MaterialPoints<dim>      &points,
           PointHeatExchange<dim>   &point_heat,
           TimerOutput              &timer,
           const ConditionalOStream &pcout,
           SolidSubCycle<dim>       *solid = nullptr);

    /// Step 0 of the macro step, before the recoat: close the track
    /// records due before @p t + @p dt (rows of tracks.csv and the probe
    /// lines after each track); @p last: at the end of the run (the open
    /// record and the probe lines '_end'). Collective.
    void
    record_tracks(const double               t,
                  const double               dt,
                  const bool                 last,
                  const MaterialPoints<dim> &points,
                  TimerOutput               &timer,
                  const ConditionalOStream  &pcout);

    /// The open window of layer_cost.csv so far, on this rank, handed from
    /// a run that ends for a rebalance to the one that resumes it in the
    /// same process (start_cost()), so that the layer's row covers the
    /// whole layer: its start, steps, walls and parts so far, and the
    /// rebalance's wall (its checkpoint, the set-up and the restore; the
    /// column wall_rebalance).
    struct CostCarry
    {
      unsigned int                  layer   = 0;
      double                        t_start = 0, wall = 0;
      double                        steps = 0, solid_steps = 0, flow_steps = 0;
      std::map<std::string, double> parts;
      double                        rebalance_wall = 0;
      /// The flow's fluid cells so far (this rank's own ones).
      typename IncompressibleFlow<dim>::FluidLoad fluid;
    };
    /// The cost of each layer (with a layer schedule; layer_cost.csv in
    /// 'Output/Directory', doc/builds.md "Cost and memory"): open the
    /// window of the layer in progress at @p t, macro step @p step (the
    /// start of the run, or the resume: then the rows of the layers that
    /// ended before it are read back from the file and the row of the
    /// layer in progress counts from the resume, unless @p carried
    /// continues it). Collective.
    void
    start_cost(const double              t,
               const unsigned int        step,
               const bool                resuming,
               const TimerOutput        &timer,
               const SolidSubCycle<dim> *solid,
               const CostCarry          *carried = nullptr);

    /// See CostCarry: the window at macro step @p step (empty, layer 0,
    /// without a layer schedule).
    CostCarry
    carry_cost(const unsigned int        step,
               const TimerOutput        &timer,
               const SolidSubCycle<dim> *solid) const;

    /// The number of the layer that starts in [@p t, @p t + @p dt) (the
    /// step of its recoat); 0: none.
    unsigned int
    layer_starting(const double t, const double dt) const;

    /// Step 0 of the macro step, before the recoat: when a layer starts in
    /// [@p t, @p t + @p dt) (or at the end of the run, @p last), the row of
    /// the layer that ends: its simulated window, the wall time on rank 0
    /// and its largest over the ranks (in total and per part of the step,
    /// as the cost report sums the timer sections), the macro
    /// (temperature) steps, solid steps and melt-flow sub-steps in it, the
    /// melt flow's fluid cells summed over its pressure systems and the
    /// busiest rank's share of them (over the layer and step by step), the
    /// points and the solid's MPM points and finite elements at its start (read
    /// at the window's first call, after its recoat and hand-over), with the
    /// hand-over the cells and points its choice kept as points per class
    /// (FeZoneHandover::Kept); then the next layer's window opens. Collective.
    void
    record_cost(const double               t,
                const double               dt,
                const bool                 last,
                const unsigned int         step,
                const TimerOutput         &timer,
                const MaterialPoints<dim> &points,
                const SolidSubCycle<dim>  *solid);

    /// After the flow, each macro step: the open track's melt extent, and
    /// with the hand-over the lowest melt of the layer.
    void
    observe_tracks() const;

    /// Elements added and points handed over by the hand-over so far
    /// (global; {0, 0} without it).
    std::array<double, 2>
    handed_over() const
    {
      return n_handed;
    }

    /// The track record's state (with 'Build/Track report') as the
    /// checkpoint section "tracks" of @p states, the hand-over's (with
    /// 'Build/Hand over cooled metal') as the section "handover".
    void
    add_state(ModuleStates<dim> &states);

    /// The melt flow whose sub-steps layer_cost.csv counts (null: none).
    void
    watch_flow(const IncompressibleFlow<dim> *flow)
    {
      flow_ptr = flow;
    }

    /// The schedule (null with one layer).
    const LayerSchedule<dim> *
    layers() const
    {
      return schedule.get();
    }

  private:
    const Scene<dim>                    &scene;
    const Laser<dim>                    &laser;
    std::unique_ptr<LayerSchedule<dim>>  schedule;
    std::unique_ptr<Recoater<dim>>       recoater;
    std::unique_ptr<PoreDetector<dim>>   pores;
    std::unique_ptr<TrackRecord<dim>>    tracks;
    std::unique_ptr<FeZoneHandover<dim>> handover;
    // Set by setup(), read by the track record.
    const BackgroundGrid<dim>     *grid_ptr    = nullptr;
    const HeatTransfer<dim>       *heat_ptr    = nullptr;
    ResultsOutput<dim>            *results_ptr = nullptr;
    const IncompressibleFlow<dim> *flow_ptr    = nullptr;
    std::array<double, 2>          n_handed    = {{0., 0.}};
    /// One row of layer_cost.csv (the wall times of rank 0, s, keyed by
    /// their column: wall_<part>; their largest over the ranks:
    /// max_wall_total and max_parts, keyed by wall_<part>).
    struct CostRow
    {
      unsigned int layer   = 1;
      double       t_start = 0, t_end = 0, wall = 0;
      double       steps = 0, solid_steps = 0, flow_steps = 0, max_wall = 0;
      double       points = 0, mpm_points = 0, elements = 0;
      /// The busiest rank's share of the MPM points (1 on one rank).
      double mpm_share_max = 0;
      /// The melt flow's fluid cells summed over the layer's pressure
      /// systems (all ranks); the largest share of them one rank owned
      /// over the layer; the share of the rank owning the most in each
      /// system, averaged with the systems' sizes as weights (the flow's
      /// steps wait for their busiest rank). Both 1 on one rank.
      double fluid_cells = 0, fluid_share_max = 0, fluid_step_share_max = 0;
      std::map<std::string, double> parts, max_parts;
      /// With the hand-over: the cells and points kept as points at the
      /// layer's start per class (kept_cells_<class>, kept_points_<class>;
      /// FeZoneHandover::Kept).
      std::map<std::string, double> kept;
    };
    std::vector<CostRow> cost_rows;
    /// The open window: its row (t_end, walls and steps yet to come), the
    /// clock, the timer's sums and the step counts at its start.
    CostRow                               cost_open;
    bool                                  cost_started = false;
    bool                                  cost_counted = false;
    std::chrono::steady_clock::time_point cost_clock;
    std::map<std::string, double>         cost_sections;
    unsigned int                          cost_step = 0, cost_solid_step = 0;
    double                                cost_flow_step = 0;
    typename IncompressibleFlow<dim>::FluidLoad cost_fluid;
    /// Parts of the open window carried from before a rebalance
    /// (start_cost()), s, keyed by their column.
    std::map<std::string, double> cost_carried;
    /// The flow's sub-steps so far (0 without the flow).
    double
    flow_substeps() const;
    /// The flow's fluid cells so far (zeros without the flow).
    typename IncompressibleFlow<dim>::FluidLoad
    fluid_load() const;
    void
    open_cost(const unsigned int        layer,
              const double              t,
              const unsigned int        step,
              const TimerOutput        &timer,
              const SolidSubCycle<dim> *solid);
    void
    write_cost() const;
    /// The hand-over after the recoat of the layer reaching @p top
    /// (@p layer_start), or within that layer.
    void
    hand_over(const double              t,
              const double              top,
              MaterialPoints<dim>      &points,
              SolidSubCycle<dim>       &solid,
              TimerOutput              &timer,
              const ConditionalOStream &pcout,
              const bool                layer_start);
  };
} // namespace femp

#endif
