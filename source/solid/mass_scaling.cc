// femp: the solid's mass-scaling factor and its adaptive controller (see
// mass_scaling.h).
#include <femp/solid/mass_scaling.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace femp
{
  MassScalingController::MassScalingController(const double factor,
                                               const double max_kinetic_ratio,
                                               const double min_factor,
                                               const double max_factor)
      : start(factor)
      , max_ratio(max_kinetic_ratio)
      , min_s(min_factor)
      , max_s(max_factor)
      , start_min_s(min_factor)
      , start_max_s(max_factor)
  {
    s.factor = factor;
  }

  void
  MassScalingController::reset()
  {
    s          = State();
    s.factor   = start;
    min_s      = start_min_s;
    max_s      = start_max_s;
    phase_K_dt = phase_time = 0;
  }

  void
  MassScalingController::measure(const double u, const double K)
  {
    // The quasi-static gauge (doc/speed_accuracy.md, sections 1 and 3):
    // the mean kinetic energy of the advance's steps over the elastic
    // energy stored at its end.
    const double k_mean = phase_time > 0 ? phase_K_dt / phase_time : K;
    s.last_ratio =
      u > 0 ? k_mean / u :
              (k_mean > 0 ? std::numeric_limits<double>::infinity() : 0.);
    phase_K_dt = phase_time = 0;
  }

  double
  MassScalingController::target() const
  {
    // Quasi-static motion is kinematic (thermal expansion), K ~ s: the
    // factor that brings the ratio to r_max is s r_max / r. Up by at most
    // x2 per temperature step, down at once; rounded down to a power of
    // 2^(1/4), so that round-off of the global sums (rank count) cannot
    // change the factor and the factor holds while r lies in
    // (2^(-1/4) r_max, r_max].
    const double f = s.factor, r = s.last_ratio;
    double       target = r > 0 ? f * max_ratio / r : 2 * f;
    target              = std::min(target, 2 * f);
    if (target > 0)
      target = std::exp2(std::floor(4 * std::log2(target) + 1e-9) / 4);
    return std::max(min_s, std::min(max_s, target));
  }

  double
  MassScalingController::change_to(const double s_new, const double K)
  {
    const double r = s_new / s.factor;
    s.kinetic_jump += (r - 1) * K;
    s.factor = s_new;
    return r;
  }

  std::array<double, 5>
  MassScalingController::saved_values() const
  {
    return {{s.factor, s.last_ratio, s.kinetic_jump, phase_K_dt, phase_time}};
  }

  void
  MassScalingController::restore(const std::array<double, 5> &values)
  {
    s.factor       = values[0];
    s.last_ratio   = values[1];
    s.kinetic_jump = values[2];
    phase_K_dt     = values[3];
    phase_time     = values[4];
  }
} // namespace femp
