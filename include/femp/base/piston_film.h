// femp: the film of melt between a boiling surface and the melting front,
// from the piston of Semak and Matsunawa (J. Phys. D 30 (1997) 2541): the
// melt leaves the spot's rim at the recoil's Bernoulli speed (mass) while
// the film conducts the flux that melts the front (energy). Used by the
// heat's front-wall piston and the flow's front-wall expulsion
// (doc/equations.md, "Front wall piston"; doc/flow.md, "Front wall
// expulsion").
#ifndef femp_base_piston_film_h
#define femp_base_piston_film_h

#include <femp/base/material.h>

namespace femp
{
  class PistonFilm
  {
  public:
    /// @p recoil_coefficient: zeta_p of the recoil pressure
    /// zeta_p p_0 exp[L_v M (T - T_v)/(R T T_v)]; @p spot_radius: r_b, m
    /// (the melt leaves over the rim length r_b / 2); @p T_far: the
    /// temperature of the solid far ahead of the front, K.
    PistonFilm(const Material &material,
               double          recoil_coefficient,
               double          spot_radius,
               double          T_far);

    /// At a surface temperature @p T_s (K): the film thickness @p delta (m)
    /// and the speed @p v_d (m/s) at which the front melts,
    /// delta = sqrt(k (T_s - T_l) r_b/2 / (u rho H)), u = sqrt(2 p_r / rho),
    /// v_d = k (T_s - T_l) / (delta rho H), H the enthalpy from T_far to the
    /// melt; both 0 when T_s is not above the liquidus.
    void
    film(double T_s, double &delta, double &v_d) const;

  private:
    const Material &mat;
    const double    zeta_p, rim_length, H_melt;
  };
} // namespace femp

#endif
