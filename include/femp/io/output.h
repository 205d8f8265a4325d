// femp: output of a scene: the grid fields and the material points as
// PVTU pieces with .pvd time series, or as HDF5 files with XDMF time series
// (Output/Format), a chosen subset of fields and point properties, CSV probe
// points and probe lines, and the CSV time series of the melt-pool size.
#ifndef femp_output_h
#define femp_output_h

#include <deal.II/base/parameter_handler.h>
#include <deal.II/particles/particle_handler.h>

#include <femp/base/parameter_table.h>
#include <femp/grid/background_grid.h>
#include <femp/heat/melt_pool.h>

#include <cstdint>
#include <fstream>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace femp
{
  using namespace dealii;
  class StateWriter;
  class StateReader;

  template <int dim>
  class Output
  {
  public:
    struct ProbeLine
    {
      std::string  name;
      Point<dim>   start, end;
      unsigned int n_samples;
    };

    struct Parameters
    {
      std::string directory       = "output";
      double      output_interval = 1e-4;
      /// When the material points are written.
      enum class WritePoints
      {
        always,
        last,
        never
      };
      /// The file format of grid fields and points.
      enum class Format
      {
        vtu,
        hdf5
      };
      WritePoints write_points = WritePoints::last;
      /// The input names of WritePoints (Output/Write material points).
      static const Choices<WritePoints>        &
      write_points_names();
      Format format = Format::vtu;
      /// The input names of Format (Output/Format).
      static const Choices<Format> &
      format_names();
      /// Output/Existing directory: 'refuse' (true) or 'clear' (false).
      bool refuse_existing = false;
      /// Its input names.
      static const Choices<bool> &
      existing_directory_names();
      /// Point properties and grid fields to write; empty: all.
      std::vector<std::string> point_properties, grid_fields;
      double                   series_interval   = 0;
      unsigned int             output_steps      = 0;
      unsigned int             progress_interval = 100;
      /// Probe values: the containing cell's ("cell") or interpolated
      /// between cell centres, weighted by the metal fraction ("linear").
      bool                    probe_linear = false;
      std::vector<Point<dim>> probe_points;
      std::vector<ProbeLine>  probe_lines;
      /// Output/Melt pool from x as written (empty: the whole domain) and
      /// its value, m: melt_pool.csv counts the cells with centre x at or
      /// above it (-inf: all).
      std::string melt_pool_from_x_text;
      double      melt_pool_from_x = -std::numeric_limits<double>::infinity();

      /// Declare (the members' values are the defaults) or read the

      /// entries, each listed once.

      void

      add_parameters(ParameterTable &table);

      static void
      declare_parameters(ParameterHandler &prm);
      void
      parse_parameters(ParameterHandler &prm);
      /// Probes must lie in the domain box [lo, hi], 'Melt pool from x'
      /// below its upper x.
      void
      check(const Point<dim> &lo, const Point<dim> &hi) const;
    };

    /// A named cell field over the local box. A field that is not
    /// continuous (a tag such as the phase or the zone) is never
    /// interpolated by the probes.
    struct Field
    {
      std::string                name;
      const std::vector<double> *values;
      bool                       continuous = true;
    };

    Output(const Parameters &prm, const BackgroundGrid<dim> &grid);

    /// Create the directory and open the CSV files (rank 0); with
    /// @p resume the CSV files are opened by load_state() instead.
    void
    initialize(const std::vector<std::string> &probe_quantities,
               const bool                      resume = false);

    /// Checkpoint: the .pvd records and the length of the CSV series.
    void
    save_state(StateWriter &out) const;
    /// Cut the CSV series back to their length at the checkpoint (rows
    /// after it are dropped) and append from there; the .pvd indices list
    /// the outputs up to the checkpoint again (rank 0 writes).
    void
    load_state(std::vector<StateReader> &parts);

    /// Write grid fields (and points) for output number @p n at @p time.
    void
    write_fields(const unsigned int                     n,
                 const double                           time,
                 const std::vector<Field>              &fields,
                 const Particles::ParticleHandler<dim> *points,
                 const std::vector<std::string>        &point_names);

    /// Append one row to the probe-point and melt-pool CSV files.
    void
    write_series(const double              time,
                 const std::vector<Field> &probe_fields,
                 const MeltPoolSize       &pool);

    /// Write every probe line's samples for output number @p n.
    void
    write_probe_lines(const unsigned int        n,
                      const double              time,
                      const std::vector<Field> &probe_fields);
    /// The same into files probe_line_<name>_<tag>.csv.
    void
    write_probe_lines(const std::string        &tag,
                      const double              time,
                      const std::vector<Field> &probe_fields);

    const Parameters &
    parameters() const
    {
      return prm;
    }

    /// Values of @p fields at @p points, point by point (global, on all
    /// ranks; collective). With "Probe interpolation = cell" the value of
    /// the containing cell; with "linear" the multilinear interpolation
    /// between the 2^dim nearest cell centres, each weighted by its metal
    /// fraction (the field named "alpha", if given), so that gas cells do
    /// not pull a surface value towards theirs. Non-continuous fields and
    /// points with no metal around take the containing cell's value.
    std::vector<double>
    sample(const std::vector<Point<dim>> &points,
           const std::vector<Field>      &fields) const;

  private:
    Parameters                                  prm;
    const BackgroundGrid<dim>                  &grid;
    std::ofstream                               probe_csv, pool_csv;
    std::vector<std::pair<double, std::string>> grid_records, point_records;
    /// XDMF <Grid> elements of the outputs written so far.
    std::vector<std::string> grid_entries, point_entries;
    bool                     grid_mesh_written = false;
    std::uint64_t            grid_mesh_nodes   = 0; ///< all ranks'
    /// HDF5 mesh file of the grid outputs (a run resumed on another
    /// partition, whose cells lie in another order, writes a new one).
    std::string grid_mesh_file = "grid_mesh.h5";
    /// Fingerprint of the partition that wrote grid_mesh_file (the number
    /// of ranks and their cell counts; 0: none yet).
    unsigned int grid_mesh_partition = 0;

    /// Write the selected grid fields in the chosen format, and the index.
    void
    write_grid_output(const unsigned int        n,
                      const double              time,
                      const std::vector<Field> &fields);
    /// Write the selected point properties in the chosen format, and the
    /// index.
    void
    write_point_output(const unsigned int                     n,
                       const double                           time,
                       const Particles::ParticleHandler<dim> &points,
                       const std::vector<std::string>        &point_names);
  };
  /// On resume from a checkpoint at @p time: keep the lines of the CSV
  /// time series @p file that do not start with a number (the header) and
  /// the rows whose first column (the time) is not after @p time, and open
  /// @p stream on it for appending. A missing file leaves @p stream closed.
  /// Called by the rank that writes the file; throws if it cannot be
  /// rewritten.
  void
  reopen_series_at(std::ofstream     &stream,
                   const std::string &file,
                   const double       time);
} // namespace femp

#endif
