// femp: the recoil pressure of an evaporating surface (recoil_law.h).
#include <femp/base/recoil_law.h>

#include <algorithm>
#include <cmath>

namespace femp
{
  namespace
  {
    constexpr double gas_constant = 8.314462618; // J/(mol K)
  }

  RecoilLaw::RecoilLaw(const Material &material,
                       const double    coefficient,
                       const bool      above_ambient)
      : zeta_p(coefficient)
      , p0(material.ambient_pressure)
      , Tv(material.evaporation_temperature)
      , exponent(material.latent_heat_evaporation * material.molar_mass /
                 (gas_constant * material.evaporation_temperature))
      , net(above_ambient)
  {
  }

  double
  RecoilLaw::pressure(const double T) const
  {
    if (zeta_p == 0 || !(T > 0))
      return 0.;
    const double p = zeta_p * p0 * std::exp(exponent * (T - Tv) / T);
    return net ? std::max(0., p - p0) : p;
  }

  double
  RecoilLaw::at_evaporation_temperature() const
  {
    return pressure(Tv);
  }
} // namespace femp
