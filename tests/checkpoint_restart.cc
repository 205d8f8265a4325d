// Checkpoint and restart (doc/checkpoint.md): the scene argv[1] (dimension
// argv[2]) run straight through, writing checkpoints at half the end time
// and at the end, against the same scene resumed from the half-way
// checkpoint on the straight run's partition ('Checkpoint/Partition on
// resume = scene'): the final checkpoints (every module's raw state),
// the time series, the .pvd indices and the thermal history must be
// bit-identical (on the number of ranks of the test); with the solid also its
// energy and probe files and its final energies (the final checkpoints hold the
// point and element stresses). With 'Build/Hand over cooled metal' the FE zone
// must have risen before the checkpoint resumed, the resumed run must hand
// nothing over again, and the largest differences of the point stresses and
// temperatures, the solid probes and the probe lines against the straight
// run are printed and must be 0. With 'Heat transfer/Metal of melt cells =
// points' the straight run must hold melt cells at the checkpoint (its
// melt_pool.csv) and its flow must have moved points. Then rank 0 alone
// resumes the same checkpoint
// (written by all ranks): the final points, and with the solid the rows of
// its energy and probe files after the checkpoint, must agree with the
// straight run to round-off (argv[3]: the gate; with melt flow the
// pressure solver's preconditioner depends on the partition, so results on
// other rank counts agree to its tolerance only). Last, a corrupt, a
// truncated and two mismatched checkpoints must be refused before any work,
// naming the fault, and with the solid one of another FE zone (without
// an FE zone: one with the zone switched on).
// argv[4], optional, is the output format: with hdf5 the XDMF indices must
// be bit-identical too, and a resume on rank 0 alone (another partition)
// must list every grid output and name mesh files that exist. argv[5],
// optional, is the number of significant digits of the printed summary
// numbers (default 8; fewer for a scene that amplifies round-off, whose
// numbers differ between processors beyond numdiff's tolerance).
#include <deal.II/base/mpi.h>

#include <femp/base/input_checks.h>

#include <filesystem>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <utility>

#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;
namespace fs = std::filesystem;

namespace
{
  std::string
  file_text(const std::string &name, const bool skip_date = false)
  {
    std::ifstream in(name, std::ios::binary);
    std::string   all, line;
    while (std::getline(in, line))
      if (!(skip_date && line.rfind("#This file was generated", 0) == 0))
        all += line + "\n";
    return in.eof() || all.size() ? all : std::string("<missing>");
  }

  /// Largest difference between the numbers of two CSV files of the same
  /// shape, each column relative to its largest magnitude in @p a (1 if
  /// the shapes differ); the rows whose first column is <= @p after are
  /// skipped, and so are lines starting with '#' before the header.
  double
  csv_difference(const std::string &a, const std::string &b, const double after)
  {
    auto rows = [&](const std::string &file) {
      std::vector<std::vector<double>> r;
      std::ifstream                    in(file);
      std::string                      line;
      bool                             header = true;
      while (std::getline(in, line))
        {
          // Comment lines ('#', probe lines), then the header.
          if (line.rfind("#", 0) == 0 || std::exchange(header, false))
            continue;
          std::vector<double> v;
          std::stringstream   s(line);
          std::string         x;
          while (std::getline(s, x, ','))
            v.push_back(std::stod(x));
          if (!v.empty() && v[0] > after * (1 + 1e-9))
            r.push_back(v);
        }
      return r;
    };
    const auto ra = rows(a), rb = rows(b);
    if (ra.size() != rb.size() || ra.empty())
      return 1;
    std::vector<double> scale(ra[0].size(), 1e-300);
    for (const auto &r : ra)
      for (std::size_t j = 0; j < r.size() && j < scale.size(); ++j)
        scale[j] = std::max(scale[j], std::abs(r[j]));
    double diff = 0;
    for (std::size_t i = 0; i < ra.size(); ++i)
      {
        if (ra[i].size() != rb[i].size() || ra[i].size() != scale.size())
          return 1;
        for (std::size_t j = 0; j < ra[i].size(); ++j)
          diff = std::max(diff, std::abs(ra[i][j] - rb[i][j]) / scale[j]);
      }
    return diff;
  }

  /// The two lines of a checkpoint index: latest, previous.
  std::pair<std::string, std::string>
  index_of(const std::string &dir)
  {
    std::ifstream in(dir + "/index");
    std::string   a, b;
    std::getline(in, a);
    std::getline(in, b);
    return {a, b};
  }

  /// The rows of a CSV file with a header line, as column -> value.
  std::vector<std::map<std::string, double>>
  csv_rows(const std::string &name)
  {
    std::ifstream                              in(name);
    std::string                                line;
    std::vector<std::string>                   names;
    std::vector<std::map<std::string, double>> rows;
    if (std::getline(in, line))
      {
        std::istringstream h(line);
        for (std::string c; std::getline(h, c, ',');)
          names.push_back(c);
      }
    while (std::getline(in, line))
      {
        std::istringstream            r(line);
        std::map<std::string, double> row;
        std::size_t                   k = 0;
        for (std::string c; std::getline(r, c, ',') && k < names.size(); ++k)
          row[names[k]] = std::stod(c);
        rows.push_back(row);
      }
    return rows;
  }

  /// The lines the runs appended to scene.log since line @p seen (which
  /// moves on to its end).
  std::vector<std::string>
  new_log_lines(std::size_t &seen)
  {
    std::ifstream            in("scene.log");
    std::vector<std::string> lines;
    std::string              line;
    for (std::size_t i = 0; std::getline(in, line); ++i)
      if (i >= seen)
        lines.push_back(line);
    seen += lines.size();
    return lines;
  }

  /// The simulated time of the checkpoint @p name (its directory, e.g.
  /// step_00000326) that the run of the lines @p log wrote, s; -1 if none.
  double
  checkpoint_time(const std::vector<std::string> &log, const std::string &name)
  {
    const std::regex written("Checkpoint: step [0-9]+, time ([-0-9.e+]+) "
                             "s -> .*" +
                             name);
    std::smatch      m;
    double           t = -1;
    for (const auto &line : log)
      if (std::regex_search(line, m, written))
        t = std::stod(m[1]);
    return t;
  }

  /// Every point (id -> position and properties), gathered on rank 0.
  template <int dim>
  std::map<unsigned long, std::vector<double>>
  gather_points(const femp::MaterialPoints<dim> &points, MPI_Comm comm)
  {
    std::vector<double> mine;
    for (const auto &p : points.particle_handler())
      {
        mine.push_back(p.get_id());
        for (int d = 0; d < dim; ++d)
          mine.push_back(p.get_location()[d]);
        for (const double v : p.get_properties())
          mine.push_back(v);
      }
    const auto all = Utilities::MPI::gather(comm, mine, 0);
    const auto n   = dim + points.n_properties() + 1;
    std::map<unsigned long, std::vector<double>> by_id;
    for (const auto &part : all)
      for (std::size_t i = 0; i + n <= part.size(); i += n)
        by_id[static_cast<unsigned long>(part[i])] =
          std::vector<double>(part.begin() + i + 1, part.begin() + i + n);
    return by_id;
  }

  /// Run @p file with @p overrides on @p comm; the points at the end.
  template <int dim>
  std::map<unsigned long, std::vector<double>>
  run(const std::string                        &file,
      MPI_Comm                                  comm,
      const std::vector<Override>              &overrides,
      typename femp::FempProblem<dim>::Summary *summary = nullptr)
  {
    dealii::ParameterHandler prm;
    parse_scene(prm, file, overrides);
    std::streambuf *old = std::cout.rdbuf();
    std::ofstream   log("scene.log", std::ios::app);
    std::cout.rdbuf(log.rdbuf());
    femp::FempProblem<dim> problem(prm, comm);
    problem.run();
    std::cout.rdbuf(old);
    if (summary)
      *summary = problem.summary();
    return gather_points(problem.material_points(), comm);
  }

  /// The message of the InputError that resuming @p overrides raises, or
  /// "accepted".
  template <int dim>
  std::string
  refusal(const std::string           &file,
          MPI_Comm                     comm,
          const std::vector<Override> &overrides)
  {
    dealii::ParameterHandler prm;
    parse_scene(prm, file, overrides);
    try
      {
        femp::FempProblem<dim> problem(prm, comm);
      }
    catch (const femp::InputError &e)
      {
        return e.what();
      }
    return "accepted";
  }

  template <int dim>
  int
  test(const std::string &scene,
       const double       gate,
       const std::string &format,
       const int          digits,
       MPI_Comm           comm)
  {
    const bool root     = Utilities::MPI::this_mpi_process(comm) == 0;
    int        failures = 0;
    auto       verdict  = [&](const std::string &what, const bool ok) {
      if (root)
        std::cout << what << ": " << (ok ? "yes" : "NO") << std::endl;
      failures += !ok;
    };
    auto print = [&](const std::string &what, const double v) {
      if (root)
        std::cout << what << " = " << std::setprecision(digits) << v
                  << std::endl;
    };
    double end_time, cell_size;
    bool   layers, fe_zone, handover, metal_of_points;
    {
      // The scene as femp reads it ('include' lines too).
      dealii::ParameterHandler prm;
      parse_scene(prm, scene, {});
      prm.enter_subsection("Time stepping");
      end_time = prm.get_double("End time");
      prm.leave_subsection();
      prm.enter_subsection("Build");
      layers   = prm.get("Layer schedule") != "none";
      handover = prm.get_bool("Hand over cooled metal");
      prm.leave_subsection();
      prm.enter_subsection("Physics");
      fe_zone = prm.get_bool("Solid stress");
      prm.leave_subsection();
      prm.enter_subsection("Solid FEM");
      fe_zone = fe_zone && prm.get_bool("Use finite elements");
      prm.leave_subsection();
      prm.enter_subsection("Heat transfer");
      metal_of_points = prm.get("Metal of melt cells") == "points" &&
                        prm.get("Advection by melt flow") == "points";
      prm.leave_subsection();
      prm.enter_subsection("Background grid");
      cell_size = prm.get_double("Cell size");
      prm.leave_subsection();
    }
    const std::vector<Override> common = {
      {"Output", "Format", format},
      {"Output", "Thermal history", "true"},
      {"Output", "Output interval", femp::num(end_time / 3)},
      {"Output", "Write material points", "always"},
      {"Checkpoint", "Every simulated time", femp::num(end_time / 2)}};
    auto with = [&](std::vector<Override> extra) {
      extra.insert(extra.begin(), common.begin(), common.end());
      return extra;
    };
    for (const std::string d : {"out0", "out1", "out2", "bad", "scene.log"})
      if (root)
        fs::remove_all(d);
    MPI_Barrier(comm);
    std::size_t log_seen = 0;

    // Straight through, with the checkpoints.
    typename femp::FempProblem<dim>::Summary s0, s1;
    const auto                               points0 =
      run<dim>(scene, comm, with({{"Output", "Directory", "out0"}}), &s0);
    const auto [last, half] = index_of("out0/checkpoint");
    if (root)
      std::cout << "checkpoints written (index): " << last << ", " << half
                << std::endl;
    const auto log0 = new_log_lines(log_seen);

    // Resumed from the half-way checkpoint, continuing a copy of the
    // output directory (the run killed after its checkpoint), on the
    // partition of the straight run (the scene's: 'Partition on resume =
    // checkpoint' would weigh the cells by the checkpoint's state, and the
    // sums would agree to round-off only; test partition_resume_handover).
    if (root)
      fs::copy("out0", "out1", fs::copy_options::recursive);
    MPI_Barrier(comm);
    const auto points1 =
      run<dim>(scene,
               comm,
               with({{"Output", "Directory", "out1"},
                     {"Checkpoint", "Partition on resume", "scene"},
                     {"Checkpoint", "Resume from", "out1/checkpoint/" + half}}),
               &s1);
    const auto log1       = new_log_lines(log_seen);
    bool       same_state = true;
    for (unsigned int r = 0; r < Utilities::MPI::n_mpi_processes(comm); ++r)
      {
        const std::string f =
          "/" + last + "/rank_" + Utilities::int_to_string(r, 5) + ".bin";
        same_state = same_state && file_text("out0/checkpoint" + f) ==
                                     file_text("out1/checkpoint" + f);
      }
    auto identical = [&](const std::string &what, const bool same) {
      verdict(what + " bit-identical", same);
    };
    identical("final state (checkpoint files of the last step)", same_state);
    for (const std::string f : {"melt_pool.csv",
                                "probe_line_AB_00003.csv",
                                "thermal_history_full_0.csv"})
      identical(f, file_text("out0/" + f) == file_text("out1/" + f));
    // A build (Build/Layer schedule): its pores too (doc/builds.md).
    if (layers)
      for (const std::string f : {"porosity.csv", "pores.csv"})
        identical(f, file_text("out0/" + f) == file_text("out1/" + f));
    for (const std::string f : {"grid.pvd", "points.pvd"})
      identical(f + " (but its date)",
                file_text("out0/" + f, true) == file_text("out1/" + f, true));
    // HDF5 output: the XDMF indices (they name the grid's mesh file).
    for (const std::string f : {"grid.xdmf", "points.xdmf"})
      if (fs::exists("out0/" + f))
        identical(f, file_text("out0/" + f) == file_text("out1/" + f));
    const bool solid = fs::exists("out0/solid_energy.csv");
    if (solid)
      {
        for (const std::string f : {"solid_energy.csv", "solid_probes.csv"})
          identical(f, file_text("out0/" + f) == file_text("out1/" + f));
        // Every output's probe lines (they hold the cell stresses: also
        // those written after a temperature step without a solid step).
        unsigned int n_lines = 0;
        bool         same    = true;
        for (const auto &e : fs::directory_iterator("out0"))
          if (e.path().filename().string().rfind("probe_line_", 0) == 0)
            {
              const std::string f = e.path().filename().string();
              same = same && file_text("out0/" + f) == file_text("out1/" + f);
              ++n_lines;
            }
        MPI_Bcast(&n_lines, 1, MPI_UNSIGNED, 0, comm);
        identical("probe lines of all " + std::to_string(n_lines) + " outputs",
                  Utilities::MPI::min(int(same), comm) == 1);
        const auto &e0 = s0.solid_energy, &e1 = s1.solid_energy;
        print("solid steps", s1.solid_steps);
        print("solid stress work", e1.internal);
        print("solid kinetic energy", e1.kinetic);
        print("solid hourglass energy", e1.hourglass);
        print("solid energy removed by melting", e1.melted);
        print("solid energy added by solidification", e1.solidified);
        identical("solid summary numbers",
                  s0.solid_steps == s1.solid_steps &&
                    e0.internal == e1.internal && e0.kinetic == e1.kinetic &&
                    e0.hourglass == e1.hourglass &&
                    e0.transfer == e1.transfer && e0.melted == e1.melted &&
                    e0.solidified == e1.solidified && e0.remap == e1.remap &&
                    e0.balance() == e1.balance());
      }
    print("steps", s1.steps);
    print("peak temperature (K)", s1.T_max);
    print("melt pool length (m)", s1.pool.length);
    print("melt pool depth (m)", s1.pool.depth);
    print("laser energy", s1.laser);
    print("stored enthalpy change", s1.stored);
    print("mean point temperature (K)", s1.point_T_mean);
    identical("summary numbers",
              s0.steps == s1.steps && s0.T_max == s1.T_max &&
                s0.laser == s1.laser && s0.stored == s1.stored &&
                s0.losses == s1.losses && s0.point_T_mean == s1.point_T_mean &&
                s0.moved_points == s1.moved_points &&
                s0.pool.depth == s1.pool.depth);

    // 'Heat transfer/Metal of melt cells = points': the cells holding melt
    // take their points' volume, which the checkpoint must hold (the
    // points' volume and melt marks change between its renewals). The
    // scene must melt before the checkpoint and the flow move the points:
    // the melt pool of the straight run's melt_pool.csv at the
    // checkpoint's time, in cells, and the flow's steps and largest point
    // speed at the end.
    if (metal_of_points && root)
      {
        const double                  t_half = checkpoint_time(log0, half);
        std::map<std::string, double> at_half;
        for (const auto &r : csv_rows("out0/melt_pool.csv"))
          if (r.at("time") <= t_half * (1 + 1e-9))
            at_half = r;
        const double cells =
          at_half.empty() ? 0 : at_half.at("volume") / std::pow(cell_size, dim);
        std::cout << "melt pool at the checkpoint (t = " << std::setprecision(3)
                  << t_half * 1e6 << " us): " << std::setprecision(2)
                  << (at_half.empty() ? 0 : at_half.at("length") * 1e6)
                  << " um long, "
                  << (at_half.empty() ? 0 : at_half.at("depth") * 1e6)
                  << " um deep, " << std::lround(cells) << " cells"
                  << std::endl;
        verdict("melt cells at the checkpoint", cells >= 1);
        verdict("the flow moved points (fluid steps and a largest point "
                "speed > 0)",
                s0.flow_steps > 0 && s0.max_fluid_speed > 0);
      }

    // A build: layer_cost.csv (doc/builds.md "Cost and memory"). The
    // straight run: one row per layer (1 + the recoats of its log), the
    // windows joined from 0 to the end, the temperature steps summing to
    // the run's, the walls >= 0 and their parts (each rounded to 1e-6 s)
    // summing to no more than the total, their largest over the ranks
    // (max_wall_*) at least rank 0's. The resumed run: the first
    // layer's row read back as the straight run wrote it, the second's
    // from the checkpoint on (with the hand-over, the classes of the
    // cells it kept as points as the straight run's in every row). Only
    // the counts are printed, no wall time.
    if (layers && root)
      {
        unsigned int n_layers = 1;
        const double t_half   = checkpoint_time(log0, half);
        std::smatch  m;
        for (const auto &line : log0)
          if (line.rfind("Recoat: layer", 0) == 0)
            ++n_layers;
        const auto c0     = csv_rows("out0/layer_cost.csv");
        const auto c1     = csv_rows("out1/layer_cost.csv");
        bool       joined = !c0.empty() && c0[0].at("t_start") == 0;
        bool       walls  = true;
        double     steps  = 0;
        for (std::size_t k = 0; k < c0.size(); ++k)
          {
            const auto &r = c0[k];
            joined        = joined && r.at("layer") == k + 1 &&
                     (k == 0 || r.at("t_start") == c0[k - 1].at("t_end"));
            steps += r.at("temperature_steps");
            double       parts = 0;
            unsigned int n     = 0;
            for (const auto &[c, w] : r)
              if (c.rfind("wall_", 0) == 0 && c != "wall_total")
                parts += w, ++n, walls = walls && w >= 0;
            walls = walls && r.at("wall_total") >= 0 &&
                    parts <= r.at("wall_total") + n * 1e-6;
            // The largest over the ranks: at least rank 0's, part by part.
            for (const auto &[c, w] : r)
              if (c.rfind("wall_", 0) == 0)
                walls =
                  walls && r.count("max_" + c) && r.at("max_" + c) >= w - 1e-6;
            std::cout << "layer_cost.csv, layer " << r.at("layer") << ": t "
                      << std::setprecision(6) << r.at("t_start") * 1e6 << " to "
                      << r.at("t_end") * 1e6 << " us, "
                      << r.at("temperature_steps") << " temperature steps, "
                      << r.at("solid_steps") << " solid steps, "
                      << r.at("points") << " points, " << r.at("mpm_points")
                      << " MPM points, " << r.at("fe_elements")
                      << " FE elements" << std::endl;
          }
        joined = joined &&
                 std::abs(c0.back().at("t_end") - end_time) <= 1e-9 * end_time;
        verdict("layer_cost.csv: one row per layer (" +
                  std::to_string(n_layers) + "), joined from 0 to the end",
                c0.size() == n_layers && joined);
        // The melt flow's sub-steps: the run's fluid steps of its report
        // (0 without the flow).
        double           fluid = 0, flow_steps = 0;
        const std::regex fluid_steps("^Melt flow: ([0-9]+) fluid steps");
        for (const auto &line : log0)
          if (std::regex_search(line, m, fluid_steps))
            fluid = std::stod(m[1]);
        for (const auto &r : c0)
          flow_steps += r.at("flow_steps");
        verdict("layer_cost.csv: the temperature steps and the melt flow's "
                "sub-steps (" +
                  std::to_string(std::lround(fluid)) + ") sum to the run's",
                steps == s0.steps && flow_steps == fluid);
        verdict("layer_cost.csv: walls >= 0, their parts within the total",
                walls);
        // The flow's fluid cells: some in each layer it stepped in, none
        // in the others; the busiest rank's shares (rounded to 4 digits)
        // between an even split and 1, exactly 1 on one rank, and the
        // share per pressure system at least the share over the layer (a
        // sum of maxima is at least the max of the sums).
        const double n_ranks = Utilities::MPI::n_mpi_processes(comm);
        bool         shares  = true;
        for (const auto &r : c0)
          {
            const double n = r.at("fluid_cells"), s = r.at("fluid_share_max"),
                         p = r.at("fluid_step_share_max");
            if (r.at("flow_steps") == 0)
              shares = shares && n == 0 && s == 0 && p == 0;
            else if (n_ranks == 1)
              shares = shares && n > 0 && s == 1 && p == 1;
            else
              shares = shares && n > 0 && s >= 1 / n_ranks - 1e-4 &&
                       s <= p + 1e-4 && p <= 1;
          }
        verdict("layer_cost.csv: fluid cells where the flow stepped, the "
                "busiest rank's shares of them in [1/ranks, 1], per system "
                "at least over the layer",
                shares);
        const unsigned int step_half = std::stoul(half.substr(5));
        bool               resumed   = c1.size() == c0.size() && c1.size() > 1;
        for (std::size_t k = 0; resumed && k < c1.size(); ++k)
          for (const std::string c : {"layer",
                                      "t_start",
                                      "t_end",
                                      "temperature_steps",
                                      "solid_steps",
                                      "flow_steps",
                                      "points",
                                      "mpm_points",
                                      "fe_elements",
                                      "fluid_cells",
                                      "fluid_share_max",
                                      "fluid_step_share_max"})
            if (k + 1 < c1.size() || c == "layer" || c == "t_end")
              resumed = resumed && c1[k].at(c) == c0[k].at(c);
        // With the hand-over, the classes of the cells it kept as points
        // (doc/builds.md "What stays material points"), also in the row of
        // the layer resumed: the checkpoint holds them.
        for (std::size_t k = 0; resumed && handover && k < c1.size(); ++k)
          for (const auto &[c, v] : c0[k])
            if (c.rfind("kept_", 0) == 0)
              resumed = resumed && c1[k].count(c) && c1[k].at(c) == v;
        resumed = resumed &&
                  std::abs(c1.back().at("t_start") - t_half) <= 1e-5 * t_half &&
                  c1.back().at("temperature_steps") == s0.steps - step_half;
        std::cout << "resumed at step " << step_half
                  << ", t = " << std::setprecision(6) << t_half * 1e6
                  << " us: its last row from t = "
                  << (c1.empty() ? -1. : c1.back().at("t_start") * 1e6)
                  << " us, "
                  << (c1.empty() ? -1. : c1.back().at("temperature_steps"))
                  << " temperature steps" << std::endl;
        verdict("layer_cost.csv resumed: the earlier rows as written, the "
                "last from the checkpoint on",
                resumed);
      }

    // With the hand-over of cooled metal: the zone rose before the
    // checkpoint (the straight run's log), the resumed run took the raised
    // zone from it (no hand-over of its own), and the largest differences
    // of the point stresses and temperatures, of the solid's probes (in
    // the raised rows) and of the probe lines' cell fields (element
    // stresses) between the two runs are 0.
    if (handover && root)
      {
        const std::regex rise("FE zone hand-over at t = ([-0-9.e+]+) s: .*"
                              "the zone's top rises from ([-0-9.e+]+) to "
                              "([-0-9.e+]+) m: ([0-9]+) elements");
        std::smatch      m;
        unsigned int     rises0 = 0, rises1 = 0;
        double           t_rise = 0, from = 0, to = 0, elements = 0;
        const double     t_half = checkpoint_time(log0, half);
        for (const auto &line : log0)
          if (std::regex_search(line, m, rise))
            {
              ++rises0;
              t_rise   = std::stod(m[1]);
              from     = std::stod(m[2]);
              to       = std::stod(m[3]);
              elements = std::stod(m[4]);
            }
        for (const auto &line : log1)
          rises1 += std::regex_search(line, m, rise);
        std::cout << "straight run: the FE zone rises " << rises0
                  << " time(s), from " << std::setprecision(3) << from * 1e6
                  << " to " << to * 1e6 << " um (" << elements
                  << " elements) at t = " << t_rise * 1e6
                  << " us; the checkpoint resumed is of t = " << t_half * 1e6
                  << " us" << std::endl;
        verdict("the zone rose before the checkpoint resumed",
                rises0 == 1 && t_half > t_rise);
        verdict("the resumed run hands nothing over again (its zone is the "
                "checkpoint's)",
                rises1 == 0);
        using P            = typename femp::MaterialPoints<dim>::PropertyIndex;
        const unsigned n_s = dim * (dim + 1) / 2;
        double         d_stress = points1.size() == points0.size() ? 0 : 1e300,
               d_T = d_stress, d_any = d_stress;
        for (const auto &[id, v] : points0)
          {
            const auto it = points1.find(id);
            if (it == points1.end())
              {
                d_stress = d_T = d_any = 1e300;
                continue;
              }
            for (std::size_t i = 0; i < v.size(); ++i)
              {
                const double       d = std::abs(it->second[i] - v[i]);
                const unsigned int k = i - dim; // the property
                d_any                = std::max(d_any, d);
                if (i >= dim && ((k >= P::stress && k < P::stress + n_s) ||
                                 (dim == 2 && k == P::stress_zz)))
                  d_stress = std::max(d_stress, d);
                if (i >= dim && k == P::temperature)
                  d_T = std::max(d_T, d);
              }
          }
        double d_lines = 0;
        for (const auto &e : fs::directory_iterator("out0"))
          if (e.path().filename().string().rfind("probe_line_", 0) == 0)
            {
              const std::string f = e.path().filename().string();
              d_lines             = std::max(d_lines,
                                 csv_difference("out0/" + f, "out1/" + f, -1.));
            }
        const double d_probes = csv_difference("out0/solid_probes.csv",
                                               "out1/solid_probes.csv",
                                               end_time / 2);
        std::cout << "largest difference, resumed against straight (same "
                     "ranks):"
                  << std::endl;
        std::cout << "  point stresses (Pa) = " << d_stress << std::endl;
        std::cout << "  point temperatures (K) = " << d_T << std::endl;
        std::cout << "  any point position or property = " << d_any
                  << std::endl;
        std::cout << "  solid probes after the checkpoint (sigma_xx, T; "
                     "relative) = "
                  << d_probes << std::endl;
        std::cout << "  probe lines of all outputs (cell fields; relative) = "
                  << d_lines << std::endl;
        verdict("all these differences 0",
                d_stress == 0 && d_T == 0 && d_any == 0 && d_probes == 0 &&
                  d_lines == 0);
      }

    // Rank 0 alone resumes the checkpoint that all ranks wrote.
    if (root)
      {
        fs::copy("out0", "out2", fs::copy_options::recursive);
        const auto points2 = run<dim>(
          scene,
          MPI_COMM_SELF,
          with({{"Output", "Directory", "out2"},
                {"Checkpoint", "Resume from", "out2/checkpoint/" + half}}));
        if (fs::exists("out0/grid.xdmf"))
          {
            // As many grid outputs as the straight run, each naming a mesh
            // file that exists (on another number of ranks the resumed run
            // writes a mesh file of its own).
            const std::string x0 = file_text("out0/grid.xdmf"),
                              x2 = file_text("out2/grid.xdmf");
            auto count = [](const std::string &x, const std::string &what) {
              unsigned int n = 0;
              for (auto i = x.find(what); i != std::string::npos;
                   i      = x.find(what, i + 1))
                ++n;
              return n;
            };
            std::set<std::string> meshes;
            for (auto i = x2.find("grid_mesh"); i != std::string::npos;
                 i      = x2.find("grid_mesh", i + 1))
              meshes.insert(x2.substr(i, x2.find(':', i) - i));
            bool all_there = !meshes.empty();
            for (const auto &m : meshes)
              all_there = all_there && fs::exists("out2/" + m);
            std::cout << "grid outputs in grid.xdmf, resumed on rank 0 alone "
                         "against straight: "
                      << count(x2, "<Time ") << " / " << count(x0, "<Time ")
                      << "; the mesh files they name present: "
                      << (all_there ? "yes" : "NO") << std::endl;
            failures +=
              !all_there || count(x2, "<Time ") != count(x0, "<Time ");
          }
        double diff = points2.size() == points0.size() ? 0 : 1;
        for (const auto &[id, v] : points0)
          {
            const auto it = points2.find(id);
            if (it == points2.end())
              {
                diff = 1;
                continue;
              }
            for (std::size_t i = 0; i < v.size(); ++i)
              diff = std::max(diff,
                              std::abs(it->second[i] - v[i]) /
                                (std::abs(v[i]) + 1e-300 + 1e-12));
          }
        std::cout << "resumed on 1 rank: " << points2.size() << " points"
                  << std::endl;
        verdict("  their max relative difference to the straight run <= " +
                  femp::num(gate),
                diff <= gate);
        if (!(diff <= gate))
          std::cout << "  (difference " << diff << ")" << std::endl;
        if (solid)
          std::cout << "  points (with their stresses): max relative "
                    << "difference " << std::setprecision(2)
                    << (diff < 1e-15 ? 0. : diff) << std::endl;
        if (solid)
          for (const std::string f : {"solid_energy.csv", "solid_probes.csv"})
            {
              // The rows after the checkpoint, relative to each column's
              // largest magnitude.
              const double d =
                csv_difference("out0/" + f, "out2/" + f, end_time / 2);
              std::cout << "  " << f << " after the checkpoint: max relative "
                        << "difference " << std::setprecision(2)
                        << (d < 1e-15 ? 0. : d) << std::endl;
              verdict("  " + f +
                        " max relative difference <= " + femp::num(gate),
                      d <= gate);
            }
      }

    // Refusals: corrupt, truncated, another grid, other physics.
    const std::string bad     = "bad/" + half;
    const std::string file    = bad + "/rank_00000.bin";
    auto              refused = [&](const std::string           &what,
                       const std::vector<Override> &o,
                       const std::string           &expect) {
      const std::string msg = refusal<dim>(scene, comm, with(o));
      const bool        ok = msg.find(expect) != std::string::npos;
      verdict(what + ": refused naming '" + expect + "'", ok);
      if (!ok && root)
        std::cout << "  (" << msg << ")" << std::endl;
    };
    const std::vector<Override> resume_bad = {
      {"Output", "Directory", "out1"}, {"Checkpoint", "Resume from", bad}};
    if (root)
      {
        fs::create_directories("bad");
        fs::copy("out0/checkpoint/" + half, bad, fs::copy_options::recursive);
        std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(-9, std::ios::end);
        f.put('\x5a');
      }
    MPI_Barrier(comm);
    refused("corrupt checkpoint", resume_bad, "is corrupt");
    MPI_Barrier(comm);
    if (root)
      fs::resize_file(file, fs::file_size(file) - 100);
    MPI_Barrier(comm);
    refused("truncated checkpoint", resume_bad, "is truncated");
    refused("other cell size",
            {{"Output", "Directory", "out1"},
             {"Checkpoint", "Resume from", "out1/checkpoint/" + half},
             {"Background grid", "Cell size", "8e-6"}},
            "Background grid/Cell size = 4e-06 m, the scene has 8e-06 m");
    refused("heat switched off",
            {{"Output", "Directory", "out1"},
             {"Checkpoint", "Resume from", "out1/checkpoint/" + half},
             {"Physics", "Heat transfer", "false"},
             {"Build", "Hand over cooled metal", "false"},
             {"Time stepping", "Time step", "1e-7"}},
            "Physics/Heat transfer = true, the scene has false");
    // With or without an FE zone.
    if (fe_zone)
      refused("other FE zone",
              {{"Output", "Directory", "out1"},
               {"Checkpoint", "Resume from", "out1/checkpoint/" + half},
               {"Solid FEM",
                "Zone upper corner",
                dim == 2 ? "160e-6, 36e-6" : "160e-6, 80e-6, 36e-6"}},
              "Solid FEM/Zone upper corner");
    else if (solid) // all material points (the 2D scene of the solid)
      refused("FE zone switched on",
              {{"Output", "Directory", "out1"},
               {"Checkpoint", "Resume from", "out1/checkpoint/" + half},
               {"Solid FEM", "Use finite elements", "true"},
               {"Solid FEM", "Zone lower corner", "0, 0"},
               {"Solid FEM", "Zone upper corner", "160e-6, 40e-6"}},
              "Solid FEM/Use finite elements = false, the scene has true");
    if (root)
      std::cout << (failures == 0 ? "all checks passed" : "CHECKS FAILED")
                << std::endl;
    return failures == 0 ? 0 : 1;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  const std::string                scene = argv[1];
  const double                     gate  = std::stod(argv[3]);
  // argv[4], optional: Output/Format (vtu, the default, or hdf5).
  const std::string format = argc > 4 ? argv[4] : "vtu";
  // argv[5], optional: significant digits of the summary numbers.
  const int digits = argc > 5 ? std::stoi(argv[5]) : 8;
  return std::string(argv[2]) == "3" ?
           test<3>(scene, gate, format, digits, MPI_COMM_WORLD) :
           test<2>(scene, gate, format, digits, MPI_COMM_WORLD);
}
