// femp: Checkpoint<dim>, checkpoint and restart of the whole state of a run
// (doc/checkpoint.md). It implements no equation of the paper: it stores
// what the next macro step of sec. 2.6 reads, so that a run stopped and
// resumed continues bit for bit as if it had not stopped.
//
// Every rank writes one binary file per checkpoint: a header (magic,
// format version, dimension, the grid, the physics switched on, the FE
// zone, the step and time) and named sections, one per module, each holding
// that rank's part of the module's state (grid fields keyed by the global
// structured cell index, material points by id with their cell, ...), with
// an FNV-1a checksum of the payload. On resume every rank reads all files
// and keeps what it owns, so a run may resume on another number of ranks.
// A checkpoint goes into a new subdirectory; only when every rank has
// written (barrier) does rank 0 replace the small index file (write a
// temporary, rename), so that a run killed while writing leaves the
// previous checkpoint valid. The last two of the user's triggers are kept,
// and a rebalance's checkpoint only while it is the newest (CheckpointKind).
#ifndef femp_checkpoint_h
#define femp_checkpoint_h

#include <deal.II/base/parameter_handler.h>

#include <femp/base/parameter_table.h>
#include <femp/base/state_stream.h>
#include <femp/grid/background_grid.h>
#include <femp/grid/cell_state.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <map>
#include <string>
#include <type_traits>
#include <vector>

namespace femp
{
  using namespace dealii;

  /// What a checkpoint is written for. 'user': a trigger of the
  /// subsection Checkpoint, or a caller's write at the end of a run; the
  /// last two of these are kept. 'rebalance': a run that goes on from it
  /// on a grid cut by its state ('Build/Rebalance above imbalance'); it is
  /// kept only while it is the newest checkpoint (the next write of any
  /// kind removes it), and it never pushes a user checkpoint out.
  enum class CheckpointKind
  {
    user,
    rebalance
  };

  template <int dim>
  class Checkpoint
  {
  public:
    /// Subsection 'Checkpoint'.
    struct Parameters
    {
      unsigned int every_steps        = 0; ///< 0: off
      double       every_time         = 0; ///< s, 0: off
      double       every_wall_minutes = 0; ///< min, 0: off
      std::string  directory          = "checkpoint";
      std::string  resume_from; ///< empty: a new run
      /// "Partition on resume": a resumed run weighs the cells by the
      /// checkpoint's FE zone and points (true, 'checkpoint') or by the
      /// scene's geometry at the start (false, 'scene').
      bool partition_by_state = true;

      /// Declare (the members' values are the defaults) or read the

      /// entries, each listed once.

      void

      add_parameters(ParameterTable &table);

      static void
      declare_parameters(ParameterHandler &prm);
      void
      parse_parameters(ParameterHandler &prm);
    };

    /// What a checkpoint must share with the scene that resumes it.
    struct Scene
    {
      std::uint32_t                dimension = dim;
      std::array<std::uint32_t, 3> n_cells{};
      std::array<double, 3>        lower_corner{};
      double                       cell_size = 0;
      std::uint8_t                 heat = 0, flow = 0, solid = 0, fe_zone = 0;
      std::array<double, 3>        fe_lower{}, fe_upper{};
      std::uint32_t                n_point_properties = 0;
    };

    /// @p output_directory: where a relative 'Directory' lies.
    Checkpoint(const Parameters  &prm,
               const std::string &output_directory,
               const Scene       &scene,
               MPI_Comm           comm);

    /// True if any trigger is on.
    bool
    enabled() const
    {
      return prm.every_steps > 0 || prm.every_time > 0 ||
             prm.every_wall_minutes > 0;
    }
    /// A checkpoint is due after step @p step at @p time (collective when
    /// the wall-clock trigger is on: rank 0 decides).
    bool
    due(const unsigned int step, const double time);

    /// Write a checkpoint of this rank's @p sections (name, bytes) at
    /// @p step, @p time (collective) and prune the older ones by @p kind's
    /// rule; returns its directory.
    std::string
    write(
      const unsigned int                                              step,
      const double                                                    time,
      const std::vector<std::pair<std::string, const StateWriter *>> &sections,
      const CheckpointKind kind = CheckpointKind::user);

    /// Read and verify the checkpoint 'Resume from' (collective): a
    /// checkpoint that is corrupt, truncated or written for another scene
    /// throws InputError naming what differs. Call before any work.
    void
    read();
    bool
    resuming() const
    {
      return !prm.resume_from.empty();
    }
    /// The parts (one per saved rank) of section @p name of the checkpoint
    /// read; throws if it has no such section.
    std::vector<StateReader>
    section(const std::string &name) const;
    bool
    has_section(const std::string &name) const;
    /// Free the checkpoint read (after every module took its state).
    void
    release()
    {
      files            = {};
      sections_of_file = {};
    }
    unsigned int
    saved_step() const
    {
      return step_read;
    }
    double
    saved_time() const
    {
      return time_read;
    }
    /// Number of ranks that wrote the checkpoint read.
    unsigned int
    saved_ranks() const
    {
      return n_files;
    }
    /// Directory of the checkpoint read.
    const std::string &
    path_read() const
    {
      return path;
    }
    /// Seconds spent writing checkpoints and their total size (all ranks,
    /// bytes), for the report.
    double
    write_seconds() const
    {
      return seconds;
    }
    std::uint64_t
    bytes_written() const
    {
      return last_bytes;
    }

    /// The trigger's own state (next simulated time), for continuity.
    void
    save_state(StateWriter &out) const;
    void
    load_state(std::vector<StateReader> &parts);

  private:
    Parameters                            prm;
    std::string                           base;
    Scene                                 scene;
    MPI_Comm                              comm;
    double                                next_time = 0;
    std::chrono::steady_clock::time_point last_wall;
    double                                seconds    = 0;
    std::uint64_t                         last_bytes = 0;

    // The checkpoint read: one file image per saved rank, its sections.
    std::string                    path;
    unsigned int                   step_read = 0;
    unsigned int                   n_files   = 0;
    double                         time_read = 0;
    std::vector<std::vector<char>> files;
    std::vector<std::map<std::string, std::pair<std::size_t, std::size_t>>>
      sections_of_file;

    /// Check one file image against the scene (InputError).
    void
    check_file(const std::vector<char> &image,
               const std::string       &file,
               const unsigned int       rank,
               const unsigned int       n_ranks);
  };
} // namespace femp

#endif
