// femp: VTU/PVTU/PVD output of grid fields and material points, CSV probes
// and the melt-pool time series.
#include <deal.II/base/data_out_base.h>
#include <deal.II/base/mpi.h>
#include <deal.II/base/utilities.h>
#include <deal.II/lac/vector.h>
#include <deal.II/numerics/data_out.h>
#include <deal.II/particles/data_out.h>

#include <femp/base/input_checks.h>
#include <femp/io/checkpoint.h>
#include <femp/io/output.h>

#include <filesystem>
#include <iomanip>

namespace femp
{
  namespace
  {
    /// Throw, naming the file, if a write to @p out failed.
    void
    check_stream(const std::ostream &out, const std::string &file)
    {
      AssertThrow(static_cast<bool>(out),
                  ExcMessage("cannot write the output file '" + file +
                             "' (missing directory, no permission or disk "
                             "full?)"));
    }

    /// Rewrite the ParaView index @p file once every rank has written its
    /// pieces (barrier), atomically: a temporary file renamed over the old
    /// one, so that a reader never sees a half-written index.
    void
    write_pvd(const std::string &                                file,
              const std::vector<std::pair<double, std::string>> &records,
              const MPI_Comm                                     comm)
    {
      const int ierr = MPI_Barrier(comm);
      AssertThrowMPI(ierr);
      if (Utilities::MPI::this_mpi_process(comm) != 0)
        return;
      const std::string tmp = file + ".tmp";
      {
        std::ofstream pvd(tmp);
        DataOutBase::write_pvd_record(pvd, records);
        pvd.close();
        check_stream(pvd, tmp);
      }
      std::error_code error;
      std::filesystem::rename(tmp, file, error);
      AssertThrow(!error, ExcMessage("cannot replace '" + file + "' by '" +
                                     tmp + "': " + error.message()));
    }
  } // namespace


  template <int dim>
  void
  Output<dim>::Parameters::declare_parameters(ParameterHandler &prm)
  {
    prm.enter_subsection("Output");
    prm.declare_entry("Directory", "output", Patterns::Anything(),
                      "Directory for all output files; created if missing. "
                      "A relative path is relative to the working directory; "
                      "an absolute path is allowed. The parameters used are "
                      "written into it as parameters.prm.");
    prm.declare_entry("Existing directory", "clear",
                      Patterns::Selection("clear|refuse"),
                      "What to do when 'Directory' holds the output of an "
                      "earlier run (numbered grid_/points_/probe_line_ "
                      "files, .pvd indices, the CSV series, parameters.prm): "
                      "'clear' removes those files (and no others) before "
                      "the run, so that no stale time step is mixed into the "
                      "new series; 'refuse' stops before any work.");
    prm.declare_entry("Output interval", "1e-4", Patterns::Double(0.),
                      "Simulated time between VTU/PVTU outputs of the fields, "
                      "s; 0 writes only the first and last state. Range [0, inf).");
    prm.declare_entry("Steps between outputs", "0", Patterns::Integer(0),
                      "Also write the fields every this many steps; 0: only "
                      "by 'Output interval'. Range [0, inf).");
    prm.declare_entry("Write material points", "last",
                      Patterns::Selection("always|last|never"),
                      "Write the material points and their properties at every "
                      "field output ('always'), only with the last one "
                      "('last'), or not at all. Point files are large: about "
                      "100 bytes per point.");
    prm.declare_entry("Time series interval", "0", Patterns::Double(0.),
                      "Simulated time between rows of the probe-point and "
                      "melt-pool CSV files, s; 0 writes a row every step.");
    prm.declare_entry("Progress interval", "100", Patterns::Integer(1),
                      "Steps between progress lines on the screen; range [1, inf).");
    prm.declare_entry("Probe points", "", Patterns::Anything(),
                      "Points whose cell values are written to probe_points.csv, "
                      "as coordinate lists (m) separated by ';', e.g. "
                      "'1e-4,2e-4,1e-4; 2e-4,2e-4,1e-4'.");
    prm.declare_entry("Probe lines", "", Patterns::Anything(),
                      "Lines sampled at every field output into "
                      "probe_line_<name>_<n>.csv, separated by ';', each "
                      "'name: x0,y0,z0 -> x1,y1,z1 : samples' (m), e.g. "
                      "'CD: -4e-4,0,-2e-5 -> 4e-4,0,-2e-5 : 201'.");
    prm.leave_subsection();
  }


  template <int dim>
  void
  Output<dim>::Parameters::parse_parameters(ParameterHandler &prm)
  {
    prm.enter_subsection("Output");
    directory         = prm.get("Directory");
    output_interval   = prm.get_double("Output interval");
    write_points      = prm.get("Write material points");
    output_steps      = prm.get_integer("Steps between outputs");
    series_interval   = prm.get_double("Time series interval");
    progress_interval = prm.get_integer("Progress interval");
    probe_points.clear();
    for (const auto &p :
         Utilities::split_string_list(prm.get("Probe points"), ';'))
      probe_points.push_back(parse_point<dim>(p, "Output/Probe points"));
    probe_lines.clear();
    const std::string allowed =
      "each probe line must read 'name: x0,y0,z0 -> x1,y1,z1 : samples' "
      "with at least 2 samples";
    for (const auto &l :
         Utilities::split_string_list(prm.get("Probe lines"), ';'))
      {
        const auto parts = Utilities::split_string_list(l, ':');
        require(parts.size() == 3, "Output/Probe lines", l, allowed);
        const auto ends = parts[1].find("->");
        require(ends != std::string::npos, "Output/Probe lines", l, allowed);
        ProbeLine line;
        line.name  = parts[0];
        line.start = parse_point<dim>(parts[1].substr(0, ends), "Output/Probe lines");
        line.end   = parse_point<dim>(parts[1].substr(ends + 2), "Output/Probe lines");
        int n      = 0;
        try
          {
            n = Utilities::string_to_int(parts[2]);
          }
        catch (...)
          {}
        require(n >= 2, "Output/Probe lines", l, allowed);
        line.n_samples = n;
        probe_lines.push_back(line);
      }
    prm.leave_subsection();
  }


  template <int dim>
  void
  Output<dim>::Parameters::check(const Point<dim> &lo, const Point<dim> &hi) const
  {
    auto inside = [&](const Point<dim> &p) {
      for (int d = 0; d < dim; ++d)
        {
          const double tol = 1e-9 * (hi[d] - lo[d]);
          if (p[d] < lo[d] - tol || p[d] > hi[d] + tol)
            return false;
        }
      return true;
    };
    for (const auto &p : probe_points)
      {
        std::ostringstream s;
        s << p;
        require(inside(p), "Output/Probe points", s.str(),
                "every probe point must lie inside the domain");
      }
    for (const auto &l : probe_lines)
      require(inside(l.start) && inside(l.end), "Output/Probe lines", l.name,
              "both ends of a probe line must lie inside the domain");
  }


  template <int dim>
  Output<dim>::Output(const Parameters &prm, const BackgroundGrid<dim> &grid)
    : prm(prm)
    , grid(grid)
  {}


  template <int dim>
  void
  Output<dim>::initialize(const std::vector<std::string> &quantities,
                          const bool                      resume)
  {
    const MPI_Comm comm = grid.communicator();
    int ok = 1;
    if (Utilities::MPI::this_mpi_process(comm) == 0)
      {
        std::error_code error;
        std::filesystem::create_directories(prm.directory, error);
        ok = !error && std::filesystem::is_directory(prm.directory);
      }
    ok = Utilities::MPI::min(ok, comm);
    require(ok == 1, "Output/Directory", prm.directory,
            "it cannot be created or is not a directory");
    if (Utilities::MPI::this_mpi_process(comm) == 0 && !resume)
      {
        pool_csv.open(prm.directory + "/melt_pool.csv");
        pool_csv << "time,length,width,depth,volume,T_max,"
                    "width_solidus_substrate,depth_solidus_substrate\n";
        check_stream(pool_csv, prm.directory + "/melt_pool.csv");
        if (!prm.probe_points.empty())
          {
            probe_csv.open(prm.directory + "/probe_points.csv");
            probe_csv << "time";
            for (unsigned int i = 0; i < prm.probe_points.size(); ++i)
              for (const auto &q : quantities)
                probe_csv << ",p" << i << "_" << q;
            probe_csv << "\n";
            check_stream(probe_csv, prm.directory + "/probe_points.csv");
          }
      }
    MPI_Barrier(comm);
  }


  template <int dim>
  std::vector<double>
  Output<dim>::sample(const std::vector<Point<dim>> &points,
                      const std::vector<Field> &     fields) const
  {
    // The owner of the cell that contains a point contributes its values;
    // everybody else adds zeros.
    std::vector<double> v(points.size() * fields.size(), 0.);
    for (std::size_t i = 0; i < points.size(); ++i)
      {
        const auto ijk = grid.cell_of(points[i]);
        if (!grid.in_box(ijk))
          continue;
        const auto idx = grid.local_index(ijk);
        if (grid.cell_status()[idx] != BackgroundGrid<dim>::owned)
          continue;
        for (std::size_t f = 0; f < fields.size(); ++f)
          v[i * fields.size() + f] = (*fields[f].values)[idx];
      }
    std::vector<double> global(v.size());
    Utilities::MPI::sum(ArrayView<const double>(v), grid.communicator(),
                        ArrayView<double>(global));
    return global;
  }


  template <int dim>
  void
  Output<dim>::write_fields(const unsigned int                      n,
                            const double                            time,
                            const std::vector<Field> &              fields,
                            const Particles::ParticleHandler<dim> * points,
                            const std::vector<std::string> &        point_names)
  {
    const MPI_Comm comm = grid.communicator();
    const auto &   tria = grid.triangulation();
    {
      DataOut<dim> data_out;
      data_out.attach_triangulation(tria);
      // Only owned cells of the domain (not the triangulation's padding).
      const auto &flat_of = grid.flat_index_of_active_cell();
      auto        wanted  = [&](const typename Triangulation<dim>::cell_iterator &c) {
        return c->is_active() && c->is_locally_owned() &&
               flat_of[c->active_cell_index()] != numbers::invalid_unsigned_int;
      };
      data_out.set_cell_selection(
        [wanted](const Triangulation<dim> &t) {
          for (auto c : t.active_cell_iterators())
            if (wanted(c))
              return typename Triangulation<dim>::cell_iterator(c);
          return t.end();
        },
        [wanted](const Triangulation<dim> &t,
                 const typename Triangulation<dim>::cell_iterator &c) {
          typename Triangulation<dim>::active_cell_iterator next(c);
          for (++next; next != t.end(); ++next)
            if (wanted(next))
              return typename Triangulation<dim>::cell_iterator(next);
          return t.end();
        });
      std::vector<Vector<float>> data(fields.size() + 1,
                                      Vector<float>(tria.n_active_cells()));
      const auto &flat = grid.flat_index_of_active_cell();
      for (const auto &cell : tria.active_cell_iterators())
        if (cell->is_locally_owned() &&
            flat[cell->active_cell_index()] != numbers::invalid_unsigned_int)
          {
            const auto i = cell->active_cell_index();
            for (std::size_t f = 0; f < fields.size(); ++f)
              data[f][i] = (*fields[f].values)[flat[i]];
            data[fields.size()][i] = cell->subdomain_id();
          }
      for (std::size_t f = 0; f < fields.size(); ++f)
        data_out.add_data_vector(data[f], fields[f].name,
                                 DataOut<dim>::type_cell_data);
      data_out.add_data_vector(data[fields.size()], "subdomain",
                               DataOut<dim>::type_cell_data);
      data_out.build_patches();
      DataOutBase::VtkFlags flags;
      flags.time              = time;
      flags.compression_level = DataOutBase::VtkFlags::best_speed;
      data_out.set_flags(flags);
      const std::string name = data_out.write_vtu_with_pvtu_record(
        prm.directory + "/", "grid", n, comm, 5, 8);
      grid_records.emplace_back(time, name);
      write_pvd(prm.directory + "/grid.pvd", grid_records, comm);
    }
    if (points)
      {
        Particles::DataOut<dim> data_out;
        std::vector<DataComponentInterpretation::DataComponentInterpretation>
          interpretation(point_names.size(),
                         DataComponentInterpretation::component_is_scalar);
        data_out.build_patches(*points, point_names, interpretation);
        DataOutBase::VtkFlags flags;
        flags.time              = time;
        flags.compression_level = DataOutBase::VtkFlags::best_speed;
        data_out.set_flags(flags);
        const std::string name = data_out.write_vtu_with_pvtu_record(
          prm.directory + "/", "points", n, comm, 5, 8);
        point_records.emplace_back(time, name);
        write_pvd(prm.directory + "/points.pvd", point_records, comm);
      }
  }


  template <int dim>
  void
  Output<dim>::write_series(const double              time,
                            const std::vector<Field> &probe_fields,
                            const MeltPoolSize &      pool)
  {
    const auto v = sample(prm.probe_points, probe_fields);
    if (Utilities::MPI::this_mpi_process(grid.communicator()) != 0)
      return;
    pool_csv << std::setprecision(8) << time << ',' << pool.length << ','
             << pool.width << ',' << pool.depth << ',' << pool.volume << ','
             << pool.T_max << ',' << pool.solidus_width << ','
             << pool.solidus_depth << '\n';
    pool_csv.flush();
    check_stream(pool_csv, prm.directory + "/melt_pool.csv");
    if (probe_csv.is_open())
      {
        probe_csv << std::setprecision(8) << time;
        for (const double x : v)
          probe_csv << ',' << x;
        probe_csv << '\n';
        probe_csv.flush();
        check_stream(probe_csv, prm.directory + "/probe_points.csv");
      }
  }


  template <int dim>
  void
  Output<dim>::write_probe_lines(const unsigned int        n,
                                 const double              time,
                                 const std::vector<Field> &probe_fields)
  {
    for (const auto &line : prm.probe_lines)
      {
        std::vector<Point<dim>> pts;
        for (unsigned int i = 0; i < line.n_samples; ++i)
          pts.push_back(line.start +
                        (double(i) / (line.n_samples - 1)) * (line.end - line.start));
        const auto v = sample(pts, probe_fields);
        if (Utilities::MPI::this_mpi_process(grid.communicator()) != 0)
          continue;
        const std::string file = prm.directory + "/probe_line_" + line.name +
                                 "_" + Utilities::int_to_string(n, 5) + ".csv";
        std::ofstream     out(file);
        check_stream(out, file);
        out << "# time = " << std::setprecision(8) << time << " s\n";
        out << "s";
        for (int d = 0; d < dim; ++d)
          out << ',' << char('x' + d);
        for (const auto &f : probe_fields)
          out << ',' << f.name;
        out << '\n';
        for (unsigned int i = 0; i < pts.size(); ++i)
          {
            out << pts[i].distance(line.start);
            for (int d = 0; d < dim; ++d)
              out << ',' << pts[i][d];
            for (std::size_t f = 0; f < probe_fields.size(); ++f)
              out << ',' << v[i * probe_fields.size() + f];
            out << '\n';
          }
        out.close();
        check_stream(out, file);
      }
  }

  template <int dim>
  void
  Output<dim>::save_state(StateWriter &out) const
  {
    // Rank 0 holds the records and writes the CSV files (flushed after
    // every row, so their size is what they hold).
    auto records = [&](const std::vector<std::pair<double, std::string>> &r) {
      out.put<std::uint64_t>(r.size());
      for (const auto &[t, name] : r)
        {
          out.put(t);
          out.put_string(name);
        }
    };
    records(grid_records);
    records(point_records);
    // (The size on disk, not tellp(): a stream reopened for appending
    // reports 0 until it writes.)
    const auto size = [&](const std::ofstream &f,
                          const std::string &  name) -> std::uint64_t {
      std::error_code ec;
      const auto      n =
        std::filesystem::file_size(prm.directory + "/" + name, ec);
      return f.is_open() && !ec ? std::uint64_t(n) : 0;
    };
    out.put(size(pool_csv, "melt_pool.csv"));
    out.put(size(probe_csv, "probe_points.csv"));
  }


  template <int dim>
  void
  Output<dim>::load_state(std::vector<StateReader> &parts)
  {
    auto &in      = parts[0];
    auto  records = [&](std::vector<std::pair<double, std::string>> &r) {
      r.resize(in.get<std::uint64_t>());
      for (auto &[t, name] : r)
        {
          t    = in.get<double>();
          name = in.get_string();
        }
    };
    records(grid_records);
    records(point_records);
    const auto pool_size  = in.get<std::uint64_t>();
    const auto probe_size = in.get<std::uint64_t>();
    const MPI_Comm comm   = grid.communicator();
    std::string    error;
    if (Utilities::MPI::this_mpi_process(comm) == 0)
      {
        namespace fs = std::filesystem;
        // Drop the rows written after the checkpoint, then append.
        auto reopen = [&](std::ofstream &f, const std::string &name,
                          const std::uint64_t size) {
          const std::string file = prm.directory + "/" + name;
          std::error_code   ec;
          if (!fs::exists(file) || fs::file_size(file, ec) < size)
            {
              error = "the time series '" + file + "' is missing or shorter "
                      "than at the checkpoint (" + std::to_string(size) +
                      " bytes); resume into the output directory of the run "
                      "that wrote the checkpoint";
              return;
            }
          fs::resize_file(file, size, ec);
          f.open(file, std::ios::app);
          if (ec || !f)
            error = "cannot truncate and reopen '" + file + "'";
        };
        reopen(pool_csv, "melt_pool.csv", pool_size);
        if (error.empty() && !prm.probe_points.empty())
          reopen(probe_csv, "probe_points.csv", probe_size);
      }
    const int ok = Utilities::MPI::min(int(error.empty()), comm);
    if (!ok)
      {
        const auto msg = Utilities::MPI::broadcast(comm, error, 0);
        throw InputError("Checkpoint/Resume from", prm.directory, msg);
      }
    // The indices list the outputs up to the checkpoint (none: removed).
    for (const auto &[name, r] :
         {std::make_pair(std::string("grid.pvd"), &grid_records),
          std::make_pair(std::string("points.pvd"), &point_records)})
      if (!r->empty())
        write_pvd(prm.directory + "/" + name, *r, comm);
      else if (Utilities::MPI::this_mpi_process(comm) == 0)
        {
          std::error_code ec;
          std::filesystem::remove(prm.directory + "/" + name, ec);
        }
  }

  template class Output<2>;
  template class Output<3>;
} // namespace femp
