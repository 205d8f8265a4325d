// femp: the recoil pressure of an evaporating metal surface (paper eq. 3;
// doc/flow.md, "Recoil pressure"), the one law that the flow's free-surface
// pressure, its front-wall film and expulsion, and the heat's front-wall
// piston all take: zeta_p p_sat(T) with the saturation pressure
// p_sat(T) = p0 exp[L_v M (T - T_v)/(R T T_v)] (Clausius-Clapeyron,
// the evaporation data of Material), or with Melt flow/Recoil above
// ambient its part above the ambient pressure p0 that the gas exerts on
// the whole surface, max(0, zeta_p p_sat(T) - p0).
#ifndef femp_base_recoil_law_h
#define femp_base_recoil_law_h

#include <femp/base/material.h>

namespace femp
{
  class RecoilLaw
  {
  public:
    /// @p coefficient: zeta_p (0: no recoil); @p above_ambient: the part
    /// above the ambient pressure p0 (Melt flow/Recoil above ambient).
    RecoilLaw(const Material &material, double coefficient, bool above_ambient);

    /// The recoil pressure at the surface temperature @p T (K), Pa; 0 for
    /// T <= 0 or zeta_p = 0.
    double
    pressure(double T) const;

    /// pressure() at the evaporation temperature T_v, where p_sat = p0:
    /// zeta_p p0, or max(0, zeta_p p0 - p0) above the ambient. A surface
    /// whose recoil exceeds it boils.
    double
    at_evaporation_temperature() const;

    double
    coefficient() const
    {
      return zeta_p;
    }

    bool
    above_ambient() const
    {
      return net;
    }

  private:
    double zeta_p, p0, Tv, exponent;
    bool   net;
  };
} // namespace femp

#endif
