// femp: where the finite-element zone may end (paper sec. 2.1: the FE zone
// is the part of the substrate that stays solid all along). Two tools:
//
// 1. A conservative estimate of the melt depth under a moving laser, used by
//    'Solid FEM/Zone upper corner = auto'. Rosenthal's moving point source on
//    a semi-infinite body with constant properties,
//      T - T0 = Q / (2 pi k R) exp(-v (R + xi) / (2 a)),
//      R = sqrt(xi^2 + z^2),  a = k / (rho c),  xi = x - v t,
//    with Q = absorptivity x power. The melt depth d is the largest depth z at
//    which max over xi of T reaches the solidus T_s; found numerically
//    (bisection in z, a dense logarithmic scan in xi <= 0). Far behind the
//    source this maximum tends to the line-source value
//      T - T0 = 2 Q / (pi e rho c v z^2),
//    i.e.  d_line = sqrt(2 Q / (pi e rho c v (T_s - T0))),
//    the high-Peclet limit (Eagar-Tsai / Christensen scaling), so that
//    d >= d_line always. Conservative choices: the powder layer, the latent
//    heat and the beam's spread are ignored (a Gaussian beam's peak at a depth
//    z is the sum of point-source peaks at distances >= z, so it cannot melt
//    deeper than the point source), the heat capacity is the smallest of the
//    c(T) table, and d is the larger of the values with the smallest and the
//    largest conductivity of the k(T) table. The depth is measured from the
//    substrate top (the powder above only adds distance). The zone's top is
//    then
//      z_top = substrate top - (1.1 d + 2 h),
//    rounded down to a grid line (h: cell size): a 10 % and two-cell margin.
//    Melt flow (Marangoni convection with dsigma/dT < 0 widens and flattens
//    the pool) and recoil (deepens it; keyholes are outside this estimate)
//    are not in the formula: the guard below catches what it misses.
//
// 2. The guard: a finite element at or above the solidus means the zone was
//    placed too high. SolidSubCycle checks it at every temperature step and
//    stops the run with FeZoneMelted's message (position, time, depth to
//    use).
#ifndef femp_fe_zone_depth_h
#define femp_fe_zone_depth_h

#include <femp/base/material.h>

#include <stdexcept>
#include <string>

namespace femp
{
  /// Rosenthal point-source melt depth (m) for absorbed power @p Q (W), speed
  /// @p v (m/s), conductivity @p k (W/(m K)), volumetric heat capacity
  /// @p rho_c (J/(m^3 K)) and temperature rise @p dT = T_s - T0 (K).
  double
  rosenthal_melt_depth(const double Q,
                       const double v,
                       const double k,
                       const double rho_c,
                       const double dT);

  /// High-Peclet (line-source) limit sqrt(2 Q / (pi e rho c v dT)), m.
  double
  line_source_melt_depth(const double Q,
                         const double v,
                         const double rho_c,
                         const double dT);

  /// The conservative melt depth of point 1 of the header comment for the
  /// material @p m, absorbed power @p Q (W), speed @p v (m/s) and initial
  /// temperature @p T0 (K), m.
  double
  conservative_melt_depth(const Material &m,
                          const double    Q,
                          const double    v,
                          const double    T0);

  /// Margin of the automatic zone: z_top = z_substrate - (factor d + cells h).
  struct FeZoneMargin
  {
    static constexpr double factor = 1.1;
    static constexpr double cells  = 2.;
  };

  /// Top of the FE zone for a melt depth @p d below @p substrate_top on a
  /// grid with lower z @p z0 and cell size @p h: substrate_top - (1.1 d +
  /// 2 h) rounded down to a grid line, m.
  double
  automatic_fe_zone_top(const double d,
                        const double substrate_top,
                        const double z0,
                        const double h);

  /// Thrown (on every rank) when a finite element reached the solidus.
  class FeZoneMelted : public std::runtime_error
  {
  public:
    using std::runtime_error::runtime_error;
  };
} // namespace femp

#endif
