// femp: output of a scene: PVTU files of the grid fields and of the material
// points with .pvd time series for ParaView, CSV probe points and probe
// lines, and the CSV time series of the melt-pool size.
#ifndef femp_output_h
#define femp_output_h

#include <deal.II/base/parameter_handler.h>
#include <deal.II/particles/particle_handler.h>

#include <femp/grid/background_grid.h>
#include <femp/heat/melt_pool.h>

#include <fstream>
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
      std::string            directory       = "output";
      double                 output_interval = 1e-4;
      std::string            write_points    = "last"; ///< always|last|never
      double                 series_interval = 0;
      unsigned int           output_steps    = 0;
      unsigned int           progress_interval = 100;
      std::vector<Point<dim>> probe_points;
      std::vector<ProbeLine>  probe_lines;

      static void
      declare_parameters(ParameterHandler &prm);
      void
      parse_parameters(ParameterHandler &prm);
      /// Probes must lie in the domain box [lo, hi].
      void
      check(const Point<dim> &lo, const Point<dim> &hi) const;
    };

    /// A named cell field over the local box.
    struct Field
    {
      std::string                name;
      const std::vector<double> *values;
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
    write_fields(const unsigned int                       n,
                 const double                             time,
                 const std::vector<Field> &               fields,
                 const Particles::ParticleHandler<dim> *  points,
                 const std::vector<std::string> &         point_names);

    /// Append one row to the probe-point and melt-pool CSV files.
    void
    write_series(const double                 time,
                 const std::vector<Field> &   probe_fields,
                 const MeltPoolSize &         pool);

    /// Write every probe line's samples for output number @p n.
    void
    write_probe_lines(const unsigned int n,
                      const double       time,
                      const std::vector<Field> &probe_fields);

    const Parameters &
    parameters() const
    {
      return prm;
    }

  private:
    Parameters                 prm;
    const BackgroundGrid<dim> &grid;
    std::ofstream              probe_csv, pool_csv;
    std::vector<std::pair<double, std::string>> grid_records, point_records;

    /// Value of @p field in the cell containing @p p (global, on all ranks).
    std::vector<double>
    sample(const std::vector<Point<dim>> &points,
           const std::vector<Field> &     fields) const;
  };
} // namespace femp

#endif
