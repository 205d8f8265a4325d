// femp: checkpoint files, their triggers, and their verification on resume
// (see the header and doc/checkpoint.md).
#include <deal.II/base/mpi.h>
#include <deal.II/base/utilities.h>

#include <femp/base/input_checks.h>
#include <femp/base/parameter_table.h>
#include <femp/base/progress_watchdog.h>
#include <femp/io/checkpoint.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace femp
{
  namespace
  {
    const char magic[8] = {'F', 'E', 'M', 'P', 'C', 'K', 'P', 'T'};
    // 2: the solid's sections (Physics/Solid stress) added; 4: the FE
    // elements' volume change; 5: the section "fe zone" (the FE zone's top
    // and the factor its masses were built at) and the evaporated-mass
    // account in the section "run"; 6: the displacements of the FE
    // zone's transition nodes in the section "solid" (the hand-over's fill
    // reads them); 7: the hand-over's penetration depth, its lowest
    // molten cell per column and the metal surface the layer met, in the
    // section "handover". A file of another version is refused.
    const std::uint32_t format_version = 7;

    /// FNV-1a, 64 bits, over @p n bytes at @p p, continued from @p h
    /// (the hash of the bytes before them; the default starts it).
    std::uint64_t
    fnv1a(const char       *p,
          const std::size_t n,
          std::uint64_t     h = 1469598103934665603ull)
    {
      for (std::size_t i = 0; i < n; ++i)
        {
          h ^= static_cast<unsigned char>(p[i]);
          h *= 1099511628211ull;
        }
      return h;
    }

    /// The payload of a rank's file: the number of sections, then for each
    /// its name and its bytes, each with its length first (the layout of
    /// StateWriter::put_string and put_vector). Visited piece by piece
    /// (@p f(pointer, bytes)), so that it is hashed and written from the
    /// modules' buffers without a copy of the whole.
    template <typename F>
    void
    for_each_payload_piece(
      const std::vector<std::pair<std::string, const StateWriter *>> &sections,
      F                                                             &&f)
    {
      const std::uint32_t n = sections.size();
      f(reinterpret_cast<const char *>(&n), sizeof(n));
      for (const auto &[section, bytes] : sections)
        {
          const std::uint64_t ns = section.size();
          f(reinterpret_cast<const char *>(&ns), sizeof(ns));
          f(section.data(), section.size());
          const std::uint64_t nb = bytes->bytes().size();
          f(reinterpret_cast<const char *>(&nb), sizeof(nb));
          f(bytes->bytes().data(), bytes->bytes().size());
        }
    }

    /// The file in a checkpoint's directory that marks it as a
    /// rebalance's (CheckpointKind::rebalance).
    const char *const rebalance_marker = "rebalance";

    std::string
    rank_file(const std::string &dir, const unsigned int rank)
    {
      return dir + "/rank_" + Utilities::int_to_string(rank, 5) + ".bin";
    }

    std::string
    triple(const std::array<double, 3> &x, const int dim)
    {
      std::ostringstream s;
      s << std::setprecision(10);
      for (int d = 0; d < dim; ++d)
        s << (d ? ", " : "") << x[d];
      return s.str();
    }
  } // namespace

  template <int dim>
  void
  Checkpoint<dim>::Parameters::add_parameters(ParameterTable &table)
  {
    table.enter_subsection("Checkpoint");
    table.add("Every steps",
              every_steps,
              Patterns::Integer(0),
              "Write a checkpoint after every this many temperature "
              "steps; 0: off. Range [0, inf).");
    table.add("Every simulated time",
              every_time,
              Patterns::Double(0.),
              "Write a checkpoint every this much simulated time, s; "
              "0: off. Range [0, inf).");
    table.add("Every wall minutes",
              every_wall_minutes,
              Patterns::Double(0.),
              "Write a checkpoint when this many minutes of wall "
              "time have passed since the start or the last "
              "checkpoint, min; 0: off. Range [0, inf). With all "
              "three triggers off (the default) checkpoints cost "
              "nothing.");
    table.add("Directory",
              directory,
              Patterns::Anything(),
              "Where checkpoints go: a relative path is relative to "
              "'Output/Directory', an absolute path is allowed. Each "
              "checkpoint is a subdirectory step_<step number>; the "
              "file 'index' names the last two, older ones are "
              "removed; a rebalance's checkpoint (Build/Rebalance "
              "above imbalance) is kept besides them only while it "
              "is the newest (doc/checkpoint.md).");
    table.add("Resume from",
              resume_from,
              Patterns::Anything(),
              "Continue the run from this checkpoint: a checkpoint "
              "directory (its index names the latest checkpoint) or "
              "one checkpoint step_<n> in it; relative to the "
              "working directory; empty: a new run. The same as the "
              "command-line option --resume DIR. The scene must be "
              "the one the checkpoint was written for (same grid, "
              "dimension, physics, FE zone); 'Time stepping/End "
              "time' may be raised. The time series in "
              "'Output/Directory' lose their rows after the "
              "checkpoint and continue.");
    table.add("Partition on resume",
              partition_by_state,
              {{true, "checkpoint"}, {false, "scene"}},
              "With 'Background grid/Partition = cost', what a run "
              "resumed from a checkpoint weighs its cells by. "
              "'checkpoint': the checkpoint's state (the FE zone it "
              "holds, which a hand-over may have raised, and the "
              "material points of each cell, solid or not), so that "
              "a build run in checkpointed segments is balanced "
              "again at each resume; results agree with 'scene' to "
              "round-off and the pressure solver's tolerance. "
              "'scene': the scene's geometry at the start, the "
              "partition of the run that wrote the checkpoint on the "
              "same number of ranks (it continues bit for bit). A "
              "new run or one rank: no effect.");
    table.leave_subsection();
  }

  template <int dim>
  void
  Checkpoint<dim>::Parameters::declare_parameters(ParameterHandler &prm)
  {
    Parameters     defaults;
    ParameterTable table(prm, ParameterTable::Mode::declare);
    defaults.add_parameters(table);
  }

  template <int dim>
  void
  Checkpoint<dim>::Parameters::parse_parameters(ParameterHandler &prm)
  {
    ParameterTable table(prm, ParameterTable::Mode::parse);
    add_parameters(table);
    prm.enter_subsection("Checkpoint");
    prm.leave_subsection();
    require(!directory.empty(),
            "Checkpoint/Directory",
            directory,
            "it must name a directory (relative to Output/Directory or "
            "absolute)");
  }

  template <int dim>
  Checkpoint<dim>::Checkpoint(const Parameters  &prm,
                              const std::string &output_directory,
                              const Scene       &scene,
                              MPI_Comm           comm)
      : prm(prm)
      , base(std::filesystem::path(prm.directory).is_absolute() ?
               prm.directory :
               output_directory + "/" + prm.directory)
      , scene(scene)
      , comm(comm)
      , next_time(prm.every_time)
      , last_wall(std::chrono::steady_clock::now())
  {
  }

  template <int dim>
  bool
  Checkpoint<dim>::due(const unsigned int step, const double time)
  {
    bool now = prm.every_steps > 0 && step % prm.every_steps == 0;
    if (prm.every_time > 0 && time >= next_time * (1 - 1e-12))
      {
        now = true;
        while (next_time <= time * (1 + 1e-12))
          next_time += prm.every_time;
      }
    if (prm.every_wall_minutes > 0)
      {
        // The ranks' clocks differ: rank 0 decides for all.
        int wall = std::chrono::duration<double>(
                     std::chrono::steady_clock::now() - last_wall)
                     .count() >= 60 * prm.every_wall_minutes;
        MPI_Bcast(&wall, 1, MPI_INT, 0, comm);
        now = now || wall;
      }
    return now;
  }

  template <int dim>
  std::string
  Checkpoint<dim>::write(
    const unsigned int                                              step,
    const double                                                    time,
    const std::vector<std::pair<std::string, const StateWriter *>> &sections,
    const CheckpointKind                                            kind)
  {
    progress::phase("writing a checkpoint");
    namespace fs             = std::filesystem;
    const auto        start  = std::chrono::steady_clock::now();
    const auto        rank   = Utilities::MPI::this_mpi_process(comm);
    const auto        n_rank = Utilities::MPI::n_mpi_processes(comm);
    const std::string name   = "step_" + Utilities::int_to_string(step, 8);
    const std::string dir    = base + "/" + name;
    std::string       error;
    if (rank == 0)
      {
        // A leftover of a run killed while writing this step is replaced.
        std::error_code ec;
        fs::remove_all(dir, ec);
        fs::create_directories(dir, ec);
        if (ec || !fs::is_directory(dir))
          error = "cannot create the checkpoint directory '" + dir + "'";
      }
    int ok = error.empty();
    MPI_Bcast(&ok, 1, MPI_INT, 0, comm);
    AssertThrow(ok,
                ExcMessage("cannot create the checkpoint directory '" + dir +
                           "' (Checkpoint/Directory)"));

    std::uint64_t payload_size = 0, checksum = fnv1a(nullptr, 0);
    for_each_payload_piece(sections, [&](const char *q, const std::size_t n) {
      payload_size += n;
      checksum = fnv1a(q, n, checksum);
    });
    StateWriter head;
    head.put(magic);
    head.put(format_version);
    head.put<std::uint32_t>(dim);
    head.put<std::uint32_t>(n_rank);
    head.put<std::uint32_t>(rank);
    head.put<std::uint32_t>(step);
    head.put(time);
    head.put(scene.n_cells);
    head.put(scene.lower_corner);
    head.put(scene.cell_size);
    head.put(scene.heat);
    head.put(scene.flow);
    head.put(scene.solid);
    head.put(scene.fe_zone);
    head.put(scene.fe_lower);
    head.put(scene.fe_upper);
    head.put(scene.n_point_properties);
    head.put(payload_size);
    head.put(checksum);
    {
      const std::string file = rank_file(dir, rank);
      std::ofstream     out(file, std::ios::binary);
      out.write(head.bytes().data(), head.bytes().size());
      for_each_payload_piece(sections, [&](const char *q, const std::size_t n) {
        out.write(q, n);
      });
      out.close();
      ok = static_cast<bool>(out);
    }
    ok = Utilities::MPI::min(ok, comm);
    AssertThrow(ok,
                ExcMessage("cannot write the checkpoint into '" + dir +
                           "' (disk full or no permission?); the "
                           "previous checkpoint stays valid"));
    // Every rank has written: the index now names the new checkpoint.
    if (rank == 0)
      {
        // A rebalance's checkpoint carries a marker file; one rewritten for
        // a trigger (the same step after a resume) lost it above.
        if (kind == CheckpointKind::rebalance)
          std::ofstream(dir + "/" + rebalance_marker)
            << "written for a rebalance (Build/Rebalance above imbalance); "
               "removed by the next checkpoint\n";
        // The index names the new checkpoint first, then the newest user
        // checkpoints of the old index (after a resume the step just
        // written may be in it already): one beside a user checkpoint (the
        // last two), two beside a rebalance's. An older rebalance's
        // checkpoint is dropped, it is no longer the newest, and so is a
        // name whose directory is gone.
        const std::size_t        n_user = kind == CheckpointKind::user ? 1 : 2;
        std::vector<std::string> kept;
        {
          std::ifstream index(base + "/index");
          for (std::string line;
               kept.size() < n_user && std::getline(index, line);)
            if (!line.empty() && line != name &&
                std::find(kept.begin(), kept.end(), line) == kept.end() &&
                fs::is_directory(base + "/" + line) &&
                !fs::exists(base + "/" + line + "/" + rebalance_marker))
              kept.push_back(line);
        }
        {
          std::ofstream index(base + "/index.tmp");
          index << name << '\n';
          for (const auto &k : kept)
            index << k << '\n';
        }
        std::error_code ec;
        fs::rename(base + "/index.tmp", base + "/index", ec);
        AssertThrow(!ec,
                    ExcMessage("cannot replace '" + base +
                               "/index': " + ec.message()));
        for (const auto &entry : fs::directory_iterator(base, ec))
          {
            const std::string n = entry.path().filename().string();
            if (entry.is_directory() && n.rfind("step_", 0) == 0 && n != name &&
                std::find(kept.begin(), kept.end(), n) == kept.end())
              fs::remove_all(entry.path(), ec);
          }
      }
    last_bytes =
      Utilities::MPI::sum<std::uint64_t>(head.bytes().size() + payload_size,
                                         comm);
    last_wall = std::chrono::steady_clock::now();
    seconds += std::chrono::duration<double>(last_wall - start).count();
    return dir;
  }

  template <int dim>
  void
  Checkpoint<dim>::check_file(const std::vector<char> &image,
                              const std::string       &file,
                              const unsigned int       rank,
                              const unsigned int       n_ranks)
  {
    const std::string what   = "Checkpoint/Resume from";
    const std::string name   = std::filesystem::path(file).filename().string();
    auto              refuse = [&](const std::string &why) {
      throw InputError(what, prm.resume_from, why);
    };
    // The header has a fixed size: read it with a reader that cannot
    // overrun (a short file is refused here, not by the reader).
    const std::size_t header_size =
      8 + 5 * 4 + 8 + 3 * 4 + 3 * 8 + 8 + 4 + 6 * 8 + 4 + 8 + 8;
    if (image.size() < header_size)
      refuse("its file " + name + " is truncated (" +
             std::to_string(image.size()) + " bytes, shorter than the header)");
    if (std::memcmp(image.data(), magic, 8) != 0)
      refuse("its file " + name +
             " is not a femp checkpoint (no magic "
             "string FEMPCKPT at its start)");
    StateReader in(image.data() + 8, header_size - 8, name);
    const auto  version = in.get<std::uint32_t>();
    if (version != format_version)
      refuse("its file " + name + " has format version " +
             std::to_string(version) + ", this femp reads version " +
             std::to_string(format_version) +
             " only (written by another version of femp: resume it with "
             "that version or start the run anew)");
    const auto file_dim  = in.get<std::uint32_t>();
    const auto file_n    = in.get<std::uint32_t>();
    const auto file_rank = in.get<std::uint32_t>();
    const auto step      = in.get<std::uint32_t>();
    const auto time      = in.get<double>();
    Scene      s;
    s.n_cells            = in.get<std::array<std::uint32_t, 3>>();
    s.lower_corner       = in.get<std::array<double, 3>>();
    s.cell_size          = in.get<double>();
    s.heat               = in.get<std::uint8_t>();
    s.flow               = in.get<std::uint8_t>();
    s.solid              = in.get<std::uint8_t>();
    s.fe_zone            = in.get<std::uint8_t>();
    s.fe_lower           = in.get<std::array<double, 3>>();
    s.fe_upper           = in.get<std::array<double, 3>>();
    s.n_point_properties = in.get<std::uint32_t>();
    const auto size      = in.get<std::uint64_t>();
    const auto checksum  = in.get<std::uint64_t>();

    auto differs = [&](const std::string &parameter,
                       const std::string &saved,
                       const std::string &now) {
      refuse("it was written for " + parameter + " = " + saved +
             ", the scene has " + now +
             "; a checkpoint resumes only the scene it was written for");
    };
    if (file_dim != dim)
      differs("Dimension", std::to_string(file_dim), std::to_string(dim));
    if (file_n != n_ranks || file_rank != rank)
      refuse("its file " + name + " belongs to another checkpoint (rank " +
             std::to_string(file_rank) + " of " + std::to_string(file_n) +
             ", expected rank " + std::to_string(rank) + " of " +
             std::to_string(n_ranks) + ")");
    if (rank == 0)
      {
        step_read = step;
        time_read = time;
      }
    else if (step != step_read || time != time_read)
      refuse("its file " + name + " is of step " + std::to_string(step) +
             ", rank_00000.bin of step " + std::to_string(step_read) +
             " (files of two checkpoints mixed)");
    const auto on_off = [](const std::uint8_t b) {
      return std::string(b ? "true" : "false");
    };
    if (s.heat != scene.heat)
      differs("Physics/Heat transfer", on_off(s.heat), on_off(scene.heat));
    if (s.flow != scene.flow)
      differs("Physics/Melt flow", on_off(s.flow), on_off(scene.flow));
    if (s.solid != scene.solid)
      differs("Physics/Solid stress", on_off(s.solid), on_off(scene.solid));
    if (s.fe_zone != scene.fe_zone)
      differs("Solid FEM/Use finite elements",
              on_off(s.fe_zone),
              on_off(scene.fe_zone));
    std::array<double, 3> n_saved{}, n_now{};
    for (int d = 0; d < 3; ++d)
      {
        n_saved[d] = s.n_cells[d];
        n_now[d]   = scene.n_cells[d];
      }
    if (s.cell_size != scene.cell_size)
      differs("Background grid/Cell size",
              num(s.cell_size) + " m",
              num(scene.cell_size) + " m");
    if (s.lower_corner != scene.lower_corner)
      differs("Background grid/Lower corner",
              triple(s.lower_corner, dim),
              triple(scene.lower_corner, dim));
    if (s.n_cells != scene.n_cells)
      differs("Background grid/Upper corner (cells per direction)",
              triple(n_saved, dim),
              triple(n_now, dim));
    if (s.fe_lower != scene.fe_lower)
      differs("Solid FEM/Zone lower corner",
              triple(s.fe_lower, dim),
              triple(scene.fe_lower, dim));
    if (s.fe_upper != scene.fe_upper)
      differs("Solid FEM/Zone upper corner",
              triple(s.fe_upper, dim),
              triple(scene.fe_upper, dim));
    if (s.n_point_properties != scene.n_point_properties)
      differs("the point properties (Material points/Carry points, "
              "Solid/Velocity transfer, Melt flow/Velocity transfer)",
              std::to_string(s.n_point_properties) + " per point",
              std::to_string(scene.n_point_properties));
    if (image.size() - header_size != size)
      refuse("its file " + name + " is truncated or overlong (" +
             std::to_string(image.size() - header_size) +
             " bytes of data, the header announces " + std::to_string(size) +
             ")");
    if (fnv1a(image.data() + header_size, size) != checksum)
      refuse("its file " + name +
             " is corrupt (the checksum of its data "
             "does not match the one in its header)");

    // The sections of the payload.
    auto       &map = sections_of_file.emplace_back();
    StateReader body(image.data() + header_size, size, name);
    const auto  n_sections = body.get<std::uint32_t>();
    std::size_t offset     = header_size + 4;
    for (unsigned int i = 0; i < n_sections; ++i)
      {
        const auto section = body.get_string();
        offset += 8 + section.size();
        const auto bytes = body.get<std::uint64_t>();
        offset += 8;
        map[section] = {offset, bytes};
        body.skip(bytes);
        offset += bytes;
      }
  }

  template <int dim>
  void
  Checkpoint<dim>::read()
  {
    namespace fs           = std::filesystem;
    const std::string what = "Checkpoint/Resume from";
    path                   = prm.resume_from;
    if (fs::exists(path + "/index"))
      {
        std::ifstream index(path + "/index");
        std::string   latest;
        std::getline(index, latest);
        require(!latest.empty(),
                what,
                prm.resume_from,
                "its index file is empty (no checkpoint was completed)");
        path += "/" + latest;
      }
    require(fs::exists(rank_file(path, 0)),
            what,
            prm.resume_from,
            "it is neither a checkpoint directory (with an index file) nor "
            "a checkpoint (a step_<n> directory with rank_00000.bin)");
    files.clear();
    sections_of_file.clear();
    unsigned int n_ranks = 1;
    for (unsigned int r = 0; r < n_ranks; ++r)
      {
        const std::string file = rank_file(path, r);
        std::ifstream     in(file, std::ios::binary);
        require(static_cast<bool>(in),
                what,
                prm.resume_from,
                "its file " + fs::path(file).filename().string() +
                  " is missing or cannot be read");
        // One read of the whole file into a buffer of its size.
        in.seekg(0, std::ios::end);
        const std::streamoff size = std::max<std::streamoff>(in.tellg(), 0);
        in.seekg(0, std::ios::beg);
        files.emplace_back(static_cast<std::size_t>(size));
        in.read(files.back().data(), size);
        require(in.gcount() == size,
                what,
                prm.resume_from,
                "its file " + fs::path(file).filename().string() +
                  " cannot be read to its end");
        if (r == 0 && files[0].size() >= 20)
          std::memcpy(&n_ranks, files[0].data() + 16, 4);
        check_file(files[r], file, r, n_ranks);
      }
    n_files = n_ranks;
  }

  template <int dim>
  bool
  Checkpoint<dim>::has_section(const std::string &name) const
  {
    return !sections_of_file.empty() && sections_of_file[0].count(name) > 0;
  }

  template <int dim>
  std::vector<StateReader>
  Checkpoint<dim>::section(const std::string &name) const
  {
    std::vector<StateReader> parts;
    for (std::size_t f = 0; f < files.size(); ++f)
      {
        const auto it = sections_of_file[f].find(name);
        AssertThrow(it != sections_of_file[f].end(),
                    ExcMessage("the checkpoint '" + path +
                               "' has no state of '" + name + "'"));
        parts.emplace_back(files[f].data() + it->second.first,
                           it->second.second,
                           name);
      }
    return parts;
  }

  template <int dim>
  void
  Checkpoint<dim>::save_state(StateWriter &out) const
  {
    out.put(next_time);
  }

  template <int dim>
  void
  Checkpoint<dim>::load_state(std::vector<StateReader> &parts)
  {
    // The trigger of the resumed run continues, unless its interval
    // changed (then from the checkpoint's time).
    const double saved = parts[0].get<double>();
    if (prm.every_time > 0)
      {
        next_time = saved;
        while (next_time <= time_read * (1 + 1e-12))
          next_time += prm.every_time;
      }
  }

  template class Checkpoint<2>;
  template class Checkpoint<3>;
} // namespace femp
