// femp: thermophysical material data (eq. 1 coefficients), parameters and
// their validation.
#include <femp/base/material.h>
#include <femp/base/parameter_table.h>

namespace femp
{
  void
  Material::add_parameters(ParameterTable &table)
  {
    ParameterHandler &prm = table.handler();
    table.enter_subsection("Material");
    table.add("Density",
              density,
              Patterns::Double(),
              "Metal density rho_m, kg/m^3; range (0, inf). Default: "
              "316L stainless steel (Kim 1975).");
    if (table.declaring())
      prm.declare_entry(
        "Specific heat",
        "300:499.2, 1670:681.2, 1730:770.4",
        Patterns::Anything(),
        "Metal specific heat c_m(T), J/(kg K), > 0: a number, or "
        "'T1:c1, T2:c2, ...' piecewise linear in T (K), held "
        "constant outside. Default: 316L (Kim 1975, type 316: "
        "459.3 + 0.1329 T solid, 300-1670 K; 770.4 liquid).");
    if (table.declaring())
      prm.declare_entry(
        "Thermal conductivity",
        "300:13.96, 1670:35.48, 1730:18.08, 3000:22.25",
        Patterns::Anything(),
        "Metal thermal conductivity lambda_m(T), W/(m K), > 0: "
        "a number or a 'T:value' table as for the specific heat. "
        "Default: 316L (Kim 1975, type 316: 9.248 + 0.01571 T "
        "solid, 300-1670 K; 12.41 + 0.003279 T liquid, "
        "1730-3000 K).");
    table.add("Solidus temperature",
              solidus,
              Patterns::Double(),
              "Solidus T_s, K; range (0, liquidus).");
    table.add("Liquidus temperature",
              liquidus,
              Patterns::Double(),
              "Liquidus T_l, K; range (solidus, inf). The liquid "
              "fraction rises linearly from T_s to T_l.");
    table.add("Latent heat of fusion",
              latent_heat_fusion,
              Patterns::Double(),
              "L_m, J/kg; range [0, inf).");
    table.add("Latent heat of evaporation",
              latent_heat_evaporation,
              Patterns::Double(0.),
              "L_v of the surface loss of eq. (1) and of the recoil "
              "pressure, J/kg; range [0, inf).");
    table.add(
      "Evaporation temperature",
      evaporation_temperature,
      Patterns::Double(0.),
      "Boiling temperature T_v at the ambient pressure, K; range (0, inf).");
    table.add("Molar mass",
              molar_mass,
              Patterns::Double(0.),
              "Molar mass M of the metal vapour, kg/mol; range (0, inf).");
    table.add("Ambient pressure",
              ambient_pressure,
              Patterns::Double(0.),
              "Ambient pressure p_0, Pa; range [0, inf).");
    table.add("Gas density",
              gas_density,
              Patterns::Double(),
              "Ambient gas density rho_g, kg/m^3; range [0, inf). "
              "Enters partially filled cells and the surface weighting "
              "2 rho c/(rho_m c_m + rho_g c_g) of eq. (1).");
    table.add("Gas specific heat",
              gas_specific_heat,
              Patterns::Double(),
              "Ambient gas specific heat c_g, J/(kg K); range [0, inf).");
    table.add("Gas thermal conductivity",
              gas_conductivity,
              Patterns::Double(),
              "Ambient gas conductivity lambda_g, W/(m K): the gas "
              "share of a partly filled cell's conductivity and the "
              "conduction from detached drops (Heat transfer/"
              "Detached drops); range [0, inf). Cells without metal "
              "are not solved.");
    table.leave_subsection();
  }

  void
  Material::declare_parameters(ParameterHandler &prm)
  {
    Material       defaults;
    ParameterTable table(prm, ParameterTable::Mode::declare);
    defaults.add_parameters(table);
  }

  void
  Material::parse_parameters(ParameterHandler &prm)
  {
    ParameterTable table(prm, ParameterTable::Mode::parse);
    add_parameters(table);
    prm.enter_subsection("Material");
    specific_heat = PiecewiseLinear::parse(prm.get("Specific heat"),
                                           "Material/Specific heat");
    conductivity  = PiecewiseLinear::parse(prm.get("Thermal conductivity"),
                                          "Material/Thermal conductivity");
    prm.leave_subsection();
    require(evaporation_temperature > 0,
            "Material/Evaporation temperature",
            evaporation_temperature,
            "it must be positive (K)");
    require(molar_mass > 0,
            "Material/Molar mass",
            molar_mass,
            "it must be positive (kg/mol)");

    require(density > 0,
            "Material/Density",
            density,
            "it must be positive (kg/m^3)");
    require(specific_heat.min_value() > 0,
            "Material/Specific heat",
            specific_heat.min_value(),
            "every specific heat must be positive (J/(kg K))");
    require(conductivity.min_value() > 0,
            "Material/Thermal conductivity",
            conductivity.min_value(),
            "every conductivity must be positive (W/(m K))");
    require(solidus > 0,
            "Material/Solidus temperature",
            solidus,
            "it must be positive (K)");
    require(liquidus > solidus,
            "Material/Liquidus temperature",
            liquidus,
            "it must exceed the solidus temperature " + num(solidus) + " K");
    require(latent_heat_fusion >= 0,
            "Material/Latent heat of fusion",
            latent_heat_fusion,
            "it must be non-negative (J/kg)");
    require(gas_density >= 0,
            "Material/Gas density",
            gas_density,
            "it must be non-negative");
    require(gas_specific_heat >= 0,
            "Material/Gas specific heat",
            gas_specific_heat,
            "it must be non-negative");
    require(gas_conductivity >= 0,
            "Material/Gas thermal conductivity",
            gas_conductivity,
            "it must be non-negative");
  }
} // namespace femp
