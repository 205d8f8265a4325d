// femp: SimulationControl, the clock and output cadence of a run (see the
// header).
#include <femp/app/simulation_control.h>
#include <femp/base/collective_error.h>
#include <femp/base/input_checks.h>
#include <femp/base/parameter_table.h>
#include <femp/base/progress_watchdog.h>
#include <femp/io/checkpoint.h>

#include <algorithm>

namespace femp
{
  void
  SimulationControl::Parameters::add_parameters(ParameterTable &table)
  {
    table.enter_subsection("Time stepping");
    table.add("End time",
              end_time,
              Patterns::Double(0.),
              "Simulated time at which the run ends, s; range (0, inf).");
    table.add("Time step",
              time_step,
              Patterns::Double(0.),
              "Temperature step, s; 0 chooses it automatically as the "
              "safety factor times the stable limit. A prescribed step "
              "above the stable limit is refused. Range [0, inf).");
    table.add("Safety factor",
              safety_factor,
              Patterns::Double(0., 1.),
              "Fraction C of the stable limit h^2 rho c / sum(lambda_f) "
              "(diffusion) and h/|u| (convection) used as the "
              "automatic step; range (0, 1].");
    table.add("Time step after solidification",
              time_step_solidified,
              Patterns::Double(0.),
              "Temperature step, s, while the laser's path has "
              "ended and the workpiece (the metal attached to the "
              "substrate; detached spatter may still be liquid) is "
              "below the solidus: the cooling, where temperatures "
              "change slowly, in fewer steps; the flow and the solid "
              "sub-cycle inside it as before. At most 'Safety "
              "factor' times the stable limit of the step (the "
              "smaller is taken). Checked at every step: metal that "
              "melts again brings 'Time step' back. 0 (default): "
              "'Time step' to the end. Range 0 or [Time step, inf) "
              "with a prescribed 'Time step' (doc/cases.md, "
              "\"Longer temperature steps in the cooling\").");
    table.add("Maximum number of steps",
              max_steps,
              Patterns::Integer(1),
              "Stop after this many steps even before the end time.");
    table.add("Stop when peak temperature below",
              stop_temperature,
              Patterns::Double(0.),
              "K; 0: off. Once the laser has finished its path (the "
              "end of its last segment; it is off after that), end "
              "the run at the first temperature step after which the "
              "hottest cell of the metal attached to the substrate "
              "is below this temperature (metal connected to the "
              "bottom of the domain through face neighbours with "
              "alpha > 0, the cells that conduct heat to the "
              "substrate: spatter droplets in the gas do not "
              "count), with "
              "the field output of the last step (e.g. the residual "
              "stress on the probe lines after cooling). The run "
              "still ends at 'End time' at the latest. Range 0 or "
              "above the initial temperature.");
    table.leave_subsection();
  }

  void
  SimulationControl::Parameters::declare_parameters(ParameterHandler &prm)
  {
    Parameters     defaults;
    ParameterTable table(prm, ParameterTable::Mode::declare);
    defaults.add_parameters(table);
  }

  void
  SimulationControl::Parameters::parse_parameters(ParameterHandler &prm)
  {
    ParameterTable table(prm, ParameterTable::Mode::parse);
    add_parameters(table);
    prm.enter_subsection("Time stepping");
    prm.leave_subsection();
    require(end_time > 0,
            "Time stepping/End time",
            end_time,
            "it must be positive (s)");
    require(safety_factor > 0,
            "Time stepping/Safety factor",
            safety_factor,
            "it must lie in (0, 1]");
    if (time_step_solidified != 0)
      {
        const std::string name = "Time stepping/Time step after solidification";
        require(time_step > 0,
                name,
                time_step_solidified,
                "it replaces a prescribed step: it needs 'Time stepping/Time "
                "step' > 0 (the automatic step 0 is already the largest "
                "stable one)");
        require(time_step_solidified >= time_step,
                name,
                time_step_solidified,
                "it must be 0 (keep 'Time step') or at least 'Time step' = " +
                  num(time_step) + " s");
      }
  }

  SimulationControl::SimulationControl(const Parameters &prm,
                                       const Cadence    &cadence)
      : prm(prm)
      , cadence(cadence)
      , next_output(cadence.output_interval)
      , wall_start(std::chrono::steady_clock::now())
  {
  }

  void
  SimulationControl::start_clock()
  {
    wall_start = std::chrono::steady_clock::now();
  }

  bool
  SimulationControl::running() const
  {
    return !last && t < prm.end_time * (1 - 1e-12) && n_step < prm.max_steps;
  }

  double
  SimulationControl::next_time_step() const
  {
    return std::min(choose(n_step, t), prm.end_time - t);
  }

  void
  SimulationControl::advance(const double dt)
  {
    // A step that cannot move the time on would repeat until the step
    // bound (collective: dt is the same on every rank).
    if (!(t + dt > t))
      throw CollectiveError(
        "the temperature step " + num(dt) + " s makes no progress at t = " +
        num(t) + " s (step " + std::to_string(n_step) +
        "; it is below the round-off of the time): the stable limit of the "
        "explicit temperature step has collapsed (" +
        (prm.time_step > 0 ?
           "'Time stepping/Time step' = " + num(prm.time_step) + " s" :
           std::string("a temperature running away?")) +
        ")");
    t += dt;
    ++n_step;
    progress::time(t, n_step);
    dt_last = dt;
    last    = t >= prm.end_time * (1 - 1e-12) || n_step >= prm.max_steps ||
           stop_requested;
    record_rate_sample();
  }

  void
  SimulationControl::record_rate_sample()
  {
    // A (wall, simulated time) sample at most every 1/64 of the elapsed
    // wall time; the window of wall_time_left() is the last quarter.
    const double wall = wall_time();
    if (!rate_samples.empty() && wall - rate_samples.back().first < wall / 64)
      return;
    rate_samples.emplace_back(wall, t);
    while (rate_samples.size() > 2 && rate_samples[1].first <= 0.75 * wall)
      rate_samples.pop_front();
  }

  bool
  SimulationControl::series_due() const
  {
    return t >= next_series * (1 - 1e-12) || last;
  }

  void
  SimulationControl::series_written()
  {
    next_series = t + cadence.series_interval;
  }

  bool
  SimulationControl::output_due() const
  {
    return (cadence.output_interval > 0 && t >= next_output * (1 - 1e-9)) ||
           (cadence.output_steps > 0 && n_step % cadence.output_steps == 0) ||
           last;
  }

  void
  SimulationControl::output_written()
  {
    ++n_output;
    while (next_output <= t * (1 + 1e-9) && cadence.output_interval > 0)
      next_output += cadence.output_interval;
  }

  bool
  SimulationControl::progress_due() const
  {
    return n_step % cadence.progress_interval == 0 || last;
  }

  double
  SimulationControl::wall_time() const
  {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() -
                                         wall_start)
      .count();
  }

  double
  SimulationControl::wall_time_left() const
  {
    // The cost per simulated second grows while a melt pool grows (more
    // fluid cells, more flow and solid sub-steps), so the rate of the last
    // quarter of the wall time predicts the rest better than the mean since
    // the start, which is several times too optimistic in a heating phase.
    const double wall = wall_time();
    const double left = std::max(0., prm.end_time - t);
    // The last step (the end time, or a stop condition met before it).
    if (t <= 0 || last)
      return 0;
    double rate = wall / t;
    if (!rate_samples.empty() && t > rate_samples.front().second &&
        wall > rate_samples.front().first)
      rate = std::max(rate,
                      (wall - rate_samples.front().first) /
                        (t - rate_samples.front().second));
    return rate * left;
  }

  void
  SimulationControl::save_state(StateWriter &out) const
  {
    out.put(t);
    out.put(dt_last);
    out.put(n_step);
    out.put(n_output);
    out.put<std::uint8_t>(last);
    out.put(next_output);
    out.put(next_series);
  }

  void
  SimulationControl::load_state(std::vector<StateReader> &parts)
  {
    // The same on every rank: the first part holds it.
    auto &in = parts[0];
    t        = in.get<double>();
    dt_last  = in.get<double>();
    n_step   = in.get<unsigned int>();
    n_output = in.get<unsigned int>();
    in.get<std::uint8_t>(); // 'last': from this run's end time instead
    next_output = in.get<double>();
    next_series = in.get<double>();
    // A resumed run with a later end time goes on past the old last step.
    last = !running();
  }
} // namespace femp
