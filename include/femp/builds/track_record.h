// femp: what a process engineer compares between builds (doc/builds.md,
// "Tracks and layers"): per track of the scan path and per layer, the bead
// height and width, the re-melt depth into the layer below (or the plate),
// and the overlap of the fusion zones of neighbouring tracks, measured from
// femp's own fields on the background grid.
//
//   - a track: a maximal run of consecutive scan-path segments with the
//     laser on; its axis runs from the first segment's start to the last
//     one's end (in the horizontal plane); its layer: 1 + the layers of the
//     schedule that started before it;
//   - its record: from its start to the start of the next track (or of the
//     next layer, before the recoat; the last track: to the end of the
//     run), the peak temperature of every metal cell (alpha >= 1/2) that
//     melted during it: a cell still at or above the solidus when the
//     record opens (the pool of an earlier track) counts only after it
//     has fallen below the solidus; the fusion zone is where that peak
//     reached the solidus, its boundary interpolated linearly between
//     cell centres;
//   - the layer's base: the top of the fused metal (alpha (1 - s_p) = 1/2,
//     s_p the unfused powder share, interpolated along the vertical) in
//     every grid column when the layer's first track starts;
//   - measured when the record closes, in cross-sections over the middle
//     half of the track (one per cell size along it), each quantity the
//     mean over the sections: the width (the widest lateral extent of the
//     fusion zone around the axis over the cell rows), the re-melt depth
//     (the largest depth of the fusion zone below the layer's base; < 0:
//     the zone did not reach it), the bead height (the highest fused
//     surface above the base over the middle half of the fusion zone's
//     width) and the overlap with the previous track of the same layer (the
//     widest common lateral extent of the two fusion zones over the rows;
//     the ratio: over this track's width).
// In 2D the track runs along x in the plane: width and overlap are not
// defined (written as nan). Every rank holds the whole grid's record after
// a reduction at each close (8 bytes per cell and track kept: this one and
// the previous), so the result does not depend on the partition.
#ifndef femp_track_record_h
#define femp_track_record_h

#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/point.h>

#include <femp/base/parameter_table.h>
#include <femp/base/state_stream.h>
#include <femp/grid/background_grid.h>
#include <femp/heat/laser.h>

#include <fstream>
#include <limits>
#include <string>
#include <vector>

namespace femp
{
  using namespace dealii;

  template <int dim>
  class TrackRecord
  {
  public:
    struct Parameters
    {
      /// Build/Track report: automatic (a scan path of more than one
      /// track, or a layer schedule), on or off.
      AutoSwitch report = AutoSwitch::automatic;

      /// Declare (the members' values are the defaults) or read the
      /// entries, each listed once.
      void
      add_parameters(ParameterTable &table);
      static void
      declare_parameters(ParameterHandler &prm);
      void
      parse_parameters(ParameterHandler &prm);
      /// Whether the tracks are reported ('auto': @p n_tracks > 1 or
      /// @p builds, a layer schedule).
      bool
      enabled(const unsigned int n_tracks, const bool builds) const
      {
        return report == AutoSwitch::on ||
               (report == AutoSwitch::automatic && (n_tracks > 1 || builds));
      }
    };

    struct Track
    {
      unsigned int layer    = 1; ///< 1, 2, ...
      unsigned int in_layer = 1; ///< its number within the layer
      double       t_start  = 0; ///< laser on, s
      double       t_end    = 0; ///< laser off, s
      /// The record closes at the first step that reaches this time, s
      /// (infinite for the last track: at the end of the run).
      double     t_close = std::numeric_limits<double>::infinity();
      Point<dim> a, b; ///< the axis, m
    };

    /// One row of tracks.csv (lengths in m, times in s, T in K).
    struct Row
    {
      unsigned int layer = 0, track = 0, in_layer = 0, sections = 0;
      double       t_start = 0, t_end = 0, t_measured = 0, length = 0;
      double       bead_height = 0, width = 0, remelt_depth = 0;
      double       overlap = 0, overlap_ratio = 0;
      double       T_max = 0; ///< hottest metal of the sections when measured
    };

    /// The tracks of @p segments; @p layer_starts: the start times of the
    /// layers after the first (increasing).
    static std::vector<Track>
    find_tracks(const std::vector<typename Laser<dim>::Segment> &segments,
                const std::vector<double>                       &layer_starts);

    /// @p T_solidus: the isotherm of the fusion zone, K; @p directory: where
    /// tracks.csv and layers.csv go (rank 0).
    TrackRecord(const BackgroundGrid<dim> &grid,
                const std::vector<Track>  &tracks,
                const double               T_solidus,
                const std::string         &directory);

    const std::vector<Track> &
    tracks() const
    {
      return list;
    }
    /// Whether a record closes or opens before the step ending at
    /// @p t_next (then call update()).
    bool
    due(const double t_next) const;
    /// Before the step from @p time to @p t_next: close the open record
    /// whose close time lies before @p t_next (measure it with the fused
    /// metal fraction @p fused = alpha (1 - s_p) and the temperature @p T,
    /// owned values of the local box; write its row), then open the track
    /// that starts before @p t_next (its layer's first: the base from
    /// @p fused; a cell with @p T at or above the solidus is still molten
    /// from an earlier track). Returns the rows written. Collective.
    std::vector<Row>
    update(const double               time,
           const double               t_next,
           const std::vector<double> &fused,
           const std::vector<double> &T);
    /// After a temperature step: the peak temperature of the metal cells
    /// (@p alpha >= 1/2) of the open record (not of a cell molten since
    /// the record opened: one that has not yet solidified).
    void
    observe(const std::vector<double> &T, const std::vector<double> &alpha);
    /// At the end of the run: close the open record at @p time. Collective.
    std::vector<Row>
    finish(const double               time,
           const std::vector<double> &fused,
           const std::vector<double> &T);

    /// The measurement of track @p k from the global (whole-grid, cell
    /// index i + n_x (j + n_y k)) peak temperatures @p peak of it and
    /// @p peak_previous of the previous track of its layer (empty: none),
    /// the base @p base and fused surface @p top per grid column (index
    /// i + n_x j) and the temperature @p T_global. Same on every rank.
    Row
    measure(const unsigned int         k,
            const std::vector<double> &peak,
            const std::vector<double> &peak_previous,
            const std::vector<double> &base,
            const std::vector<double> &top,
            const std::vector<double> &T_global) const;
    /// Per grid column, the height where the global field @p fused falls
    /// to 1/2 from below, interpolated between cell centres (the lower
    /// corner's height where even the lowest cell is below 1/2).
    std::vector<double>
    surface(const std::vector<double> &fused) const;
    /// The whole grid's field from the owned values of @p local, combined
    /// by max over the ranks (collective).
    std::vector<double>
    global(const std::vector<double> &local) const;

    void
    save_state(StateWriter &out) const;
    /// Resume: the record, and tracks.csv and layers.csv rewritten from
    /// the rows saved.
    void
    load_state(StateReader &in);

  private:
    const BackgroundGrid<dim> &grid;
    const std::vector<Track>   list;
    const double               T_solidus;
    const std::string          directory;
    /// The track whose record is open (list.size(): none) and the next to
    /// open.
    unsigned int open_track = 0, next_track = 0;
    bool         is_open = false;
    /// Peak temperature per cell of the local box (owned values); -1: still
    /// molten from an earlier track.
    std::vector<double> peak;
    /// Global records kept: the previous closed track's peak, the base
    /// of the current layer per column.
    std::vector<double> previous_peak, base;
    unsigned int        previous_track = 0;
    bool                has_previous   = false;
    std::vector<Row>    rows;

    /// Close the open record at @p time: measure, write. Collective.
    Row
    close(const double               time,
          const std::vector<double> &fused,
          const std::vector<double> &T);
    void
    write_files() const;
  };
} // namespace femp

#endif
