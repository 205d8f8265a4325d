// femp: the temperature coefficient dsigma/dT of the surface tension, which
// drives the Marangoni traction of the free surface (paper eq. 3; doc/flow.md,
// "Surface tension model"). Two models (Melt flow/Surface tension model):
//  - linear: one constant dsigma/dT (Melt flow/Surface tension temperature
//    derivative);
//  - surfactant: the surface tension of a metal with a surface-active solute
//    (sulphur in steel) after Sahoo, DebRoy and McNallan, Metall. Trans. B
//    19 (1988) 483, eq. for sigma(T):
//      sigma(T) = sigma_m - A (T - T_m) - R T Gamma_s ln(1 + K a_s),
//      K(T)     = k_l exp(-dH/(R T)),
//    whose derivative (K' = K dH/(R T^2))
//      dsigma/dT = -A - R Gamma_s ln(1 + K a_s)
//                  - Gamma_s dH K a_s / (T (1 + K a_s))
//    is positive where the solute covers the surface (low T) and turns
//    negative above the temperature where it desorbs.
// The capillary pressure keeps the constant Melt flow/Surface tension.
#ifndef femp_surface_tension_h
#define femp_surface_tension_h

#include <femp/base/parameter_table.h>

namespace femp
{
  class SurfaceTension
  {
  public:
    enum class Model
    {
      linear,    ///< one constant dsigma/dT
      surfactant ///< Sahoo et al. 1988
    };

    /// The constants of the surfactant model (Melt flow/Surfactant), SI
    /// units with amounts in mol. Defaults: Sahoo et al.'s Fe-S system
    /// (A, Gamma_s, k_l, dH), no solute (a_s = 0).
    struct Surfactant
    {
      double pure_metal_gradient  = 4.3e-4;  ///< A, N/(m K): -dsigma/dT, a_s=0
      double surface_excess       = 1.3e-5;  ///< Gamma_s, mol/m^2
      double entropy_factor       = 3.18e-3; ///< k_l, dimensionless
      double segregation_enthalpy = -1.66e5; ///< dH, J/mol (< 0)
      double activity             = 0;       ///< a_s, dimensionless (wt%)

      /// Declare or read the entries of the subsection Surfactant (the
      /// caller has entered Melt flow).
      void
      add_parameters(ParameterTable &table);
      /// Refuse (InputError naming Melt flow/Surfactant/<entry>, the value
      /// and the range) a constant outside its range.
      void
      check() const;
    };

    /// Declare or read Melt flow/Surface tension model into @p model.
    static void
    add_model_parameter(ParameterTable &table, Model &model);

    /// The law of @p model; @p linear_gradient is the constant dsigma/dT of
    /// the linear model, N/(m K).
    SurfaceTension(const Model       model,
                   const double      linear_gradient,
                   const Surfactant &surfactant);

    /// dsigma/dT at the temperature @p T (K, > 0), N/(m K).
    double
    gradient(const double T) const;

    /// sigma(T1) - sigma(T0), N/m (temperatures in K, > 0).
    double
    difference(const double T0, const double T1) const;

    /// Whether the Marangoni stress is on: the surfactant model, or a
    /// non-zero linear coefficient.
    bool
    marangoni() const
    {
      return model == Model::surfactant || linear_gradient != 0;
    }

  private:
    /// sigma(T) - sigma_m - A T_m of the surfactant model, N/m.
    double
    surfactant_tension(const double T) const;

    Model      model;
    double     linear_gradient;
    Surfactant s;
  };
} // namespace femp

#endif
