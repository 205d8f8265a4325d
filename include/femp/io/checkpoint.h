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
// previous checkpoint valid. The last two are kept.
#ifndef femp_checkpoint_h
#define femp_checkpoint_h

#include <deal.II/base/parameter_handler.h>

#include <femp/grid/background_grid.h>

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

  /// Bytes of one module's state on one rank (plain copies of trivially
  /// copyable values; vectors and strings with their length first).
  class StateWriter
  {
  public:
    template <typename T>
    void
    put(const T &value)
    {
      static_assert(std::is_trivially_copyable<T>::value,
                    "only plain values are written");
      const char *p = reinterpret_cast<const char *>(&value);
      data.insert(data.end(), p, p + sizeof(T));
    }
    template <typename T>
    void
    put_vector(const std::vector<T> &values)
    {
      static_assert(std::is_trivially_copyable<T>::value,
                    "only plain values are written");
      put<std::uint64_t>(values.size());
      const char *p = reinterpret_cast<const char *>(values.data());
      data.insert(data.end(), p, p + sizeof(T) * values.size());
    }
    void
    put_string(const std::string &s)
    {
      put<std::uint64_t>(s.size());
      data.insert(data.end(), s.begin(), s.end());
    }
    const std::vector<char> &
    bytes() const
    {
      return data;
    }

  private:
    std::vector<char> data;
  };

  /// Reads what a StateWriter wrote; throws (naming @p what) on reading past
  /// the end, which a checksum-verified file only does when the format of
  /// the writer and the reader differ.
  class StateReader
  {
  public:
    StateReader(const char        *begin,
                const std::size_t  size,
                const std::string &what)
        : p(begin)
        , end(begin + size)
        , what(what)
    {
    }
    template <typename T>
    T
    get()
    {
      static_assert(std::is_trivially_copyable<T>::value,
                    "only plain values are read");
      T value;
      check(sizeof(T));
      std::memcpy(&value, p, sizeof(T));
      p += sizeof(T);
      return value;
    }
    template <typename T>
    std::vector<T>
    get_vector()
    {
      const auto n = get<std::uint64_t>();
      check(n * sizeof(T));
      std::vector<T> values(n);
      std::memcpy(values.data(), p, n * sizeof(T));
      p += n * sizeof(T);
      return values;
    }
    std::string
    get_string()
    {
      const auto n = get<std::uint64_t>();
      check(n);
      std::string s(p, p + n);
      p += n;
      return s;
    }
    /// Skip @p n bytes.
    void
    skip(const std::uint64_t n)
    {
      check(n);
      p += n;
    }
    bool
    at_end() const
    {
      return p == end;
    }

  private:
    const char *p, *end;
    std::string what;
    void
    check(const std::uint64_t n) const;
  };

  /// Global linear index i + n_0 (j + n_1 k) of the structured cell @p ijk.
  template <int dim, typename Index>
  std::uint64_t
  global_cell_number(const BackgroundGrid<dim> &grid, const Index &ijk)
  {
    std::uint64_t g = 0;
    for (int d = dim - 1; d >= 0; --d)
      g = g * grid.n_cells()[d] + ijk[d];
    return g;
  }

  /// Local flat index of the cell with global linear index @p g if this
  /// rank owns it, else numbers::invalid_size_type-like -1.
  template <int dim>
  std::int64_t
  owned_local_index(const BackgroundGrid<dim> &grid, std::uint64_t g)
  {
    std::array<int, dim> ijk;
    for (int d = 0; d < dim; ++d)
      {
        ijk[d] = g % grid.n_cells()[d];
        g /= grid.n_cells()[d];
      }
    if (!grid.in_box(ijk))
      return -1;
    const auto idx = grid.local_index(ijk);
    return grid.cell_status()[idx] == BackgroundGrid<dim>::owned ?
             std::int64_t(idx) :
             -1;
  }

  /// Save the owned values of cell fields (same size as the local box),
  /// keyed by the global cell number.
  template <int dim>
  void
  save_cell_fields(StateWriter                                    &out,
                   const BackgroundGrid<dim>                      &grid,
                   const std::vector<const std::vector<double> *> &fields)
  {
    const auto                &owned = grid.owned_cells();
    std::vector<std::uint64_t> keys(owned.size());
    for (std::size_t k = 0; k < owned.size(); ++k)
      keys[k] = global_cell_number(grid, grid.global_index(owned[k]));
    out.put<std::uint32_t>(fields.size());
    out.put_vector(keys);
    std::vector<double> v(owned.size());
    for (const auto *f : fields)
      {
        for (std::size_t k = 0; k < owned.size(); ++k)
          v[k] = (*f)[owned[k]];
        out.put_vector(v);
      }
  }

  /// Restore what save_cell_fields() wrote, from the parts of all saved
  /// ranks: each rank keeps its owned cells; ghosts are exchanged.
  template <int dim>
  void
  load_cell_fields(std::vector<StateReader>                 &parts,
                   const BackgroundGrid<dim>                &grid,
                   const std::vector<std::vector<double> *> &fields)
  {
    for (auto &in : parts)
      {
        const auto n_fields = in.get<std::uint32_t>();
        AssertThrow(n_fields == fields.size(),
                    ExcMessage("checkpoint: wrong number of cell fields"));
        const auto                keys = in.get_vector<std::uint64_t>();
        std::vector<std::int64_t> local(keys.size());
        for (std::size_t k = 0; k < keys.size(); ++k)
          local[k] = owned_local_index(grid, keys[k]);
        for (auto *f : fields)
          {
            const auto v = in.get_vector<double>();
            for (std::size_t k = 0; k < keys.size(); ++k)
              if (local[k] >= 0)
                (*f)[local[k]] = v[k];
          }
      }
    for (auto *f : fields)
      grid.update_ghosts(*f);
  }

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
    /// @p step, @p time (collective); returns its directory.
    std::string
    write(
      const unsigned int                                              step,
      const double                                                    time,
      const std::vector<std::pair<std::string, const StateWriter *>> &sections);

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
