// femp: the temperature coefficient dsigma/dT of the Marangoni traction,
// constant or from the surfactant model of Sahoo, DebRoy and McNallan,
// Metall. Trans. B 19 (1988) 483 (doc/flow.md, "Surface tension model").
// See include/femp/flow/surface_tension.h.
#include <femp/base/input_checks.h>
#include <femp/flow/surface_tension.h>

#include <cmath>

namespace femp
{
  namespace
  {
    constexpr double R_gas = 8.314462618; // J/(mol K)
  }                                       // namespace

  void
  SurfaceTension::add_model_parameter(ParameterTable &table, Model &model)
  {
    table.add("Surface tension model",
              model,
              {{Model::linear, "linear"}, {Model::surfactant, "surfactant"}},
              "dsigma/dT of the Marangoni stress (doc/flow.md, \"Surface "
              "tension model\"): 'linear' (default), the constant Surface "
              "tension temperature derivative; 'surfactant', the surface "
              "tension of a metal with a surface-active solute (Sahoo, "
              "DebRoy and McNallan 1988), sigma(T) = sigma_m - A (T - T_m) "
              "- R T Gamma_s ln(1 + k_l exp(-dH/(R T)) a_s), evaluated at "
              "each free-surface cell's temperature with the constants of "
              "the subsection Surfactant (the Surface tension temperature "
              "derivative is then not used). The capillary pressure keeps "
              "the constant Surface tension either way.");
  }

  void
  SurfaceTension::Surfactant::add_parameters(ParameterTable &table)
  {
    table.enter_subsection("Surfactant");
    table.add("Pure metal temperature derivative",
              pure_metal_gradient,
              Patterns::Double(),
              "A of the surfactant model: -dsigma/dT of the metal without "
              "the solute, N/(m K) (pure iron: 4.3e-4, Sahoo et al. 1988). "
              "Range [0, 1e-2].");
    table.add("Surface excess at saturation",
              surface_excess,
              Patterns::Double(),
              "Gamma_s of the surfactant model: the solute's surface "
              "excess at saturation, mol/m^2 (sulphur in iron: 1.3e-5, "
              "i.e. 1.3e-8 kmol/m^2, Sahoo et al. 1988). Range (0, 1e-3].");
    table.add("Entropy factor",
              entropy_factor,
              Patterns::Double(),
              "k_l of the surfactant model: the entropy factor of the "
              "solute's segregation to the surface, dimensionless (sulphur "
              "in iron: 3.18e-3, Sahoo et al. 1988). Range (0, 1e3].");
    table.add("Segregation enthalpy",
              segregation_enthalpy,
              Patterns::Double(),
              "dH of the surfactant model: the standard heat of adsorption "
              "of the solute, J/mol (sulphur in iron: -1.66e5, i.e. "
              "-1.66e8 J/kmol, Sahoo et al. 1988). Range [-1e6, 0).");
    table.add("Activity",
              activity,
              Patterns::Double(),
              "a_s of the surfactant model: the solute's activity in the "
              "melt, dimensionless (Henrian, 1 wt% standard state: about "
              "the solute's content in wt%); 0: no solute, dsigma/dT = -A. "
              "Range [0, 100].");
    table.leave_subsection();
  }

  void
  SurfaceTension::Surfactant::check() const
  {
    const std::string p = "Melt flow/Surfactant/";
    require(std::isfinite(pure_metal_gradient) && pure_metal_gradient >= 0 &&
              pure_metal_gradient <= 1e-2,
            p + "Pure metal temperature derivative",
            pure_metal_gradient,
            "it must lie in [0, 1e-2] N/(m K)");
    require(std::isfinite(surface_excess) && surface_excess > 0 &&
              surface_excess <= 1e-3,
            p + "Surface excess at saturation",
            surface_excess,
            "it must lie in (0, 1e-3] mol/m^2");
    require(std::isfinite(entropy_factor) && entropy_factor > 0 &&
              entropy_factor <= 1e3,
            p + "Entropy factor",
            entropy_factor,
            "it must lie in (0, 1e3]");
    require(std::isfinite(segregation_enthalpy) &&
              segregation_enthalpy >= -1e6 && segregation_enthalpy < 0,
            p + "Segregation enthalpy",
            segregation_enthalpy,
            "it must lie in [-1e6, 0) J/mol (the adsorption of a "
            "surface-active solute releases heat)");
    require(std::isfinite(activity) && activity >= 0 && activity <= 100,
            p + "Activity",
            activity,
            "it must lie in [0, 100]");
  }

  SurfaceTension::SurfaceTension(const Model       model,
                                 const double      linear_gradient,
                                 const Surfactant &surfactant)
      : model(model)
      , linear_gradient(linear_gradient)
      , s(surfactant)
  {
  }

  // dsigma/dT of sigma(T) = sigma_m - A (T - T_m) - R T Gamma_s ln(1 + K a_s)
  // with K = k_l exp(-dH/(R T)), K' = K dH/(R T^2):
  //   dsigma/dT = -A - R Gamma_s ln(1 + K a_s)
  //               - R T Gamma_s a_s K'/(1 + K a_s)
  //             = -A - R Gamma_s ln(1 + K a_s)
  //               - Gamma_s dH/T * K a_s/(1 + K a_s).
  // The last term is positive (dH < 0): the solute's desorption with rising
  // T raises sigma. K a_s/(1 + K a_s) is written 1/(1 + 1/(K a_s)), finite
  // for any K a_s > 0.
  double
  SurfaceTension::gradient(const double T) const
  {
    if (model == Model::linear)
      return linear_gradient;
    const double x = s.entropy_factor *
                     std::exp(-s.segregation_enthalpy / (R_gas * T)) *
                     s.activity;
    const double coverage = x > 0 ? 1. / (1. + 1. / x) : 0.;
    return -s.pure_metal_gradient - R_gas * s.surface_excess * std::log1p(x) -
           s.surface_excess * s.segregation_enthalpy / T * coverage;
  }

  double
  SurfaceTension::surfactant_tension(const double T) const
  {
    const double x = s.entropy_factor *
                     std::exp(-s.segregation_enthalpy / (R_gas * T)) *
                     s.activity;
    return -s.pure_metal_gradient * T -
           R_gas * T * s.surface_excess * std::log1p(x);
  }

  double
  SurfaceTension::difference(const double T0, const double T1) const
  {
    if (model == Model::linear)
      return linear_gradient * (T1 - T0);
    return surfactant_tension(T1) - surfactant_tension(T0);
  }
} // namespace femp
