// femp: SimulationControl, the clock of a run: simulated time and step
// number, the choice of the next temperature step (a hook set by the
// problem: the stable limit of the heat equation or the fluid step), the
// end test (end time or step limit), and when field output, the time
// series and the progress line are due (the cadence of the Output
// parameters). It holds no physics; FempProblem::run() asks it what to do
// next (the macro time loop of the paper's sec. 2.6).
#ifndef femp_simulation_control_h
#define femp_simulation_control_h

#include <deal.II/base/parameter_handler.h>

#include <femp/base/parameter_table.h>

#include <chrono>
#include <deque>
#include <functional>
#include <utility>
#include <vector>

namespace femp
{
  using namespace dealii;
  class StateWriter;
  class StateReader;

  class SimulationControl
  {
  public:
    /// Subsection 'Time stepping'.
    struct Parameters
    {
      double end_time      = 1e-3; ///< s
      double time_step     = 0;    ///< s, 0: automatic
      double safety_factor = 0.5;  ///< of the stable limit, (0, 1]
      /// s, 0: off. With a prescribed time_step: the temperature step
      /// while the laser's path has ended and the workpiece is below the
      /// solidus (the driver decides; at most safety_factor times the
      /// stable limit).
      double       time_step_solidified = 0;
      unsigned int max_steps            = 100000000;
      /// K; 0: off. After the laser's path, end the run once the hottest
      /// metal cell is below this temperature (the driver asks for it).
      double stop_temperature = 0;

      /// Declare (the members' values are the defaults) or read the

      /// entries, each listed once.

      void

      add_parameters(ParameterTable &table);

      static void
      declare_parameters(ParameterHandler &prm);
      void
      parse_parameters(ParameterHandler &prm);
    };

    /// How often to write (from the Output parameters): field output every
    /// @p output_interval s (0: off) and every @p output_steps steps (0:
    /// off), the time series every @p series_interval s (0: every step),
    /// the progress line every @p progress_interval steps. The first and
    /// the last step always write.
    struct Cadence
    {
      double       output_interval   = 1e-4;
      unsigned int output_steps      = 0;
      double       series_interval   = 0;
      unsigned int progress_interval = 100;
    };

    /// The step chooser: the wanted temperature step at (step, time) before
    /// it is shortened to end at the end time.
    using StepChooser =
      std::function<double(const unsigned int step, const double time)>;

    SimulationControl(const Parameters &prm, const Cadence &cadence);

    /// Start the wall clock (for the progress line).
    void
    start_clock();
    /// The wall clock of a run: its start and the recent (wall, simulated
    /// time) samples of wall_time_left().
    struct Clock
    {
      std::chrono::steady_clock::time_point start;
      std::deque<std::pair<double, double>> samples;
    };
    Clock
    clock() const
    {
      return {wall_start, rate_samples};
    }
    /// Go on with the wall clock @p c of the part of the run before a
    /// rebalance (in this process), as one run: the progress line's wall
    /// and estimate count from the run's start.
    void
    continue_clock(const Clock &c)
    {
      wall_start   = c.start;
      rate_samples = c.samples;
    }
    void
    set_step_chooser(const StepChooser &chooser)
    {
      choose = chooser;
    }

    /// True while the end time and the step limit are not reached.
    bool
    running() const;
    /// The next step: the chooser's step, shortened to end at the end time.
    double
    next_time_step() const;
    /// Advance the clock by @p dt (time, step number, last-step flag).
    void
    advance(const double dt);
    /// Make the step that the next advance() takes the last one (a stop
    /// condition met before the end time, e.g. the scene has cooled down).
    void
    request_stop()
    {
      stop_requested = true;
    }
    /// The step just taken is the last one.
    bool
    is_last() const
    {
      return last;
    }

    double
    time() const
    {
      return t;
    }
    unsigned int
    step() const
    {
      return n_step;
    }
    /// The size of the last step, s.
    double
    time_step() const
    {
      return dt_last;
    }
    const Parameters &
    parameters() const
    {
      return prm;
    }

    /// Time series due at this step? series_written() sets the next time.
    bool
    series_due() const;
    void
    series_written();
    /// Field output due at this step? output_written() counts the file and
    /// moves the next output time past now.
    bool
    output_due() const;
    /// Number of the next field output (0 for the initial state).
    unsigned int
    output_number() const
    {
      return n_output;
    }
    void
    output_written();
    /// Progress line due at this step?
    bool
    progress_due() const;
    /// Wall time since start_clock(), s, and the estimate of what is left:
    /// the simulated time left times the wall time per simulated second of
    /// the last quarter of the run so far (or of the whole run so far, if
    /// that is slower).
    double
    wall_time() const;
    double
    wall_time_left() const;

    /// Checkpoint (Checkpoint<dim>): time, step, last step and the output,
    /// series and progress cadence.
    void
    save_state(StateWriter &out) const;
    void
    load_state(std::vector<StateReader> &parts);

  private:
    Parameters                            prm;
    Cadence                               cadence;
    StepChooser                           choose;
    double                                t = 0, dt_last = 0;
    unsigned int                          n_step = 0, n_output = 0;
    bool                                  last = false, stop_requested = false;
    double                                next_output, next_series     = 0;
    std::chrono::steady_clock::time_point wall_start;
    /// (wall time, simulated time) samples of the recent past.
    std::deque<std::pair<double, double>> rate_samples;
    void
    record_rate_sample();
  };
} // namespace femp

#endif
