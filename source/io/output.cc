// femp: Output<dim>, the output of the grid fields and the material points
// as VTU/PVTU pieces with a .pvd index (vtu_pvtu.h), or as HDF5 with an
// XDMF index (hdf5_xdmf.h; grid: the mesh once in grid_mesh.h5, one value
// per cell and field per output in grid_<n>.h5; points: one points_<n>.h5
// per output since they move); the chosen fields and point properties only;
// the CSV probes (probes.cc) and the melt-pool time series. Every index is
// rewritten after a barrier under a temporary name and then renamed, so a
// killed run leaves an index that lists complete files only.
#include <deal.II/base/data_out_base.h>
#include <deal.II/base/mpi.h>
#include <deal.II/base/utilities.h>
#include <deal.II/lac/vector.h>
#include <deal.II/numerics/data_out.h>

#include <femp/base/input_checks.h>
#include <femp/base/parameter_table.h>
#include <femp/base/progress_watchdog.h>
#include <femp/base/state_stream.h>
#include <femp/grid/material_points.h>
#include <femp/io/hdf5_xdmf.h>
#include <femp/io/output.h>
#include <femp/io/output_files.h>
#include <femp/io/vtu_pvtu.h>
#include <femp/solid/solid_sub_cycle.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <iomanip>

namespace femp
{
  namespace
  {
    /// Identifies the partition of @p grid: p4est's cells follow one fixed
    /// order, cut into consecutive pieces, so the number of ranks and
    /// their owned cell counts fix it (FNV-1a over them; never 0).
    /// Collective.
    template <int dim>
    std::uint32_t
    partition_fingerprint(const BackgroundGrid<dim> &grid)
    {
      const auto counts =
        Utilities::MPI::all_gather(grid.communicator(),
                                   std::uint64_t(grid.owned_cells().size()));
      std::uint64_t h   = 1469598103934665603ull;
      auto          mix = [&](std::uint64_t x) {
        for (int b = 0; b < 8; ++b, x >>= 8)
          h = (h ^ (x & 0xff)) * 1099511628211ull;
      };
      mix(counts.size());
      for (const auto c : counts)
        mix(c);
      const std::uint32_t f = std::uint32_t(h ^ (h >> 32));
      return f == 0 ? 1 : f;
    }
  } // namespace

  namespace
  {

    /// Every grid field femp writes (FempProblem::write_output); a run
    /// writes those of the physics it has switched on.
    template <int dim>
    std::vector<std::string>
    known_grid_fields()
    {
      std::vector<std::string> names = {"T", "gamma", "alpha", "p"};
      for (int d = 0; d < dim; ++d)
        names.push_back(std::string("u_") + char('x' + d));
      for (const auto &n : SolidSubCycle<dim>::cell_field_names())
        names.push_back(n);
      for (const char *n : {"laser_source", "phase", "zone", "subdomain"})
        names.push_back(n);
      // With pore detection (builds/pore_detector.h).
      for (const char *n : {"pore", "unfused_powder", "partially_molten"})
        names.push_back(n);
      return names;
    }

    /// Parse 'all' or a comma-separated list of names out of @p known
    /// (empty result: all).
    std::vector<std::string>
    parse_selection(const std::string              &text,
                    const std::vector<std::string> &known,
                    const std::string              &parameter)
    {
      if (Utilities::trim(text) == "all")
        return {};
      std::string allowed = "it must be 'all' or a comma-separated list of";
      for (std::size_t i = 0; i < known.size(); ++i)
        allowed += (i ? ", " : " ") + known[i];
      const auto names = Utilities::split_string_list(text, ',');
      require(!names.empty(), parameter, text, allowed);
      for (const auto &name : names)
        require(std::find(known.begin(), known.end(), name) != known.end(),
                parameter,
                name,
                allowed);
      return names;
    }

  } // namespace

  template <int dim>
  const Choices<typename Output<dim>::Parameters::WritePoints> &
  Output<dim>::Parameters::write_points_names()
  {
    static const Choices<WritePoints> names = {{WritePoints::always, "always"},
                                               {WritePoints::last, "last"},
                                               {WritePoints::never, "never"}};
    return names;
  }

  template <int dim>
  const Choices<typename Output<dim>::Parameters::Format> &
  Output<dim>::Parameters::format_names()
  {
    static const Choices<Format> names = {{Format::vtu, "vtu"},
                                          {Format::hdf5, "hdf5"}};
    return names;
  }

  template <int dim>
  const Choices<bool> &
  Output<dim>::Parameters::existing_directory_names()
  {
    static const Choices<bool> names = {{false, "clear"}, {true, "refuse"}};
    return names;
  }

  template <int dim>
  void
  Output<dim>::Parameters::add_parameters(ParameterTable &table)
  {
    ParameterHandler &prm = table.handler();
    table.enter_subsection("Output");
    table.add("Directory",
              directory,
              Patterns::Anything(),
              "Directory for all output files; created if missing. "
              "A relative path is relative to the working directory; "
              "an absolute path is allowed. The parameters used are "
              "written into it as parameters.prm.");
    table.add("Existing directory",
              refuse_existing,
              existing_directory_names(),
              "What to do when 'Directory' holds the output of an "
              "earlier run (numbered grid_/points_/probe_line_ "
              "files, .pvd indices, the CSV series, parameters.prm): "
              "'clear' removes those files (and no others) before "
              "the run, so that no stale time step is mixed into the "
              "new series; 'refuse' stops before any work.");
    table.add("Output interval",
              output_interval,
              Patterns::Double(0.),
              "Simulated time between VTU/PVTU outputs of the fields, "
              "s; 0 writes only the first and last state. Range [0, inf).");
    table.add("Steps between outputs",
              output_steps,
              Patterns::Integer(0),
              "Also write the fields every this many steps; 0: only "
              "by 'Output interval'. Range [0, inf).");
    table.add("Write material points",
              write_points,
              write_points_names(),
              "Write the material points and their properties at every "
              "field output ('always'), only with the last one "
              "('last'), or not at all. Point files are large: about "
              "100 bytes per point.");
    table.add("Format",
              format,
              format_names(),
              "File format of the grid fields and the material "
              "points: 'vtu' writes compressed VTU pieces (one per "
              "rank or group of ranks) with PVTU records and the "
              "indices grid.pvd, points.pvd; 'hdf5' writes one "
              "compressed HDF5 file per output for all ranks "
              "(MPI-IO: grid_<n>.h5 with one value per cell, the "
              "grid's mesh once in grid_mesh.h5; points_<n>.h5) "
              "with the indices grid.xdmf, points.xdmf (ParaView: "
              "open the .xdmf with the 'XDMF Reader'). Sizes and "
              "write times of both: doc/output.md.");
    if (table.declaring())
      prm.declare_entry("Point properties",
                        "all",
                        Patterns::Anything(),
                        "Material-point properties to write, 'all' or a "
                        "comma-separated list of: mass (kg), volume (m^3), "
                        "temperature (K), state (0 powder, 1 solid, 2 fluid), "
                        "peak_temperature (K), "
                        "velocity_x, velocity_y, velocity_z (m/s), stress_xx, "
                        "stress_yy, stress_zz, stress_xy, stress_xz, stress_yz "
                        "(Pa), plastic_strain (-), viscous_pressure (Pa), "
                        "affine_velocity_xx ... affine_velocity_zz (1/s). "
                        "Properties a scene does not carry (the stresses "
                        "without the solid) are skipped; the point id is "
                        "always written.");
    if (table.declaring())
      prm.declare_entry(
        "Grid fields",
        "all",
        Patterns::Anything(),
        "Grid cell fields to write, 'all' or a comma-separated "
        "list of: T (K), gamma (liquid fraction, -), alpha "
        "(metal fraction, -), p (Pa), u_x, u_y, u_z (m/s), "
        "sigma_xx, sigma_yy, sigma_zz, von_mises (Pa), "
        "plastic_strain (-), laser_source (W/m^3), phase (0 "
        "gas, 1 solid, 2 mushy, 3 liquid), zone (0 gas, 1 "
        "powder, 2 solid, 3 fluid), subdomain (MPI rank); with pore "
        "detection pore (number in pores.csv, 0 outside pores), "
        "unfused_powder, partially_molten (shares, -). Fields of physics a "
        "scene switches off are skipped. Probe lines sample "
        "their fields regardless.");
    table.add("Time series interval",
              series_interval,
              Patterns::Double(0.),
              "Simulated time between rows of the probe-point and "
              "melt-pool CSV files, s; 0 writes a row every step. A scene "
              "without laser power (or without the heat) and without "
              "probe points writes melt_pool.csv at least an 'Output "
              "interval' apart (at the first and the last step when that "
              "is 0).");
    table.add("Progress interval",
              progress_interval,
              Patterns::Integer(1),
              "Steps between progress lines on the screen; range [1, inf).");
    table.add("Melt pool from x",
              melt_pool_from_x_text,
              Patterns::Anything(),
              "The melt pool and the fusion zone of melt_pool.csv are "
              "measured over the cells whose centre x is at least this "
              "value, m (the others count as gas there): for a track "
              "along x, the cross-sections of its start, which a face of "
              "the domain near it may keep hot and wide, are left out. "
              "Empty: the whole domain. Range: below the domain's upper "
              "x.");
    if (table.declaring())
      prm.declare_entry(
        "Probe points",
        "",
        Patterns::Anything(),
        "Points whose cell values are written to probe_points.csv, "
        "as coordinate lists (m) separated by ';', e.g. "
        "'1e-4,2e-4,1e-4; 2e-4,2e-4,1e-4'.");
    table.add("Probe interpolation",
              probe_linear,
              {{false, "cell"}, {true, "linear"}},
              "How probe points and probe lines read the cell fields: "
              "'cell' gives the value of the cell that contains the "
              "sample (piecewise constant, exact cell values); "
              "'linear' interpolates between the nearest cell centres "
              "(bilinear/trilinear), weighting each cell by its metal "
              "fraction, so that an isotherm can be placed inside a "
              "cell. Tags (phase, zone) are never interpolated.");
    if (table.declaring())
      prm.declare_entry("Probe lines",
                        "",
                        Patterns::Anything(),
                        "Lines sampled at every field output into "
                        "probe_line_<name>_<n>.csv, separated by ';', each "
                        "'name: x0,y0,z0 -> x1,y1,z1 : samples' (m), e.g. "
                        "'CD: -4e-4,0,-2e-5 -> 4e-4,0,-2e-5 : 201'.");
    table.leave_subsection();
  }

  template <int dim>
  void
  Output<dim>::Parameters::declare_parameters(ParameterHandler &prm)
  {
    Parameters     defaults;
    ParameterTable table(prm, ParameterTable::Mode::declare);
    defaults.add_parameters(table);
  }

  template <int dim>
  void
  Output<dim>::Parameters::parse_parameters(ParameterHandler &prm)
  {
    ParameterTable table(prm, ParameterTable::Mode::parse);
    add_parameters(table);
    prm.enter_subsection("Output");
    point_properties =
      parse_selection(prm.get("Point properties"),
                      MaterialPoints<dim>::property_names(
                        MaterialPoints<dim>::PropertyIndex::n_properties),
                      "Output/Point properties");
    grid_fields = parse_selection(prm.get("Grid fields"),
                                  known_grid_fields<dim>(),
                                  "Output/Grid fields");

    melt_pool_from_x = -std::numeric_limits<double>::infinity();
    if (!Utilities::trim(melt_pool_from_x_text).empty())
      {
        bool ok = true;
        try
          {
            melt_pool_from_x =
              Utilities::string_to_double(melt_pool_from_x_text);
          }
        catch (...)
          {
            ok = false;
          }
        require(ok && std::isfinite(melt_pool_from_x),
                "Output/Melt pool from x",
                melt_pool_from_x_text,
                "it must be empty (the whole domain) or a position x in m");
      }
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
        line.name = parts[0];
        line.start =
          parse_point<dim>(parts[1].substr(0, ends), "Output/Probe lines");
        line.end =
          parse_point<dim>(parts[1].substr(ends + 2), "Output/Probe lines");
        int n = 0;
        try
          {
            n = Utilities::string_to_int(parts[2]);
          }
        catch (...)
          {
          }
        require(n >= 2, "Output/Probe lines", l, allowed);
        line.n_samples = n;
        probe_lines.push_back(line);
      }
    prm.leave_subsection();
  }

  template <int dim>
  void
  Output<dim>::Parameters::check(const Point<dim> &lo,
                                 const Point<dim> &hi) const
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
        require(inside(p),
                "Output/Probe points",
                s.str(),
                "every probe point must lie inside the domain");
      }
    require(melt_pool_from_x < hi[0],
            "Output/Melt pool from x",
            melt_pool_from_x_text,
            "it must lie below the domain's upper x, " + num(hi[0]) +
              " m (else no cell is measured)");
    for (const auto &l : probe_lines)
      require(inside(l.start) && inside(l.end),
              "Output/Probe lines",
              l.name,
              "both ends of a probe line must lie inside the domain");
  }

  template <int dim>
  Output<dim>::Output(const Parameters &prm, const BackgroundGrid<dim> &grid)
      : prm(prm)
      , grid(grid)
  {
  }

  template <int dim>
  void
  Output<dim>::initialize(const std::vector<std::string> &quantities,
                          const bool                      resume)
  {
    const MPI_Comm comm = grid.communicator();
    int            ok   = 1;
    if (Utilities::MPI::this_mpi_process(comm) == 0)
      {
        std::error_code error;
        std::filesystem::create_directories(prm.directory, error);
        ok = !error && std::filesystem::is_directory(prm.directory);
      }
    ok = Utilities::MPI::min(ok, comm);
    require(ok == 1,
            "Output/Directory",
            prm.directory,
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
  void
  Output<dim>::write_fields(const unsigned int                     n,
                            const double                           time,
                            const std::vector<Field>              &fields,
                            const Particles::ParticleHandler<dim> *points,
                            const std::vector<std::string>        &point_names)
  {
    progress::phase("writing the field output");
    std::vector<Field> chosen;
    for (const auto &f : fields)
      if (selected(prm.grid_fields, f.name))
        chosen.push_back(f);
    write_grid_output(n, time, chosen);
    if (points)
      write_point_output(n, time, *points, point_names);
  }

  template <int dim>
  void
  Output<dim>::write_grid_output(const unsigned int        n,
                                 const double              time,
                                 const std::vector<Field> &fields)
  {
    const MPI_Comm comm = grid.communicator();
    const auto    &tria = grid.triangulation();
    DataOut<dim>   data_out;
    data_out.attach_triangulation(tria);
    // Only owned cells of the domain (not the triangulation's padding).
    const auto &flat_of = grid.flat_index_of_active_cell();
    auto wanted = [&](const typename Triangulation<dim>::cell_iterator &c) {
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
      [wanted](const Triangulation<dim>                         &t,
               const typename Triangulation<dim>::cell_iterator &c) {
        typename Triangulation<dim>::active_cell_iterator next(c);
        for (++next; next != t.end(); ++next)
          if (wanted(next))
            return typename Triangulation<dim>::cell_iterator(next);
        return t.end();
      });
    const bool with_subdomain = selected(prm.grid_fields, "subdomain");
    if (prm.format == Parameters::Format::hdf5)
      {
        // HDF5: the background grid, its partition and the order of the
        // cells never change during a run, so the mesh (node coordinates,
        // cells) is written once, from DataOut's patches with the nodes
        // that cells share merged (DataOutFilter), and each output holds
        // only the cell fields (one value per cell, not per corner as in
        // the VTU pieces). deal.II 9.4's own write_hdf5_parallel and
        // create_xdmf_entry fail when a rank has nothing to write and store
        // only node data, so write_h5() writes the arrays.
        H5Part part;
        part.dim      = dim;
        part.corners  = GeometryInfo<dim>::vertices_per_cell;
        part.compress = true;
        std::vector<unsigned int> flat; // the fields' index of each cell
        for (const auto &cell : tria.active_cell_iterators())
          if (wanted(cell))
            flat.push_back(flat_of[cell->active_cell_index()]);
        part.n_cells = flat.size();
        if (!grid_mesh_written)
          {
            Vector<float> owner(tria.n_active_cells());
            data_out.add_data_vector(owner,
                                     "owner",
                                     DataOut<dim>::type_cell_data);
            data_out.build_patches();
            DataOutBase::DataOutFilter filter(
              DataOutBase::DataOutFilterFlags(true, true));
            data_out.write_filtered_data(filter);
            if (filter.n_nodes() > 0)
              {
                filter.fill_node_data(part.nodes);
                filter.fill_cell_data(0, part.cells);
              }
            part.n_nodes = filter.n_nodes();
          }
        for (const auto &f : fields)
          {
            part.data.push_back({f.name, true, true, {}});
            auto &v = part.data.back().values;
            v.reserve(flat.size());
            for (const auto i : flat)
              v.push_back((*f.values)[i]);
          }
        if (with_subdomain)
          part.data.push_back(
            {"subdomain",
             true,
             true,
             std::vector<double>(flat.size(),
                                 Utilities::MPI::this_mpi_process(comm))});
        const std::string &mesh = grid_mesh_file;
        const std::string  file =
          "grid_" + Utilities::int_to_string(n, 5) + ".h5";
        auto layout = write_h5(prm.directory + "/" + mesh,
                               prm.directory + "/" + file,
                               !grid_mesh_written,
                               part,
                               comm);
        if (!grid_mesh_written)
          {
            grid_mesh_nodes     = layout.nodes;
            grid_mesh_partition = partition_fingerprint(grid);
          }
        layout.nodes      = grid_mesh_nodes;
        grid_mesh_written = true;
        grid_entries.push_back(xdmf_entry(time, mesh, file, part, layout));
        write_xdmf(prm.directory + "/grid.xdmf", grid_entries, comm);
        return;
      }
    std::vector<Vector<float>> data(fields.size() + with_subdomain,
                                    Vector<float>(tria.n_active_cells()));
    for (const auto &cell : tria.active_cell_iterators())
      if (wanted(cell))
        {
          const auto i = cell->active_cell_index();
          for (std::size_t f = 0; f < fields.size(); ++f)
            data[f][i] = (*fields[f].values)[flat_of[i]];
          if (with_subdomain)
            data[fields.size()][i] = cell->subdomain_id();
        }
    for (std::size_t f = 0; f < fields.size(); ++f)
      data_out.add_data_vector(data[f],
                               fields[f].name,
                               DataOut<dim>::type_cell_data);
    if (with_subdomain)
      data_out.add_data_vector(data[fields.size()],
                               "subdomain",
                               DataOut<dim>::type_cell_data);
    data_out.build_patches();
    write_vtu_record(
      data_out, prm.directory, "grid", n, time, grid_records, comm);
  }

  template <int dim>
  void
  Output<dim>::write_point_output(const unsigned int                     n,
                                  const double                           time,
                                  const Particles::ParticleHandler<dim> &points,
                                  const std::vector<std::string> &point_names)
  {
    const MPI_Comm comm = grid.communicator();
    if (prm.format == Parameters::Format::vtu)
      {
        PointPatches<dim> data_out(points, point_names, prm.point_properties);
        write_vtu_record(
          data_out, prm.directory, "points", n, time, point_records, comm);
        return;
      }
    // HDF5: the points move, so each output holds their positions too (as
    // 4-byte floats, like the VTU pieces); no connectivity (Polyvertex);
    // the id as a double (exact), the properties as 4-byte floats.
    H5Part part;
    part.dim          = dim;
    part.corners      = 1;
    part.single_nodes = true;
    part.compress     = true;
    part.n_nodes = part.n_cells = points.n_locally_owned_particles();
    part.data.push_back({"id", false, false, {}});
    std::vector<unsigned int> columns;
    for (unsigned int i = 0; i < point_names.size(); ++i)
      if (selected(prm.point_properties, point_names[i]))
        {
          columns.push_back(i);
          part.data.push_back({point_names[i], true, false, {}});
        }
    part.nodes.reserve(part.n_nodes * dim);
    for (auto &set : part.data)
      set.values.reserve(part.n_nodes);
    for (const auto &point : points)
      {
        for (int d = 0; d < dim; ++d)
          part.nodes.push_back(point.get_location()[d]);
        part.data[0].values.push_back(point.get_id());
        const auto props = point.get_properties();
        for (unsigned int c = 0; c < columns.size(); ++c)
          part.data[c + 1].values.push_back(props[columns[c]]);
      }
    const std::string file = "points_" + Utilities::int_to_string(n, 5) + ".h5";
    const auto        layout = write_h5(
      prm.directory + "/" + file, prm.directory + "/" + file, true, part, comm);
    point_entries.push_back(xdmf_entry(time, file, file, part, layout));
    write_xdmf(prm.directory + "/points.xdmf", point_entries, comm);
  }

  template <int dim>
  void
  Output<dim>::write_series(const double              time,
                            const std::vector<Field> &probe_fields,
                            const MeltPoolSize       &pool)
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
                          const std::string   &name) -> std::uint64_t {
      std::error_code ec;
      const auto n = std::filesystem::file_size(prm.directory + "/" + name, ec);
      return f.is_open() && !ec ? std::uint64_t(n) : 0;
    };
    out.put(size(pool_csv, "melt_pool.csv"));
    out.put(size(probe_csv, "probe_points.csv"));
    // HDF5 output: the XDMF entries written so far and the grid's mesh
    // file (empty with VTU output).
    auto strings = [&](const std::vector<std::string> &v) {
      out.put<std::uint64_t>(v.size());
      for (const auto &x : v)
        out.put_string(x);
    };
    strings(grid_entries);
    strings(point_entries);
    out.put_string(grid_mesh_written ? grid_mesh_file : std::string());
    out.put<std::uint64_t>(grid_mesh_nodes);
    out.put<std::uint32_t>(grid_mesh_partition);
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
    auto       strings    = [&](std::vector<std::string> &v) {
      v.resize(in.get<std::uint64_t>());
      for (auto &x : v)
        x = in.get_string();
    };
    strings(grid_entries);
    strings(point_entries);
    const std::string mesh_file = in.get_string();
    grid_mesh_nodes             = in.get<std::uint64_t>();
    grid_mesh_partition         = in.get<std::uint32_t>();
    const MPI_Comm comm         = grid.communicator();
    if (!mesh_file.empty() &&
        grid_mesh_partition == partition_fingerprint(grid))
      {
        // Same partition: the mesh file stands. (Checkpoints of earlier
        // versions stored the number of ranks here: they get a new mesh
        // file, which is always right.)
        grid_mesh_file    = mesh_file;
        grid_mesh_written = true;
      }
    else
      {
        // None yet, or the cells of this partition lie in another order:
        // the next grid output writes a mesh file of its own (the earlier
        // outputs keep theirs).
        grid_mesh_file = "grid_mesh_" +
                         Utilities::int_to_string(grid_entries.size(), 5) +
                         ".h5";
        grid_mesh_written = false;
      }
    std::string error;
    if (Utilities::MPI::this_mpi_process(comm) == 0)
      {
        namespace fs = std::filesystem;
        // Drop the rows written after the checkpoint, then append.
        auto reopen = [&](std::ofstream      &f,
                          const std::string  &name,
                          const std::uint64_t size) {
          const std::string file = prm.directory + "/" + name;
          std::error_code   ec;
          if (!fs::exists(file) || fs::file_size(file, ec) < size)
            {
              error = "the time series '" + file +
                      "' is missing or shorter "
                      "than at the checkpoint (" +
                      std::to_string(size) +
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
    const auto rewrite =
      [&](const std::string &name, const auto &records, const auto &write) {
        const std::string file = prm.directory + "/" + name;
        if (!records.empty())
          write(file, records, comm);
        else if (Utilities::MPI::this_mpi_process(comm) == 0)
          {
            std::error_code ec;
            std::filesystem::remove(file, ec);
          }
      };
    rewrite("grid.pvd", grid_records, write_pvd);
    rewrite("points.pvd", point_records, write_pvd);
    rewrite("grid.xdmf", grid_entries, write_xdmf);
    rewrite("points.xdmf", point_entries, write_xdmf);
  }

  void
  reopen_series_at(std::ofstream     &stream,
                   const std::string &file,
                   const double       time)
  {
    std::ifstream in(file);
    if (!in)
      return;
    std::string kept, line;
    while (std::getline(in, line))
      {
        char      *end = nullptr;
        const auto t   = std::strtod(line.c_str(), &end);
        // Rows are written with 8 significant digits.
        if (end == line.c_str() || t <= time * (1 + 1e-7))
          kept += line + '\n';
      }
    in.close();
    {
      std::ofstream out(file, std::ios::trunc);
      out << kept;
      out.close();
      AssertThrow(static_cast<bool>(out),
                  ExcMessage("cannot rewrite the time series '" + file +
                             "' on resume"));
    }
    stream.open(file, std::ios::app);
    AssertThrow(static_cast<bool>(stream),
                ExcMessage("cannot reopen the time series '" + file + "'"));
  }

  template class Output<2>;
  template class Output<3>;
} // namespace femp
