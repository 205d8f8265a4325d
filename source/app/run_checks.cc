// femp: checks of a scene before any work that span several modules or the
// machine (scene file, output file names, memory, output directory), and
// the run limits; the end-of-run cost report. No paper equations.
#include <deal.II/base/mpi.h>
#include <deal.II/base/utilities.h>

#include <femp/app/physics_switches.h>
#include <femp/app/run_checks.h>
#include <femp/base/input_checks.h>
#include <femp/base/parameter_file.h>
#include <femp/base/parameter_lookup.h>
#include <femp/builds/recoater.h>
#include <femp/heat/laser.h>
#include <femp/io/output.h>
#include <femp/io/output_lock.h>

#include <algorithm>
#include <boost/serialization/map.hpp>
#include <boost/serialization/string.hpp>
#include <boost/serialization/utility.hpp>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <regex>
#include <set>
#include <sstream>

namespace femp
{
  namespace
  {
    RunLimits limits;

    /// Physical memory of this machine in bytes (0 if unknown).
    double
    physical_memory()
    {
      std::ifstream in("/proc/meminfo");
      std::string   key, unit;
      double        kb = 0;
      while (in >> key >> kb >> unit)
        if (key == "MemTotal:")
          return kb * 1024.;
      return 0;
    }
  } // namespace

  std::string
  short_value(const std::string &value)
  {
    if (value.size() <= 80)
      return value;
    return value.substr(0, 60) + " ... (" + std::to_string(value.size()) +
           " characters)";
  }

  void
  check_scene_file(const std::string &file_name)
  {
    namespace fs            = std::filesystem;
    const std::string param = "scene file (command line)";
    std::error_code   error;
    require(fs::exists(file_name, error),
            param,
            short_value(file_name),
            "the file does not exist");
    require(fs::is_regular_file(file_name, error),
            param,
            short_value(file_name),
            "it is not a regular file (a directory?); give a .prm file");
    std::ifstream in(file_name);
    require(static_cast<bool>(in),
            param,
            short_value(file_name),
            "the file cannot be read");

    // JSON and XML scenes: deal.II checks them as a whole.
    const std::string ext = fs::path(file_name).extension().string();
    if (ext == ".json" || ext == ".xml")
      return;

    // Statements of this file (not of the files it includes), with
    // deal.II's syntax: '#' comments, '\' continues a line.
    std::vector<std::string>        sections;
    std::map<std::string, unsigned> set_at; // parameter -> line
    unsigned int                    line_no = 0, statements = 0;
    std::string                     line, pending;
    unsigned int                    pending_line = 0;
    while (std::getline(in, line))
      {
        ++line_no;
        const auto hash = line.find('#');
        if (hash != std::string::npos)
          line.erase(hash);
        line = dealii::Utilities::trim(line);
        if (pending.empty())
          pending_line = line_no;
        if (!line.empty() && line.back() == '\\')
          {
            pending += line.substr(0, line.size() - 1) + " ";
            continue;
          }
        line = dealii::Utilities::trim(pending + line);
        pending.clear();
        if (line.empty())
          continue;
        std::istringstream s(line);
        std::string        word;
        s >> word;
        if (word == "subsection")
          {
            std::string name;
            std::getline(s, name);
            sections.push_back(dealii::Utilities::trim(name));
          }
        else if (word == "end" && !sections.empty())
          sections.pop_back();
        else if (word == "include")
          ++statements;
        else if (word == "set")
          {
            ++statements;
            const auto eq = line.find('=');
            if (eq == std::string::npos)
              continue; // deal.II reports the syntax error
            std::string key;
            for (const auto &sec : sections)
              key += sec + "/";
            key += dealii::Utilities::trim(line.substr(3, eq - 3));
            const auto previous = set_at.find(key);
            require(previous == set_at.end(),
                    key,
                    file_name + ", line " + std::to_string(pending_line),
                    "it is set twice in this file (first at line " +
                      (previous == set_at.end() ?
                         std::string() :
                         std::to_string(previous->second)) +
                      "); set each parameter once (a 'set' after an "
                      "'include' may override an included value)");
            set_at[key] = pending_line;
          }
      }
    require(statements > 0,
            param,
            short_value(file_name),
            "it holds no 'set' or 'include' statement: an empty scene "
            "would silently run the default scene");
  }

  void
  RunLimits::Parameters::add_parameters(ParameterTable &table)
  {
    table.enter_subsection("Run limits");
    table.add(
      "Memory limit",
      memory_limit,
      dealii::Patterns::Double(0.),
      "Largest memory the scene may need, GiB, by a rough estimate from "
      "the number of cells, material points and probe samples made before "
      "any work; a larger scene is refused. 0: the physical memory of this "
      "machine (/proc/meminfo). Range [0, inf).");
    table.add(
      "Disk limit",
      disk_limit,
      dealii::Patterns::Double(0.),
      "Largest output the scene may write, GiB, by a rough estimate from "
      "the cells, the material points written, the number of field outputs "
      "('Output interval', 'End time') and the format, made before any "
      "work; a larger scene is refused. 0: the free space of the file "
      "system that holds 'Output/Directory'. Range [0, inf).");
    table.add(
      "Maximum flow sub-steps",
      max_flow_substeps,
      dealii::Patterns::Integer(1),
      "Most melt-flow sub-steps within one temperature step; the run stops "
      "with an error when the flow needs more (a flow that blows up makes "
      "its stable step tiny). Range [1, inf).");
    table.add("Maximum solid sub-steps",
              max_solid_substeps,
              dealii::Patterns::Integer(1),
              "Most solid sub-steps within one temperature step; a scene whose "
              "elastic step limit would need more is refused before any work. "
              "Range [1, inf).");
    table.add(
      "Progress wall interval",
      progress_wall_interval,
      dealii::Patterns::Double(0.01),
      "Longest wall time without a line of output, s: when the run has "
      "printed nothing for this long (a slow step, a long sub-cycle, "
      "output or a checkpoint being written), rank 0 prints 'femp: still "
      "working: <phase>' with the simulated time, the step and the "
      "sub-step. Range [0.01, inf).");
    table.leave_subsection();
  }

  RunLimits::Parameters
  RunLimits::Parameters::of(const dealii::ParameterHandler &prm)
  {
    // Reading moves only the handler's position, which it restores.
    Parameters     p;
    ParameterTable table(const_cast<dealii::ParameterHandler &>(prm),
                         ParameterTable::Mode::parse);
    p.add_parameters(table);
    return p;
  }

  void
  declare_run_limits(dealii::ParameterHandler &prm)
  {
    RunLimits::Parameters defaults;
    ParameterTable        table(prm, ParameterTable::Mode::declare);
    defaults.add_parameters(table);
  }

  const RunLimits &
  run_limits()
  {
    return limits;
  }

  void
  check_output_file_names(const dealii::ParameterHandler &prm)
  {
    namespace fs = std::filesystem;
    const std::string allowed =
      "a file of the output directory must be named relative to it, "
      "without '..' or an absolute path (Output/Directory may be absolute)";
    for (const std::string name : {"Energy file", "Probe file"})
      {
        const std::string v = parameter_text(prm, "Solid", name);
        const fs::path    p(v);
        bool              ok = !p.is_absolute();
        for (const auto &part : p)
          ok = ok && part != "..";
        require(ok, "Solid/" + name, short_value(v), allowed);
      }
    for (const auto &l : dealii::Utilities::split_string_list(
           parameter_text(prm, "Output", "Probe lines"), ';'))
      {
        const std::string line_name =
          dealii::Utilities::split_string_list(l, ':').front();
        require(std::regex_match(line_name, std::regex("[A-Za-z0-9_.+-]*")) &&
                  line_name.find("..") == std::string::npos,
                "Output/Probe lines",
                short_value(l),
                "a probe line's name becomes part of a file name: use "
                "letters, digits, '_', '-', '+', '.' (no '..')");
      }
  }

  void
  check_values(const dealii::ParameterHandler &prm)
  {
    const int         dim  = std::stoi(parameter_text(prm, "", "Dimension"));
    const std::string text = dealii::Utilities::trim(
      parameter_text(prm, "Heat transfer", "Initial temperature"));
    char        *end = nullptr;
    const double T   = std::strtod(text.c_str(), &end);
    // (An expression is checked at every cell centre by HeatTransfer.)
    if (!text.empty() && end == text.c_str() + text.size())
      require(std::isfinite(T) && T > 0 && T <= 1e5,
              "Heat transfer/Initial temperature",
              short_value(text),
              "it must be a finite temperature in (0, 1e5] K");

    const double packing =
      parameter_double(prm, "Material points/Powder layer", "Packing fraction");
    require(packing > 0 && packing <= 0.64,
            "Material points/Powder layer/Packing fraction",
            packing,
            "it must lie in (0, 0.64] (no powder: 'Layer thickness = 0')");

    const std::string path_file =
      parameter_text(prm, "Laser", "Scan path file");
    // Layers from the scan path need its heights: the line of 'Start
    // point' to 'End point' and the femp format lie at height 0.
    if (parameter_choice(prm,
                         "Build",
                         "Layer schedule",
                         layer_source_names()) == LayerSource::scan_path)
      require(!path_file.empty() &&
                parameter_choice(prm,
                                 "Laser",
                                 "Scan path format",
                                 scan_path_format_choices()) !=
                  ScanPathFormat::femp,
              "Build/Layer schedule",
              "scan path",
              "it needs 'Laser/Scan path file' in a format with heights "
              "(adamantine_segment, adamantine_event_series, additivefoam); "
              "the femp format and the line of 'Laser/Start point' lie at one "
              "height (one layer: 'none'; more: 'times')");
    if (path_file.empty())
      {
        const auto a = dealii::Utilities::split_string_list(
          parameter_text(prm, "Laser", "Start point"), ',');
        const auto b = dealii::Utilities::split_string_list(
          parameter_text(prm, "Laser", "End point"), ',');
        double length2 = 0;
        for (int d = 0; d < dim - 1 && d < int(a.size()) && d < int(b.size());
             ++d)
          {
            const double l = dealii::Utilities::string_to_double(b[d]) -
                             dealii::Utilities::string_to_double(a[d]);
            length2 += l * l;
          }
        require(length2 > 0 || parameter_double(prm, "Laser", "Power") == 0,
                "Laser/End point",
                short_value(parameter_text(prm, "Laser", "End point")),
                "it must differ from 'Laser/Start point' in the horizontal "
                "coordinates: a line scan of zero length takes no time, so "
                "the laser would deposit nothing (power 0 turns it off)");
      }
    else if (parameter_choice(
               prm, "Laser", "Scan path format", scan_path_format_choices()) ==
             ScanPathFormat::femp)
      {
        // Every segment line must hold the numbers of this dimension's
        // format (the 3D format read in 2D would shift every column; the
        // other formats are checked by their reader, heat/scan_path.h).
        std::ifstream in(path_file);
        require(static_cast<bool>(in),
                "Laser/Scan path file",
                short_value(path_file),
                unopened_file(path_file));
        const unsigned int wanted = 2 * (dim - 1) + 2;
        std::string        line;
        unsigned int       line_no = 0;
        while (std::getline(in, line))
          {
            ++line_no;
            const auto first = line.find_first_not_of(" \t\r");
            if (first == std::string::npos || line[first] == '#')
              continue;
            std::istringstream s(line);
            std::string        word;
            unsigned int       n = 0;
            while (s >> word)
              {
                ++n;
                char        *end = nullptr;
                const double x   = std::strtod(word.c_str(), &end);
                require(end != word.c_str() + word.size() ||
                          (std::isfinite(x) && std::abs(x) <= 1e30),
                        "Laser/Scan path file",
                        short_value(path_file) + ", line " +
                          std::to_string(line_no) + ": '" + short_value(line) +
                          "'",
                        "the number '" + word +
                          "' is not finite or beyond 1e30 in magnitude: "
                          "every number of a scan path must be finite, in "
                          "SI units (m, m/s, W)");
              }
            require(n == wanted,
                    "Laser/Scan path file",
                    short_value(path_file) + ", line " +
                      std::to_string(line_no) + ": '" + short_value(line) + "'",
                    "in " + std::to_string(dim) +
                      "D each segment line must hold " +
                      std::to_string(wanted) + " numbers, " +
                      (dim == 2 ? "'x0 x1 speed power'" :
                                  "'x0 y0 x1 y1 speed power'") +
                      "; this line has " + std::to_string(n));
          }
      }
  }

  namespace
  {
    /// Cells of the background grid and metal points (substrate and powder
    /// layer) of a scene, from its parameters, for the estimates below.
    struct SceneSize
    {
      bool   valid  = false;
      double cells  = 0;
      double points = 0;
    };

    SceneSize
    scene_size(const dealii::ParameterHandler &prm)
    {
      SceneSize  size;
      const int  dim = prm.get_integer("Dimension");
      const auto lo  = dealii::Utilities::split_string_list(
        parameter_text(prm, "Background grid", "Lower corner"), ',');
      const auto hi = dealii::Utilities::split_string_list(
        parameter_text(prm, "Background grid", "Upper corner"), ',');
      const double h = parameter_double(prm, "Background grid", "Cell size");
      if (lo.size() < std::size_t(dim) || hi.size() < std::size_t(dim) ||
          !(h > 0))
        return size;
      double cells = 1, area = 1;
      for (int d = 0; d < dim; ++d)
        {
          const double e = dealii::Utilities::string_to_double(hi[d]) -
                           dealii::Utilities::string_to_double(lo[d]);
          if (!(e > 0))
            return size;
          cells *= std::ceil(e / h * (1 - 1e-9));
          if (d < dim - 1)
            area *= e;
        }
      const double bottom = dealii::Utilities::string_to_double(lo[dim - 1]);
      const double spacing =
        parameter_double(prm, "Material points", "Point spacing");
      const double top =
        parameter_double(prm, "Material points", "Substrate top");
      const double layer   = parameter_double(prm,
                                            "Material points/Powder layer",
                                            "Layer thickness");
      const double packing = parameter_double(prm,
                                              "Material points/Powder layer",
                                              "Packing fraction");
      size.valid           = true;
      size.cells           = cells;
      size.points          = spacing > 0 ?
                               area * (std::max(0., top - bottom) + layer * packing) /
                        std::pow(spacing, dim) :
                               0.;
      return size;
    }
  } // namespace

  void
  check_memory(dealii::ParameterHandler &prm, const unsigned int n_ranks)
  {
    const auto   run_limits   = RunLimits::Parameters::of(prm);
    const double limit_gib    = run_limits.memory_limit;
    limits.max_flow_substeps  = run_limits.max_flow_substeps;
    limits.max_solid_substeps = run_limits.max_solid_substeps;
    // Cells of the background grid, metal points (substrate and powder).
    const SceneSize size = scene_size(prm);
    if (!size.valid)
      return; // the modules report malformed corners
    const double cells = size.cells, points = size.points;
    // Probe line samples.
    double samples = 0;
    for (const auto &l : dealii::Utilities::split_string_list(
           parameter_text(prm, "Output", "Probe lines"), ';'))
      {
        const auto parts = dealii::Utilities::split_string_list(l, ':');
        if (parts.size() == 3)
          samples += std::max(0., std::atof(parts[2].c_str()));
      }
    // Bytes per item, measured on the default 3D scene (156 250 cells,
    // 1.05 million points: 0.65 GB) and rounded up; flow and solid add
    // their matrices and point properties.
    const auto   physics = PhysicsSwitches::of(prm);
    const bool   flow    = physics.melt_flow;
    const bool   solid   = physics.solid_stress;
    const double bytes =
      cells * (1500. + (flow ? 1500. : 0.) + (solid ? 1000. : 0.)) +
      points * (400. + (solid ? 300. : 0.)) + samples * 200. + n_ranks * 100e6;
    const double limit =
      limit_gib > 0 ? limit_gib * 1024. * 1024. * 1024. : physical_memory();
    limits.memory_limit = limit;
    if (limit <= 0 || bytes <= limit)
      return;
    std::ostringstream s;
    s.precision(3);
    s << "the scene needs about " << bytes / 1e9 << " GB (" << cells
      << " cells, " << points << " material points, " << samples
      << " probe-line samples, " << n_ranks << " ranks), more than the "
      << limit / 1e9 << " GB allowed: coarsen 'Background grid/Cell size' or "
      << "'Material points/Point spacing', or raise 'Run limits/Memory "
         "limit' (GiB) if the estimate is wrong or the ranks run on several "
         "machines";
    throw InputError("Run limits/Memory limit", num(limit_gib), s.str());
  }

  void
  check_disk(dealii::ParameterHandler &prm)
  {
    const double    limit_gib = RunLimits::Parameters::of(prm).disk_limit;
    const SceneSize size      = scene_size(prm);
    if (!size.valid)
      return; // the modules report malformed corners
    const double cells = size.cells, points = size.points;
    // Field outputs: the first, one per 'Output interval', the last (a
    // step-based cadence is not known before the first step: not counted).
    const double end      = parameter_double(prm, "Time stepping", "End time");
    const double interval = parameter_double(prm, "Output", "Output interval");
    const double outputs =
      2 + (interval > 0 ? std::floor(end / interval * (1 + 1e-12)) : 0.);
    using OutputPrm    = Output<3>::Parameters;
    const auto   which = parameter_choice(prm,
                                        "Output",
                                        "Write material points",
                                        OutputPrm::write_points_names());
    const double point_outputs =
      which == OutputPrm::WritePoints::always ?
        outputs :
        (which == OutputPrm::WritePoints::last ? 1. : 0.);
    // Bytes per cell and per point and output, measured on the VTU output
    // of the 3D scenes (about 45 B per cell with every field, 100 B per
    // point) and rounded up; HDF5 writes about a quarter of that.
    const double format =
      parameter_choice(prm, "Output", "Format", OutputPrm::format_names()) ==
          OutputPrm::Format::hdf5 ?
        0.25 :
        1.;
    const double bytes =
      format * (outputs * cells * 50. + point_outputs * points * 100.);
    double limit = limit_gib * 1024. * 1024. * 1024.;
    if (limit_gib == 0)
      {
        // The free space where the output goes (its nearest existing
        // folder).
        std::filesystem::path dir =
          std::filesystem::absolute(parameter_text(prm, "Output", "Directory"));
        std::error_code ec;
        while (!dir.empty() && !std::filesystem::exists(dir, ec) &&
               dir != dir.root_path())
          dir = dir.parent_path();
        const auto space = std::filesystem::space(dir, ec);
        if (ec)
          return; // unknown: nothing to check against
        limit = double(space.available);
      }
    if (bytes <= limit)
      return;
    std::ostringstream s;
    s.precision(3);
    s << "the scene would write about " << bytes / 1e9 << " GB (" << outputs
      << " field outputs of " << cells << " cells, " << point_outputs
      << " outputs of " << points << " material points, format "
      << parameter_text(prm, "Output", "Format") << "), more than the "
      << limit / 1e9 << " GB "
      << (limit_gib > 0 ? "allowed" : "free where 'Output/Directory' is")
      << ": raise 'Output/Output interval', set 'Output/Write material "
         "points = last' or 'never', use 'Output/Format = hdf5', or raise "
         "'Run limits/Disk limit' (GiB) if the estimate is wrong";
    throw InputError("Run limits/Disk limit", num(limit_gib), s.str());
  }

  void
  prepare_output_directory(const dealii::ParameterHandler &prm,
                           const MPI_Comm                  comm)
  {
    namespace fs                = std::filesystem;
    const std::string directory = parameter_text(prm, "Output", "Directory");
    const bool        refuse =
      parameter_choice(prm,
                       "Output",
                       "Existing directory",
                       Output<3>::Parameters::existing_directory_names());
    std::string error;
    // One run per folder: the lock before anything there is cleared or
    // written (rank 0 takes it; every rank gets the outcome).
    {
      std::error_code ec;
      if (dealii::Utilities::MPI::this_mpi_process(comm) == 0)
        fs::create_directories(directory, ec);
      if (dealii::Utilities::MPI::this_mpi_process(comm) == 0 &&
          !fs::is_directory(directory, ec))
        error = InputError("Output/Directory",
                           short_value(directory),
                           "it cannot be created or is not a directory" +
                             (ec ? " (" + ec.message() + ")" : std::string()))
                  .what();
      error = dealii::Utilities::MPI::broadcast(comm, error, 0);
      if (!error.empty())
        throw std::runtime_error(error);
      std::string       note;
      const std::string refused = OutputLock::acquire(directory, comm, note);
      if (!refused.empty())
        throw InputError("Output/Directory", short_value(directory), refused);
      if (!note.empty())
        std::cerr << note << std::endl;
    }
    if (dealii::Utilities::MPI::this_mpi_process(comm) == 0)
      {
        // Files a run of femp writes: numbered VTU/PVTU pieces or HDF5
        // files, probe lines, the track shape, the .pvd/.xdmf indices,
        // the CSV series, this parameter listing and the timing table.
        const std::regex ours(
          "(grid|points)(_[0-9]+(\\.[0-9]+)?\\.(vtu|pvtu)|\\.pvd)|"
          "(grid|points)(_[0-9]+|_mesh)\\.h5|(grid|points)\\.xdmf|"
          "probe_line_.*_[0-9]+\\.csv|melt_pool\\.csv|probe_points\\.csv|"
          "track_shape_[0-9]+\\.csv|track_bead\\.csv|"
          "absorption\\.csv|parameters\\.prm|timing\\.txt|.*\\.(pvd|xdmf)\\."
          "tmp");
        const std::string energy = parameter_text(prm, "Solid", "Energy file");
        const std::string probes = parameter_text(prm, "Solid", "Probe file");
        std::error_code   ec;
        std::vector<fs::path> earlier;
        if (fs::is_directory(directory, ec))
          for (const auto &entry : fs::directory_iterator(directory, ec))
            {
              const std::string name = entry.path().filename().string();
              if (entry.is_regular_file(ec) &&
                  (std::regex_match(name, ours) || name == energy ||
                   name == probes))
                earlier.push_back(entry.path());
            }
        // Resuming a checkpoint continues this directory's series: they
        // stay (the rows after the checkpoint are dropped on resume).
        if (!parameter_text(prm, "Checkpoint", "Resume from").empty())
          earlier.clear();
        if (!earlier.empty() && refuse)
          error = InputError("Output/Directory",
                             short_value(directory),
                             "it holds the output of an earlier run (e.g. " +
                               earlier.front().filename().string() +
                               ") and 'Output/Existing directory = refuse'; "
                               "choose another directory, remove it, or set "
                               "'Output/Existing directory = clear'")
                    .what();
        if (error.empty() && !earlier.empty())
          for (const auto &f : earlier)
            if (!fs::remove(f, ec) || ec)
              {
                error = "cannot remove '" + f.string() +
                        "' of an earlier run (Output/Existing directory = "
                        "clear): " +
                        ec.message();
                break;
              }
        if (error.empty())
          {
            fs::create_directories(directory, ec);
            if (ec || !fs::is_directory(directory))
              error =
                InputError("Output/Directory",
                           short_value(directory),
                           "it cannot be created or is not a "
                           "directory" +
                             (ec ? " (" + ec.message() + ")" : std::string()))
                  .what();
          }
        if (error.empty())
          {
            const std::string file = directory + "/parameters.prm";
            std::ofstream     out(file);
            out << "# Parameters of this run of femp (all of them, with the "
                   "values used).\n";
            const_cast<dealii::ParameterHandler &>(prm).print_parameters(
              out,
              dealii::ParameterHandler::OutputStyle(
                dealii::ParameterHandler::ShortPRM |
                dealii::ParameterHandler::KeepDeclarationOrder));
            out.close();
            if (!out)
              error = "cannot write '" + file + "'";
          }
      }
    error = dealii::Utilities::MPI::broadcast(comm, error, 0);
    if (!error.empty())
      throw std::runtime_error(error);
  }

  namespace
  {
    /// When the program (the library) started: the total of the cost
    /// report.
    const auto program_start = std::chrono::steady_clock::now();

  } // namespace

  std::string
  part_of(const std::string &section)
  {
    if (section.rfind("flow: ", 0) == 0)
      return "melt flow";
    if (section.rfind("setup: ", 0) == 0)
      return "setup";
    return section;
  }

  void
  add_timer_sums(const dealii::TimerOutput &timer, TimerSums &sums)
  {
    const auto wall =
      timer.get_summary_data(dealii::TimerOutput::total_wall_time);
    const auto calls = timer.get_summary_data(dealii::TimerOutput::n_calls);
    for (const auto &[name, t] : wall)
      {
        sums[name].first += t;
        sums[name].second +=
          calls.count(name) ? (unsigned int) calls.at(name) : 0u;
      }
  }

  void
  print_cost_report(const dealii::TimerOutput &timer,
                    const std::string         &directory,
                    const MPI_Comm             comm,
                    const TimerSums           &earlier)
  {
    using Sections = TimerSums;
    Sections mine  = earlier;
    add_timer_sums(timer, mine);
    const double total = std::chrono::duration<double>(
                           std::chrono::steady_clock::now() - program_start)
                           .count();
    const auto all = dealii::Utilities::MPI::gather(comm, mine, 0);
    if (dealii::Utilities::MPI::this_mpi_process(comm) != 0)
      return;
    const unsigned int n_ranks = all.size();

    // The screen: the slowest rank's time per part.
    std::map<std::string, double> part_max;
    for (const auto &rank : all)
      {
        std::map<std::string, double> part;
        for (const auto &[name, tc] : rank)
          part[part_of(name)] += tc.first;
        for (const auto &[name, t] : part)
          part_max[name] = std::max(part_max[name], t);
      }
    std::vector<std::pair<double, std::string>> parts;
    for (const auto &[name, t] : part_max)
      parts.emplace_back(t, name);
    std::sort(parts.rbegin(), parts.rend());
    std::ostringstream s;
    s << std::fixed;
    s << "Wall time: " << std::setprecision(1) << total << " s";
    if (n_ranks > 1)
      s << " on " << n_ranks << " ranks (each part: its slowest rank)";
    s << "\n";
    double timed = 0;
    for (const auto &[t, name] : parts)
      timed += t;
    // What no section times on the slowest ranks: the scene's reading and
    // checks, the step choice, the progress lines, the end report.
    parts.emplace_back(std::max(0., total - timed), "other (not timed)");
    for (const auto &[t, name] : parts)
      s << "  " << std::left << std::setw(20) << name << std::right
        << std::setw(10) << std::setprecision(t < 10 ? 2 : 1) << t << " s"
        << std::setw(7) << std::setprecision(1)
        << (total > 0 ? 100 * t / total : 0.) << " %\n";
    s << "  (per section and rank: " << directory << "/timing.txt)\n";
    std::cout << s.str() << std::flush;

    // The file: every section over the ranks.
    std::set<std::string> names;
    for (const auto &rank : all)
      for (const auto &[name, tc] : rank)
        names.insert(name);
    std::ofstream f(directory + "/timing.txt");
    f << "# femp: wall time per timer section over the " << n_ranks
      << " rank(s), s; total since start " << std::setprecision(6) << total
      << " s (rank 0). Columns: section, calls (rank 0), min, rank of min, "
         "average, max, rank of max (a rank without the section counts "
         "0)\n";
    f << std::left << std::setw(34) << "section" << std::right << std::setw(10)
      << "calls" << std::setw(12) << "min" << std::setw(6) << "rank"
      << std::setw(12) << "average" << std::setw(12) << "max" << std::setw(6)
      << "rank"
      << "\n";
    for (const auto &name : names)
      {
        double       lo = std::numeric_limits<double>::max(), hi = -1, sum = 0;
        unsigned int r_lo = 0, r_hi = 0;
        for (unsigned int r = 0; r < n_ranks; ++r)
          {
            const auto   it = all[r].find(name);
            const double t  = it == all[r].end() ? 0. : it->second.first;
            sum += t;
            if (t < lo)
              lo = t, r_lo = r;
            if (t > hi)
              hi = t, r_hi = r;
          }
        const auto   it0 = all[0].find(name);
        const double n0  = it0 == all[0].end() ? 0 : it0->second.second;
        f << std::left << std::setw(34) << name << std::right << std::setw(10)
          << n0 << std::setprecision(4) << std::setw(12) << lo << std::setw(6)
          << r_lo << std::setw(12) << sum / n_ranks << std::setw(12) << hi
          << std::setw(6) << r_hi << "\n";
      }
  }
} // namespace femp
