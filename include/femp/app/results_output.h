// femp: what a run writes, in one list: the cell fields (each registered
// once by the module that owns it, with where it goes: the probe series,
// the probe lines, the field files), the fields computed only when output
// is written (phase, zone, the solid's stresses), and the extra files
// written beside them (ray-traced absorption, track shape, thermal
// history). Each module's output is registered by one call
// (add_heat_output(), add_flow_output(), add_solid_output(),
// add_track_shape(), add_thermal_history()); the time series, with the
// melt pool of the workpiece (workpiece_melt_pool()), and the field output
// are written when the SimulationControl says they are due
// (write_when_due()); the formats are Output's.
#ifndef femp_results_output_h
#define femp_results_output_h

#include <deal.II/base/timer.h>

#include <femp/app/module_states.h>
#include <femp/app/scene.h>
#include <femp/app/simulation_control.h>
#include <femp/flow/incompressible_flow.h>
#include <femp/grid/background_grid.h>
#include <femp/grid/material_points.h>
#include <femp/grid/metal_bodies.h>
#include <femp/heat/heat_transfer.h>
#include <femp/heat/melt_pool.h>
#include <femp/io/output.h>
#include <femp/io/track_shape.h>
#include <femp/solid/solid_sub_cycle.h>

#include <fstream>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace femp
{
  using namespace dealii;

  template <int dim>
  class ResultsOutput
  {
  public:
    /// Where a field goes; each reach includes the ones after it.
    enum class Reach
    {
      probes, ///< the probe-point series (columns), probe lines, field files
      lines,  ///< probe lines and field files
      files   ///< field files only
    };

    /// A file written beside the standard output; every function may be
    /// empty.
    struct Writer
    {
      /// With every row of the time series, at @p time.
      std::function<void(const double time)> series;
      /// With every field output number @p n at @p time.
      std::function<void(const unsigned int n, const double time)> fields;
      /// On resume from a checkpoint at @p time: cut the files back.
      std::function<void(const double time)> resume;
      /// After every temperature step, with the time @p time at its end.
      std::function<void(const double time)> temperature_step;
      /// At the end of the run.
      std::function<void()> finish;
    };

    ResultsOutput(const typename Output<dim>::Parameters &prm,
                  const BackgroundGrid<dim>              &grid,
                  MaterialPoints<dim>                    &points);

    /// A cell field kept by a module (it must outlive this object).
    void
    add_field(const std::string         &name,
              const std::vector<double> &values,
              const Reach                reach,
              const bool                 continuous = true);
    /// Cell fields computed when field output is written: @p compute fills
    /// one vector per name.
    void
    add_fields(
      const std::vector<std::string>                                &names,
      const std::function<void(std::vector<std::vector<double>> &)> &compute,
      const Reach                                                    reach,
      const bool continuous = true);
    /// A file written beside the standard output.
    void
    add_writer(const Writer &w)
    {
      writers.push_back(w);
    }

    /// Open the files (with @p resume: Output's load_state() reopens the
    /// series; the writers are cut back by resume()). Call after every
    /// field with Reach::probes is added.
    void
    initialize(const bool resume);
    /// One row of the time series at @p time with the melt pool @p pool.
    void
    write_series(const double time, const MeltPoolSize &pool);
    /// Field output number @p n at @p time (@p last: the run's last step).
    void
    write_fields(const unsigned int n, const double time, const bool last);
    /// On resume from a checkpoint at @p time.
    void
    resume(const double time);
    /// After a temperature step ending at @p time (the writers that watch
    /// every step).
    void
    after_temperature_step(const double time);
    /// At the end of the run: the writers' last files.
    void
    finish();

    /// The time series and the field output that @p control says are due
    /// after the step just taken, timed on @p timer: a series row with the
    /// melt pool @p pool measures (kept in @p row_pool), the field output
    /// (the last one of the run at the end).
    void
    write_when_due(SimulationControl                   &control,
                   TimerOutput                         &timer,
                   const std::function<MeltPoolSize()> &pool,
                   MeltPoolSize                        &row_pool);
    /// The field output now, numbered and timed by @p control (@p last: the
    /// run's last step), timed on @p timer.
    void
    write_fields(SimulationControl &control,
                 TimerOutput       &timer,
                 const bool         last);
    /// The probe lines alone at @p time, in files named with @p tag
    /// (probe_line_<name>_<tag>.csv).
    void
    write_probe_lines(const std::string &tag, const double time);

    /// The formats' writer (its state goes into a checkpoint).
    Output<dim> &
    output()
    {
      return *out;
    }

  private:
    struct Entry
    {
      std::vector<std::string>                                names;
      const std::vector<double>                              *values = nullptr;
      std::function<void(std::vector<std::vector<double>> &)> compute;
      Reach                                                   reach;
      bool                                                    continuous;
    };
    const typename Output<dim>::Parameters &prm;
    MaterialPoints<dim>                    &points;
    std::unique_ptr<Output<dim>>            out;
    std::vector<Entry>                      entries;
    std::vector<Writer>                     writers;

    /// The fields that reach at least @p reach (kept fields only for
    /// Reach::probes), in the order probes, lines, files; @p computed
    /// holds the values of the computed ones.
    std::vector<typename Output<dim>::Field>
    fields(const Reach reach, std::vector<std::vector<double>> *computed) const;
  };

  /// Ray-traced absorption: absorption.csv in @p directory (rank 0), one
  /// row per time-series row (time, incident, absorbed, escaped power,
  /// absorbed fraction, hits per ray of the last trace).
  template <int dim>
  typename ResultsOutput<dim>::Writer
  absorption_series(const HeatTransfer<dim> &heat,
                    const std::string       &directory,
                    const MPI_Comm           comm);

  /// The track's surface and bead (TrackShape) with every field output;
  /// the writer keeps @p track.
  template <int dim>
  typename ResultsOutput<dim>::Writer
  track_shape_files(const std::shared_ptr<TrackShape<dim>> &track,
                    const MaterialPoints<dim>              &points,
                    const HeatTransfer<dim>                &heat,
                    const double                            liquidus,
                    const std::string                      &directory);

  /// The heat module's output, registered on @p results: T, gamma and
  /// alpha (probes), the laser source, the phase (0 gas, 1 solid, 2 mushy,
  /// 3 liquid) and the points' zone tags (files), and with a ray-traced
  /// laser absorption.csv (absorption_series()) when the @p scene has the
  /// heat transfer on.
  template <int dim>
  void
  add_heat_output(ResultsOutput<dim>        &results,
                  const Scene<dim>          &scene,
                  const HeatTransfer<dim>   &heat,
                  const MaterialPoints<dim> &points,
                  const MPI_Comm             comm);

  /// The flow's output: pressure (Pa) and cell-centred fluid velocity
  /// (m/s), probes.
  template <int dim>
  void
  add_flow_output(ResultsOutput<dim>            &results,
                  const IncompressibleFlow<dim> &flow);

  /// The solid's output (also on the probe lines): sigma_xx, sigma_yy,
  /// sigma_zz, von Mises, equivalent plastic strain (FE element or mean
  /// over the cell's solid points), computed when written.
  template <int dim>
  void
  add_solid_output(ResultsOutput<dim>       &results,
                   const SolidSubCycle<dim> &solid);

  /// The thermal history of every cell for microstructure codes
  /// (ThermalHistory): it watches the temperature after every temperature
  /// step from now on, writes its files at the end of the run and keeps
  /// its state under the checkpoint section 'thermal history' of
  /// @p states; nothing unless the @p scene asks for it.
  template <int dim>
  void
  add_thermal_history(ResultsOutput<dim>        &results,
                      ModuleStates<dim>         &states,
                      const Scene<dim>          &scene,
                      const BackgroundGrid<dim> &grid,
                      const HeatTransfer<dim>   &heat);

  /// The melt pool now (measure_melt_pool()) at the @p scene's liquidus,
  /// solidus and substrate top. Only the workpiece of @p bodies (the metal
  /// attached to the substrate) holds the pool: a detached drop, liquid or
  /// not, is no pool; only the cells from 'Output/Melt pool from x' on
  /// count. Collective.
  template <int dim>
  MeltPoolSize
  workpiece_melt_pool(const Scene<dim>          &scene,
                      const BackgroundGrid<dim> &grid,
                      const HeatTransfer<dim>   &heat,
                      MetalBodies<dim>          &bodies);

  /// The track shape (TrackShape) along the laser's first segment (the
  /// domain's centre without a path), its files registered on @p results
  /// (track_shape_files()); nothing unless the @p scene asks for it.
  template <int dim>
  void
  add_track_shape(ResultsOutput<dim>        &results,
                  const Scene<dim>          &scene,
                  const BackgroundGrid<dim> &grid,
                  const Laser<dim>          &laser,
                  const MaterialPoints<dim> &points,
                  const HeatTransfer<dim>   &heat);
} // namespace femp

#endif
