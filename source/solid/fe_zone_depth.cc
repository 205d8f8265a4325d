// femp: conservative melt-depth estimate for the automatic finite-element
// zone (Rosenthal's moving point source and its line-source limit); see
// fe_zone_depth.h for the formulas and the margin.
#include <femp/solid/fe_zone_depth.h>

#include <algorithm>
#include <cmath>

namespace femp
{
  namespace
  {
    /// Largest temperature rise at depth z over all positions xi <= 0
    /// behind the source (ahead of it, the same R is colder).
    double
    peak_rise_at_depth(const double z,
                       const double Q,
                       const double v,
                       const double k,
                       const double a)
    {
      auto rise = [&](const double s) {
        const double R = std::sqrt(s * s + z * z);
        // R - s = z^2 / (R + s): no cancellation far behind the source.
        return Q / (2 * M_PI * k * R) *
               std::exp(-v * z * z / ((R + s) * 2 * a));
      };
      // The far-field maximum lies at s = v z^2 / (4 a); scan s on a
      // logarithmic grid well past it and well below z, then refine.
      const double s_hi = 100 * std::max(z, v * z * z / (4 * a));
      const double s_lo = 1e-4 * z;
      const int    n    = 400;
      double       best = rise(0.), s_best = 0.;
      for (int i = 0; i <= n; ++i)
        {
          const double s = s_lo * std::pow(s_hi / s_lo, double(i) / n);
          const double r = rise(s);
          if (r > best)
            best = r, s_best = s;
        }
      // Golden-section refinement in [s_best / q, s_best * q].
      const double q = std::pow(s_hi / s_lo, 1. / n);
      double lo = s_best > 0 ? s_best / q : 0., hi = std::max(s_best * q, s_lo);
      const double g = 0.5 * (std::sqrt(5.) - 1);
      for (int it = 0; it < 60; ++it)
        {
          const double m1 = hi - g * (hi - lo), m2 = lo + g * (hi - lo);
          if (rise(m1) > rise(m2))
            hi = m2;
          else
            lo = m1;
        }
      return std::max(best, rise(0.5 * (lo + hi)));
    }
  } // namespace

  double
  rosenthal_melt_depth(const double Q,
                       const double v,
                       const double k,
                       const double rho_c,
                       const double dT)
  {
    if (Q <= 0 || dT <= 0)
      return 0.;
    const double a = k / rho_c;
    // Bracket: the rise falls with z; double until below dT.
    double lo = 0.,
           hi = std::max(1e-9, line_source_melt_depth(Q, v, rho_c, dT));
    while (peak_rise_at_depth(hi, Q, v, k, a) >= dT)
      lo = hi, hi *= 2;
    for (int it = 0; it < 60; ++it)
      {
        const double z                                      = 0.5 * (lo + hi);
        (peak_rise_at_depth(z, Q, v, k, a) >= dT ? lo : hi) = z;
      }
    return lo;
  }

  double
  line_source_melt_depth(const double Q,
                         const double v,
                         const double rho_c,
                         const double dT)
  {
    if (Q <= 0 || dT <= 0)
      return 0.;
    return std::sqrt(2 * Q / (M_PI * std::exp(1.) * rho_c * v * dT));
  }

  double
  conservative_melt_depth(const Material &m,
                          const double    Q,
                          const double    v,
                          const double    T0)
  {
    const double rho_c = m.density * m.specific_heat.min_value();
    const double dT    = m.solidus - T0;
    double       d     = line_source_melt_depth(Q, v, rho_c, dT);
    for (const double k :
         {m.conductivity.min_value(), m.conductivity.max_value()})
      d = std::max(d, rosenthal_melt_depth(Q, v, k, rho_c, dT));
    return d;
  }

  double
  automatic_fe_zone_top(const double d,
                        const double substrate_top,
                        const double z0,
                        const double h)
  {
    const double top =
      substrate_top - (FeZoneMargin::factor * d + FeZoneMargin::cells * h);
    return z0 + std::floor((top - z0) / h + 1e-9) * h;
  }
} // namespace femp
