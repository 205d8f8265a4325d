// femp: thermal history of every background-grid cell for microstructure
// codes (cellular automata such as ExaCA, phase field). It watches the
// temperature of eq. (1) after each step and records each melt event of a
// metal cell: the time t_m it rose above the liquidus T_l, the time t_l it
// fell below it again, the time t_s it fell below the solidus T_s, and at
// t_l the cooling rate cr = -dT/dt, the temperature gradient G = |grad T|
// and the isotherm speed R = cr / G. Crossing times are interpolated
// linearly within the step. Each rank writes its own cells to
//   <Output/Directory>/thermal_history_<rank>.csv        x,y,z,tm,tl,cr
//   <Output/Directory>/thermal_history_full_<rank>.csv   ... ts,G,R too
// (m, s, K/s, K/m, m/s; ExaCA reads the first layout). A cell still above
// the liquidus at the end is not listed; ts = -1 when the solidus was not
// reached, because the run ended or the cell melted again from the mush
// (then a new event starts at the new t_m).
#ifndef femp_thermal_history_h
#define femp_thermal_history_h

#include <deal.II/base/parameter_handler.h>

#include <femp/base/parameter_table.h>
#include <femp/grid/background_grid.h>

#include <string>
#include <vector>

namespace femp
{
  using namespace dealii;
  class StateWriter;
  class StateReader;

  template <int dim>
  class ThermalHistory
  {
  public:
    struct Parameters
    {
      bool enabled = false;

      /// Declare (the members' values are the defaults) or read the

      /// entries, each listed once.

      void

      add_parameters(ParameterTable &table);

      static void
      declare_parameters(ParameterHandler &prm);
      void
      parse_parameters(ParameterHandler &prm);
    };

    /// One melt event of one cell.
    struct Event
    {
      std::uint32_t cell; ///< local flat index
      double        tm, tl, ts, cooling_rate, gradient;
    };

    /// Start watching @p T (the temperature at @p time) on @p grid; cells
    /// already above @p liquidus count as melted at @p time.
    ThermalHistory(const BackgroundGrid<dim> &grid,
                   const double               solidus,
                   const double               liquidus,
                   const std::vector<double> &T,
                   const std::vector<double> &alpha,
                   const double               time);

    /// The temperature @p T after a step ending at @p time; @p alpha is the
    /// metal fraction (cells without metal are skipped).
    void
    observe(const std::vector<double> &T,
            const std::vector<double> &alpha,
            const double               time);

    /// Melt events that crossed the liquidus on the way down, so far.
    const std::vector<Event> &
    events() const
    {
      return finished;
    }

    /// Write this rank's two CSV files into @p directory (which must exist).
    void
    write(const std::string &directory) const;

    /// Checkpoint: per owned cell the last temperature, melt state and
    /// time and the open event; the finished events with their cell.
    void
    save_state(StateWriter &out) const;
    void
    load_state(std::vector<StateReader> &parts);

  private:
    double
    gradient(const std::vector<double> &T,
             const std::vector<double> &alpha,
             const std::size_t          idx) const;

    const BackgroundGrid<dim> &grid;
    const double               T_s, T_l;
    double                     t_old;
    std::vector<double>        T_old;
    /// Per owned cell (same order as grid.owned_cells()): 0 solid, 1 above
    /// the liquidus, 2 in the mush after the liquidus crossing.
    std::vector<std::uint8_t> state;
    std::vector<double>       melt_time;
    std::vector<std::int64_t> open_event; ///< index in finished, or -1
    std::vector<Event>        finished;
  };
} // namespace femp

#endif
