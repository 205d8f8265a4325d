// femp: the one list of what a run writes (results_output.h).
#include <deal.II/base/mpi.h>

#include <femp/app/results_output.h>
#include <femp/base/free_heap.h>
#include <femp/base/input_checks.h>

#include <iomanip>

namespace femp
{
  template <int dim>
  ResultsOutput<dim>::ResultsOutput(const typename Output<dim>::Parameters &prm,
                                    const BackgroundGrid<dim> &grid,
                                    MaterialPoints<dim>       &points)
      : prm(prm)
      , points(points)
      , out(std::make_unique<Output<dim>>(prm, grid))
  {
  }

  template <int dim>
  void
  ResultsOutput<dim>::add_field(const std::string         &name,
                                const std::vector<double> &values,
                                const Reach                reach,
                                const bool                 continuous)
  {
    entries.push_back({{name}, &values, {}, reach, continuous});
  }

  template <int dim>
  void
  ResultsOutput<dim>::add_fields(
    const std::vector<std::string>                                &names,
    const std::function<void(std::vector<std::vector<double>> &)> &compute,
    const Reach                                                    reach,
    const bool                                                     continuous)
  {
    AssertThrow(reach != Reach::probes,
                ExcMessage("a computed field cannot be a probe series column"));
    entries.push_back({names, nullptr, compute, reach, continuous});
  }

  template <int dim>
  std::vector<typename Output<dim>::Field>
  ResultsOutput<dim>::fields(const Reach                       reach,
                             std::vector<std::vector<double>> *computed) const
  {
    std::vector<typename Output<dim>::Field> f;
    for (const Reach r : {Reach::probes, Reach::lines, Reach::files})
      {
        if (static_cast<int>(r) > static_cast<int>(reach))
          break;
        for (const auto &e : entries)
          if (e.reach == r)
            {
              if (e.values)
                f.push_back({e.names[0], e.values, e.continuous});
              else if (computed)
                {
                  std::vector<std::vector<double>> v;
                  e.compute(v);
                  for (std::size_t i = 0; i < e.names.size(); ++i)
                    {
                      computed->push_back(std::move(v[i]));
                      f.push_back({e.names[i], nullptr, e.continuous});
                    }
                }
            }
      }
    // The computed values' addresses, once the list holds them all.
    if (computed)
      {
        std::size_t k = 0;
        for (auto &field : f)
          if (!field.values)
            field.values = &(*computed)[k++];
      }
    return f;
  }

  template <int dim>
  void
  ResultsOutput<dim>::initialize(const bool resume)
  {
    std::vector<std::string> names;
    for (const auto &f : fields(Reach::probes, nullptr))
      names.push_back(f.name);
    out->initialize(names, resume);
  }

  template <int dim>
  void
  ResultsOutput<dim>::write_series(const double time, const MeltPoolSize &pool)
  {
    out->write_series(time, fields(Reach::probes, nullptr), pool);
    for (const auto &w : writers)
      if (w.series)
        w.series(time);
  }

  template <int dim>
  void
  ResultsOutput<dim>::write_probe_lines(const std::string &tag,
                                        const double       time)
  {
    if (prm.probe_lines.empty())
      return;
    std::vector<std::vector<double>> computed;
    computed.reserve(32); // addresses kept in the field list
    out->write_probe_lines(tag, time, fields(Reach::lines, &computed));
  }

  template <int dim>
  void
  ResultsOutput<dim>::write_fields(const unsigned int n,
                                   const double       time,
                                   const bool         last)
  {
    points.flush_point_temperatures();
    std::vector<std::vector<double>> computed;
    computed.reserve(32); // addresses kept in the field list
    const auto all = fields(Reach::files, &computed);
    std::vector<typename Output<dim>::Field> lines;
    {
      // Probe lines: the fields that reach them (the list's first part).
      std::size_t n_lines = 0;
      for (const auto &e : entries)
        if (e.reach != Reach::files)
          n_lines += e.names.size();
      lines.assign(all.begin(), all.begin() + n_lines);
    }
    const bool with_points =
      points.carried() &&
      (prm.write_points == Output<dim>::Parameters::WritePoints::always ||
       (prm.write_points == Output<dim>::Parameters::WritePoints::last &&
        last));
    out->write_fields(n,
                      time,
                      all,
                      with_points ? &points.particle_handler() : nullptr,
                      points.used_property_names());
    out->write_probe_lines(n, time, lines);
    for (const auto &w : writers)
      if (w.fields)
        w.fields(n, time);
  }

  template <int dim>
  void
  ResultsOutput<dim>::resume(const double time)
  {
    for (const auto &w : writers)
      if (w.resume)
        w.resume(time);
  }

  template <int dim>
  void
  ResultsOutput<dim>::after_temperature_step(const double time)
  {
    for (const auto &w : writers)
      if (w.temperature_step)
        w.temperature_step(time);
  }

  template <int dim>
  void
  ResultsOutput<dim>::finish()
  {
    for (const auto &w : writers)
      if (w.finish)
        w.finish();
  }

  template <int dim>
  void
  ResultsOutput<dim>::write_when_due(SimulationControl &control,
                                     TimerOutput       &timer,
                                     const std::function<MeltPoolSize()> &pool,
                                     MeltPoolSize &row_pool)
  {
    if (control.series_due())
      {
        TimerOutput::Scope t(timer, "time series");
        row_pool = pool();
        write_series(control.time(), row_pool);
        control.series_written();
      }
    if (control.output_due())
      write_fields(control, timer, control.is_last());
  }

  template <int dim>
  void
  ResultsOutput<dim>::write_fields(SimulationControl &control,
                                   TimerOutput       &timer,
                                   const bool         last)
  {
    TimerOutput::Scope t(timer, "output");
    write_fields(control.output_number(), control.time(), last);
    // The fields computed for the files and the writers' buffers are freed.
    release_free_heap();
    control.output_written();
  }

  template <int dim>
  typename ResultsOutput<dim>::Writer
  absorption_series(const HeatTransfer<dim> &heat,
                    const std::string       &directory,
                    const MPI_Comm           comm)
  {
    if (Utilities::MPI::this_mpi_process(comm) != 0)
      return {};
    auto csv  = std::make_shared<std::unique_ptr<std::ofstream>>();
    auto name = directory + "/absorption.csv";
    typename ResultsOutput<dim>::Writer w;
    w.series = [csv, name, directory, &heat](const double time) {
      if (!*csv)
        {
          *csv = std::make_unique<std::ofstream>(name);
          **csv << "time,incident,absorbed,escaped,absorbed_fraction,"
                   "hits_per_ray\n";
        }
      // The last trace: of the step that ended at this time.
      const auto &r = heat.last_trace();
      **csv << std::setprecision(8) << time << ',' << r.incident << ','
            << r.absorbed << ',' << r.escaped << ','
            << (r.incident > 0 ? r.absorbed / r.incident : 0.) << ','
            << double(r.n_hits) / std::max(1u, r.n_rays) << '\n';
      (*csv)->flush();
      require(bool(**csv),
              "Output/Directory",
              directory,
              "absorption.csv cannot be written there");
    };
    w.resume = [csv, name](const double time) {
      *csv = std::make_unique<std::ofstream>();
      reopen_series_at(**csv, name, time);
      if (!(*csv)->is_open())
        csv->reset();
    };
    return w;
  }

  template <int dim>
  typename ResultsOutput<dim>::Writer
  track_shape_files(const std::shared_ptr<TrackShape<dim>> &track,
                    const MaterialPoints<dim>              &points,
                    const HeatTransfer<dim>                &heat,
                    const double                            liquidus,
                    const std::string                      &directory)
  {
    typename ResultsOutput<dim>::Writer w;
    w.fields =
      [track, &points, &heat, liquidus, directory](const unsigned int n,
                                                   const double       time) {
        const auto sections =
          track->measure(heat.metal_fraction(),
                         track->resolidified_cells(points, liquidus));
        track->write(directory, n, time, sections);
      };
    w.resume = [track, directory](const double time) {
      track->resume(directory, time);
    };
    return w;
  }

  template class ResultsOutput<2>;
  template class ResultsOutput<3>;
  template <int dim>
  void
  add_heat_output(ResultsOutput<dim>        &results,
                  const Scene<dim>          &scene,
                  const HeatTransfer<dim>   &heat,
                  const MaterialPoints<dim> &points,
                  const MPI_Comm             comm)
  {
    using Reach = typename ResultsOutput<dim>::Reach;
    // Columns of the probe series, probe lines and field files: in the
    // order of registration within each reach.
    results.add_field("T", heat.temperature(), Reach::probes);
    results.add_field("gamma", heat.liquid_fraction(), Reach::probes);
    results.add_field("alpha", heat.metal_fraction(), Reach::probes);
    results.add_field("laser_source", heat.laser_source(), Reach::files);
    // The phase and the zone tags of the points (tags: never
    // interpolated).
    results.add_fields(
      {"phase", "zone"},
      [&heat, &points](std::vector<std::vector<double>> &v) {
        const auto         &a = heat.metal_fraction();
        const auto         &g = heat.liquid_fraction();
        std::vector<double> phase(a.size(), 0.);
        for (std::size_t i = 0; i < phase.size(); ++i)
          phase[i] = a[i] <= 0 ? 0 : (g[i] <= 0 ? 1 : (g[i] < 1 ? 2 : 3));
        v.clear();
        v.push_back(std::move(phase));
        v.push_back(points.zone_tags(a, heat.temperature()));
      },
      Reach::files,
      false);
    if (scene.heat_enabled && heat.ray_traced())
      results.add_writer(absorption_series(heat, scene.output.directory, comm));
  }

  template <int dim>
  void
  add_flow_output(ResultsOutput<dim>            &results,
                  const IncompressibleFlow<dim> &flow)
  {
    using Reach                   = typename ResultsOutput<dim>::Reach;
    static const char *u_names[3] = {"u_x", "u_y", "u_z"};
    results.add_field("p", flow.pressure(), Reach::probes);
    for (int d = 0; d < dim; ++d)
      results.add_field(u_names[d], flow.cell_velocity()[d], Reach::probes);
  }

  template <int dim>
  void
  add_solid_output(ResultsOutput<dim> &results, const SolidSubCycle<dim> &solid)
  {
    results.add_fields(
      SolidSubCycle<dim>::cell_field_names(),
      [&solid](std::vector<std::vector<double>> &v) { solid.cell_fields(v); },
      ResultsOutput<dim>::Reach::lines);
  }

  template <int dim>
  void
  add_track_shape(ResultsOutput<dim>        &results,
                  const Scene<dim>          &scene,
                  const BackgroundGrid<dim> &grid,
                  const Laser<dim>          &laser,
                  const MaterialPoints<dim> &points,
                  const HeatTransfer<dim>   &heat)
  {
    if (!scene.track.enabled(scene.melt_flow))
      return;
    // Centre line and default cross-section from the laser's first
    // segment (the middle of the domain without a path).
    const Point<dim> centre =
      0.5 * (scene.grid.lower_corner + scene.grid.upper_corner);
    Point<dim> a = centre, b = centre;
    if (!laser.segments().empty())
      a = laser.segments().front().start, b = laser.segments().front().end;
    const auto track =
      std::make_shared<TrackShape<dim>>(scene.track,
                                        grid,
                                        dim == 3 ? a[1] : 0.,
                                        scene.points.substrate_top,
                                        0.5 * (a[0] + b[0]));
    results.add_writer(track_shape_files(
      track, points, heat, scene.material.liquidus, scene.output.directory));
  }

  template <int dim>
  void
  add_thermal_history(ResultsOutput<dim>        &results,
                      ModuleStates<dim>         &states,
                      const Scene<dim>          &scene,
                      const BackgroundGrid<dim> &grid,
                      const HeatTransfer<dim>   &heat)
  {
    if (!scene.history.enabled)
      return;
    const auto history =
      std::make_shared<ThermalHistory<dim>>(grid,
                                            scene.material.solidus,
                                            scene.material.liquidus,
                                            heat.temperature(),
                                            heat.metal_fraction(),
                                            0.);
    typename ResultsOutput<dim>::Writer w;
    w.temperature_step = [history, &heat](const double time) {
      history->observe(heat.temperature(), heat.metal_fraction(), time);
    };
    const std::string directory = scene.output.directory;
    w.finish = [history, directory] { history->write(directory); };
    results.add_writer(w);
    states.add("thermal history",
               *history,
               "it was written without 'Thermal history/Enable' (the "
               "history before it is lost)");
  }

  template <int dim>
  MeltPoolSize
  workpiece_melt_pool(const Scene<dim>          &scene,
                      const BackgroundGrid<dim> &grid,
                      const HeatTransfer<dim>   &heat,
                      MetalBodies<dim>          &bodies)
  {
    return measure_melt_pool(grid,
                             heat.temperature(),
                             heat.metal_fraction(),
                             scene.material.liquidus,
                             scene.points.substrate_top,
                             scene.material.solidus,
                             &bodies.workpiece_cells(),
                             scene.output.melt_pool_from_x);
  }

  template ResultsOutput<2>::Writer
  absorption_series(const HeatTransfer<2> &, const std::string &, MPI_Comm);
  template ResultsOutput<3>::Writer
  absorption_series(const HeatTransfer<3> &, const std::string &, MPI_Comm);
  template MeltPoolSize
  workpiece_melt_pool(const Scene<2> &,
                      const BackgroundGrid<2> &,
                      const HeatTransfer<2> &,
                      MetalBodies<2> &);
  template MeltPoolSize
  workpiece_melt_pool(const Scene<3> &,
                      const BackgroundGrid<3> &,
                      const HeatTransfer<3> &,
                      MetalBodies<3> &);
#define FEMP_INSTANTIATE(D)                                     \
  template ResultsOutput<D>::Writer track_shape_files(          \
    const std::shared_ptr<TrackShape<D>> &,                     \
    const MaterialPoints<D> &,                                  \
    const HeatTransfer<D> &,                                    \
    double,                                                     \
    const std::string &);                                       \
  template void add_heat_output(ResultsOutput<D> &,             \
                                const Scene<D> &,               \
                                const HeatTransfer<D> &,        \
                                const MaterialPoints<D> &,      \
                                MPI_Comm);                      \
  template void add_flow_output(ResultsOutput<D> &,             \
                                const IncompressibleFlow<D> &); \
  template void add_solid_output(ResultsOutput<D> &,            \
                                 const SolidSubCycle<D> &);     \
  template void add_track_shape(ResultsOutput<D> &,             \
                                const Scene<D> &,               \
                                const BackgroundGrid<D> &,      \
                                const Laser<D> &,               \
                                const MaterialPoints<D> &,      \
                                const HeatTransfer<D> &);       \
  template void add_thermal_history(ResultsOutput<D> &,         \
                                    ModuleStates<D> &,          \
                                    const Scene<D> &,           \
                                    const BackgroundGrid<D> &,  \
                                    const HeatTransfer<D> &);
  FEMP_INSTANTIATE(2)
  FEMP_INSTANTIATE(3)
#undef FEMP_INSTANTIATE
} // namespace femp
