// femp: thermophysical material data of the metal and the ambient gas,
// used by eq. (1): density, temperature tables of specific heat and
// conductivity, solidus/liquidus, latent heats, the evaporation data
// (also read by the recoil pressure of the flow) and the liquid fraction
// gamma = clamp((T - T_s)/(T_l - T_s), 0, 1) of doc/method.md, "Zones and
// discretizations".
#ifndef femp_material_h
#define femp_material_h

#include <deal.II/base/parameter_handler.h>

#include <femp/base/input_checks.h>
#include <femp/base/parameter_table.h>

#include <algorithm>

namespace femp
{
  using namespace dealii;

  struct Material
  {
    double          density = 7955.;             ///< rho_m, kg/m^3
    PiecewiseLinear specific_heat{500.};         ///< c_m(T), J/(kg K)
    PiecewiseLinear conductivity{20.};           ///< lambda_m(T), W/(m K)
    double          solidus            = 1670.;  ///< T_s, K
    double          liquidus           = 1730.;  ///< T_l, K
    double          latent_heat_fusion = 2.68e5; ///< L_m, J/kg
    double          gas_density        = 1.6;    ///< rho_g, kg/m^3
    double          gas_specific_heat  = 520.;   ///< c_g, J/(kg K)
    double          gas_conductivity   = 0.018;  ///< lambda_g, W/(m K)
    // Evaporation: the surface loss of eq. (1) (HeatTransfer) and the
    // recoil pressure (FreeSurface) read these.
    double latent_heat_evaporation = 7.41e6;  ///< L_v, J/kg
    double evaporation_temperature = 3090.;   ///< T_v at p_0, K
    double molar_mass              = 0.0558;  ///< M of the vapour, kg/mol
    double ambient_pressure        = 101325.; ///< p_0, Pa

    /// Declare (the members' values are the defaults) or read the

    /// entries, each listed once.

    void

    add_parameters(ParameterTable &table);

    static void
    declare_parameters(ParameterHandler &prm);
    void
    parse_parameters(ParameterHandler &prm);

    double
    liquid_fraction(const double T) const
    {
      return std::clamp((T - solidus) / (liquidus - solidus), 0., 1.);
    }
  };
} // namespace femp

#endif
