// femp: the one list of what a run writes (results_output.h).
#include <deal.II/base/mpi.h>

#include <femp/app/results_output.h>
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
  track_shape_files(TrackShape<dim>           &track,
                    const MaterialPoints<dim> &points,
                    const HeatTransfer<dim>   &heat,
                    const double               liquidus,
                    const std::string         &directory)
  {
    typename ResultsOutput<dim>::Writer w;
    w.fields =
      [&track, &points, &heat, liquidus, directory](const unsigned int n,
                                                    const double       time) {
        const auto sections =
          track.measure(heat.metal_fraction(),
                        track.resolidified_cells(points, liquidus));
        track.write(directory, n, time, sections);
      };
    w.resume = [&track, directory](const double time) {
      track.resume(directory, time);
    };
    return w;
  }

  template class ResultsOutput<2>;
  template class ResultsOutput<3>;
  template <int dim>
  void
  add_heat_output(ResultsOutput<dim>        &results,
                  const HeatTransfer<dim>   &heat,
                  const MaterialPoints<dim> &points,
                  const bool                 heat_enabled,
                  const std::string         &directory,
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
    if (heat_enabled && heat.ray_traced())
      results.add_writer(absorption_series(heat, directory, comm));
  }

  template <int dim>
  std::unique_ptr<TrackShape<dim>>
  add_track_shape(ResultsOutput<dim>                         &results,
                  const typename TrackShape<dim>::Parameters &prm,
                  const BackgroundGrid<dim>                  &grid,
                  const Point<dim>                           &centre,
                  const Laser<dim>                           &laser,
                  const MaterialPoints<dim>                  &points,
                  const HeatTransfer<dim>                    &heat,
                  const double                                substrate_top,
                  const double                                liquidus,
                  const std::string                          &directory)
  {
    // Centre line and default cross-section from the laser's first
    // segment (the middle of the domain without a path).
    Point<dim> a = centre, b = centre;
    if (!laser.segments().empty())
      a = laser.segments().front().start, b = laser.segments().front().end;
    auto track = std::make_unique<TrackShape<dim>>(
      prm, grid, dim == 3 ? a[1] : 0., substrate_top, 0.5 * (a[0] + b[0]));
    results.add_writer(
      track_shape_files(*track, points, heat, liquidus, directory));
    return track;
  }

  template ResultsOutput<2>::Writer
  absorption_series(const HeatTransfer<2> &, const std::string &, MPI_Comm);
  template ResultsOutput<3>::Writer
  absorption_series(const HeatTransfer<3> &, const std::string &, MPI_Comm);
  template ResultsOutput<2>::Writer
  track_shape_files(TrackShape<2> &,
                    const MaterialPoints<2> &,
                    const HeatTransfer<2> &,
                    double,
                    const std::string &);
  template ResultsOutput<3>::Writer
  track_shape_files(TrackShape<3> &,
                    const MaterialPoints<3> &,
                    const HeatTransfer<3> &,
                    double,
                    const std::string &);
  template void
  add_heat_output(ResultsOutput<2> &,
                  const HeatTransfer<2> &,
                  const MaterialPoints<2> &,
                  bool,
                  const std::string &,
                  MPI_Comm);
  template void
  add_heat_output(ResultsOutput<3> &,
                  const HeatTransfer<3> &,
                  const MaterialPoints<3> &,
                  bool,
                  const std::string &,
                  MPI_Comm);
  template std::unique_ptr<TrackShape<2>>
  add_track_shape(ResultsOutput<2> &,
                  const TrackShape<2>::Parameters &,
                  const BackgroundGrid<2> &,
                  const Point<2> &,
                  const Laser<2> &,
                  const MaterialPoints<2> &,
                  const HeatTransfer<2> &,
                  double,
                  double,
                  const std::string &);
  template std::unique_ptr<TrackShape<3>>
  add_track_shape(ResultsOutput<3> &,
                  const TrackShape<3>::Parameters &,
                  const BackgroundGrid<3> &,
                  const Point<3> &,
                  const Laser<3> &,
                  const MaterialPoints<3> &,
                  const HeatTransfer<3> &,
                  double,
                  double,
                  const std::string &);
} // namespace femp
