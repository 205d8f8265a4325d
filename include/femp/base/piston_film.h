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
#include <femp/base/recoil_law.h>

namespace femp
{
  class PistonFilm
  {
  public:
    /// @p recoil: the recoil pressure p_r(T) that expels the melt (the
    /// flow's law, RecoilLaw); @p spot_radius: r_b, m (the melt leaves over
    /// the rim length r_b / 2); @p T_far: the temperature of the solid far
    /// ahead of the front, K.
    PistonFilm(const Material  &material,
               const RecoilLaw &recoil,
               double           spot_radius,
               double           T_far);

    /// At a surface temperature @p T_s (K): the film thickness @p delta (m)
    /// and the speed @p v_d (m/s) at which the front melts,
    /// delta = sqrt(k (T_s - T_l) r_b/2 / (u rho H)), u = sqrt(2 p_r / rho),
    /// v_d = k (T_s - T_l) / (delta rho H), H the enthalpy from T_far to the
    /// melt; both 0 when T_s is not above the liquidus or p_r(T_s) is not
    /// above zero (no recoil expels the melt).
    void
    film(double T_s, double &delta, double &v_d) const;

  private:
    const Material &mat;
    const RecoilLaw recoil;
    const double    rim_length, H_melt;
  };
} // namespace femp

#endif
