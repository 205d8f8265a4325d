// femp: the time-step policy: the temperature step, the cooling step, the
// projected step count and the termination criteria (time_step_policy.h).
#include <femp/app/run_checks.h>
#include <femp/app/time_step_policy.h>
#include <femp/base/collective_error.h>
#include <femp/base/input_checks.h>

#include <cmath>
#include <iomanip>
#include <sstream>

namespace femp
{
  template <int dim>
  TimeStepPolicy<dim>::TimeStepPolicy(const Scene<dim>              &scene,
                                      const Laser<dim>              &laser,
                                      HeatTransfer<dim>             &heat,
                                      MetalBodies<dim>              &bodies,
                                      const IncompressibleFlow<dim> *flow,
                                      ConditionalOStream            &out)
      : scene(scene)
      , laser(laser)
      , heat(heat)
      , bodies(bodies)
      , flow(flow)
      , out(out)
  {
  }

  template <int dim>
  bool
  TimeStepPolicy<dim>::after_path_and_below(const double time,
                                            const double T_limit)
  {
    return time >= laser.end_time() * (1 - 1e-12) &&
           workpiece_peak_temperature() < T_limit;
  }

  template <int dim>
  const MetalPeakTemperatures &
  TimeStepPolicy<dim>::metal_peak_temperatures()
  {
    if (!metal_peaks)
      metal_peaks = bodies.peak_temperatures(heat.temperature());
    return *metal_peaks;
  }

  template <int dim>
  double
  TimeStepPolicy<dim>::workpiece_peak_temperature()
  {
    return metal_peak_temperatures().workpiece();
  }

  template <int dim>
  double
  TimeStepPolicy<dim>::choose(const unsigned int     step,
                              const double           time,
                              const CellFields<dim> &fields)
  {
    const auto &prm = scene.time;
    if (!scene.heat_enabled)
      {
        // Frozen temperature: the prescribed step, else the fluid step.
        const double dt =
          prm.time_step > 0 ?
            prm.time_step :
            (scene.flow.time_step > 0 ? scene.flow.time_step :
                                        flow->stable_time_step().min());
        check_projected_steps(step, dt);
        return dt;
      }
    const double stable =
      step == 0 ? heat.stable_time_step(fields) : heat.last_stable_time_step();
    if (prm.time_step_solidified > 0)
      {
        // The cooling step, while the laser's path has ended and the
        // workpiece is below the solidus (checked at every step, the same
        // test as the solid's cooling switch), within the stable limit.
        const bool cooling = after_path_and_below(time, scene.material.solidus);
        const double dt_cooling =
          std::max(prm.time_step,
                   std::min(prm.time_step_solidified,
                            prm.safety_factor * stable));
        if (cooling != cooling_step)
          out << "Time stepping: at t = " << time << " s "
              << (cooling ? "the laser's path has ended and the workpiece "
                            "is below the solidus: temperature step " :
                            "metal attached to the workpiece is above the "
                            "solidus again: temperature step ")
              << (cooling ? dt_cooling : prm.time_step) << " s" << std::endl;
        cooling_step = cooling;
        // (Above the limit only if 'Time step' itself is: refused below.)
        if (cooling && dt_cooling <= stable)
          return dt_cooling;
      }
    const double dt =
      prm.time_step > 0 ? prm.time_step : prm.safety_factor * stable;
    if (prm.time_step > stable)
      {
        std::ostringstream s;
        s << "it exceeds the stable limit " << stable << " s of the explicit "
          << "temperature step"
          << (step > 0 ? " reached at step " + std::to_string(step) +
                           ", time " + num(time) + " s" :
                         std::string())
          << "; use 0 (automatic) or a step <= " << stable << " s";
        // Collective: the stable limit is a global minimum.
        throw CollectiveError(
          InputError("Time stepping/Time step", num(prm.time_step), s.str())
            .what());
      }
    check_projected_steps(step, dt);
    return dt;
  }

  template <int dim>
  void
  TimeStepPolicy<dim>::check_projected_steps(const unsigned int step,
                                             const double       dt) const
  {
    // No run that silently stops short: refuse a projected step count
    // above the bound (collective: dt is the same on every rank).
    const auto &prm = scene.time;
    if (step > 0 || prm.end_time / dt <= prm.max_steps)
      return;
    throw CollectiveError(
      InputError("Time stepping/Maximum number of steps",
                 std::to_string(prm.max_steps),
                 "the first step of " + num(dt) + " s needs about " +
                   num(std::ceil(prm.end_time / dt)) +
                   " steps to reach 'End time'; raise the bound or shorten "
                   "the scene")
        .what());
  }

  template <int dim>
  bool
  TimeStepPolicy<dim>::cooled_down(const double time_end)
  {
    const double T_stop = scene.time.stop_temperature;
    if (!(T_stop > 0 && scene.heat_enabled &&
          after_path_and_below(time_end, T_stop)))
      return false;
    std::ostringstream T_peak; // to 0.01 K: it lies just below
    T_peak << std::fixed << std::setprecision(2)
           << workpiece_peak_temperature();
    // (The stream keeps the precision of the last progress line: set it.)
    out << std::setprecision(6) << "Stopping at t = " << time_end
        << " s: the laser's path has ended and the peak "
           "temperature of the metal attached to the substrate "
        << T_peak.str() << " K is below " << T_stop << " K" << std::endl;
    return true;
  }

  template <int dim>
  bool
  TimeStepPolicy<dim>::solid_may_cool(const double time,
                                      const bool   solid_uses_cooling_step)
  {
    // With the melt flow, once the workpiece has solidified after the
    // laser's path (the metal attached to the substrate: spatter drops in
    // the gas may stay liquid): the larger cooling step of the same
    // accuracy.
    const auto &s = scene.solid_stress;
    return scene.melt_flow && s.cools_after_solidification() &&
           !solid_uses_cooling_step &&
           after_path_and_below(time, scene.material.solidus);
  }

  template <int dim>
  void
  TimeStepPolicy<dim>::cool_solid_when_due(SolidSubCycle<dim> &solid,
                                           const double        time)
  {
    if (!solid_may_cool(time, solid.uses_cooling_step()))
      return;
    const std::string change = solid.use_cooling_step();
    if (!change.empty())
      out << "Solid: the melt has solidified after the laser's path "
             "(t = "
          << time << " s): " << change << std::endl;
  }

  template <int dim>
  typename IncompressibleFlow<dim>::SubcycleControl
  TimeStepPolicy<dim>::flow_subcycle(const SimulationControl &control) const
  {
    typename IncompressibleFlow<dim>::SubcycleControl c;
    c.max_substeps = run_limits().max_flow_substeps;
    c.wall_time    = [&control]() { return control.wall_time(); };
    c.log          = &out;
    return c;
  }

  template <int dim>
  std::function<bool()>
  TimeStepPolicy<dim>::flow_may_melt() const
  {
    if (!scene.heat_enabled)
      return {};
    return
      [this]() { return !(heat.max_temperature() < scene.material.solidus); };
  }

  template class TimeStepPolicy<2>;
  template class TimeStepPolicy<3>;
} // namespace femp
