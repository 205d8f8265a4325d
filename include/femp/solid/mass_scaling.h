// femp: MassScalingController, the mass-scaling factor s of the solid and
// its adaptive controller (doc/speed_accuracy.md, section 3; no equation of
// the paper: the inertial masses of eqs. 10-16 are s times the true ones).
// With a fixed factor it only holds s. Adaptive: over each solid advance
// it integrates the kinetic energy of the steps; at the end the ratio of
// their mean to the stored elastic energy, K / U_el, measures how far from
// quasi-static the run is, and the factor moves so that the ratio
// approaches 'Solid/Max kinetic ratio': up by at most 2x per advance, down
// at once, rounded down to a power of 2^(1/4) so that round-off of the
// global sums cannot change it, within ['Min factor', 'Max factor']. A
// change at kept velocities changes the kinetic energy by (s_new / s_old -
// 1) K, booked as the kinetic jump so that the energy balance still closes.
#ifndef femp_mass_scaling_h
#define femp_mass_scaling_h

#include <array>

namespace femp
{
  class MassScalingController
  {
  public:
    /// What a checkpoint must keep besides the current phase's integral.
    struct State
    {
      double factor = 1; ///< current s
      /// Ratio K / U_el measured at the end of the last solid advance
      /// (mean kinetic energy of its steps over the stored elastic energy).
      double last_ratio = 0;
      /// Kinetic energy booked for the changes of s so far, J (2D: J/m).
      double kinetic_jump = 0;
    };

    /// Starting factor @p factor; the adaptive rule's target ratio
    /// @p max_kinetic_ratio and range [@p min_factor, @p max_factor].
    MassScalingController(const double factor            = 1,
                          const double max_kinetic_ratio = 1e-3,
                          const double min_factor        = 1,
                          const double max_factor        = 1e4);

    /// Back to the starting factor and range, nothing measured or booked.
    void
    reset();
    /// Limit the adaptive rule to [@p min_factor, @p max_factor] from now
    /// on (the factor itself is not changed).
    void
    set_range(const double min_factor, const double max_factor)
    {
      min_s = min_factor;
      max_s = max_factor;
    }
    double
    factor() const
    {
      return s.factor;
    }
    const State &
    state() const
    {
      return s;
    }
    /// One solid step of length @p dt that ended with kinetic energy @p K.
    void
    add_step(const double K, const double dt)
    {
      phase_K_dt += K * dt;
      phase_time += dt;
    }
    /// End of a solid advance: the ratio of the mean kinetic energy of its
    /// steps (@p K, the kinetic energy now, without steps) to the stored
    /// elastic energy @p u (both global); a new phase starts.
    void
    measure(const double u, const double K);
    /// The factor the adaptive rule asks for after measure() (the current
    /// one when it holds).
    double
    target() const;
    /// Change the factor to @p s_new at kinetic energy @p K (kept
    /// velocities): books the jump; returns s_new / s_old.
    double
    change_to(const double s_new, const double K);
    /// Checkpoint: factor, last ratio, kinetic jump, and the current
    /// phase's integral of K and its length.
    std::array<double, 5>
    saved_values() const;
    void
    restore(const std::array<double, 5> &values);

  private:
    State  s;
    double start, max_ratio, min_s, max_s, start_min_s, start_max_s;
    /// Integral of K over the solid steps of the current advance and its
    /// length, J s and s.
    double phase_K_dt = 0, phase_time = 0;
  };
} // namespace femp

#endif
