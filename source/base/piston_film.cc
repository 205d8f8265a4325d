// femp: the film of Semak and Matsunawa's piston (piston_film.h).
#include <femp/base/piston_film.h>

#include <algorithm>
#include <cmath>

namespace femp
{
  PistonFilm::PistonFilm(const Material  &material,
                         const RecoilLaw &recoil,
                         const double     spot_radius,
                         const double     T_far)
      : mat(material)
      , recoil(recoil)
      , rim_length(spot_radius / 2)
      , H_melt(material.specific_heat.antiderivative(material.liquidus) -
               material.specific_heat.antiderivative(
                 std::min(T_far, material.liquidus)) +
               material.latent_heat_fusion)
  {
  }

  void
  PistonFilm::film(const double T_s, double &delta, double &v_d) const
  {
    delta = v_d     = 0;
    const double dT = T_s - mat.liquidus;
    if (!(dT > 0) || !(H_melt > 0))
      return;
    const double p_r = recoil.pressure(T_s);
    if (!(p_r > 0))
      return;
    const double u  = std::sqrt(2 * p_r / mat.density);
    const double k  = mat.conductivity.value(0.5 * (T_s + mat.liquidus));
    const double rH = mat.density * H_melt;
    delta           = std::sqrt(k * dT * rim_length / (u * rH));
    v_d             = k * dT / (delta * rH);
  }
} // namespace femp
