// femp: the thermo-elasto-plastic constitutive model of the solid (paper
// eq. 5, METHOD sec. 4), shared by the material points (SolidMPM) and the
// finite elements (SolidFEM).
//
// Hypoelastic-plastic, rate form, one explicit increment per solid step:
//   D = sym(L), W = skew(L)             (L: velocity gradient)
//   D_e = D - D_p - alpha dT/dt I       (thermal strain rate beta T', with
//                                        beta = 3 kappa alpha, i.e. the
//                                        thermal stress modulus)
//   sigma^Jaumann = C(T) : D_e
// Objective update: sigma* = R sigma R^T with the Hughes-Winget rotation
// R = (I - W dt/2)^-1 (I + W dt/2) (exactly orthogonal, so a rigid rotation
// leaves the invariants unchanged), then the elastic predictor with the
// moduli at the new temperature, then J2 radial return with linear
// isotropic hardening:
//   f = q - (sigma_y(T) + H(T) eps_p),  q = sqrt(3/2 s:s),
//   d_gamma = f / (3 mu + H),  s <- s (1 - 3 mu d_gamma / q_trial).
// Young's modulus E(T), plastic (hardening) modulus H(T) = d sigma_y/d eps_p
// and the initial yield stress sigma_y(T) are piecewise-linear temperature
// tables. A point at or above the solidus carries no stress and no plastic
// strain (melted); when it solidifies it therefore starts stress-free.
//
// Stresses are always 3x3 (in 2D: plane strain, the out-of-plane stress
// sigma_zz is carried as a state variable). Only deal.II tensors are used,
// so this header stays light.
#ifndef femp_constitutive_h
#define femp_constitutive_h

#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/symmetric_tensor.h>
#include <deal.II/base/tensor.h>

#include <femp/input_checks.h>

namespace femp
{
  using namespace dealii;

  struct SolidMaterial
  {
    PiecewiseLinear youngs_modulus{1.93e11}; ///< E(T), Pa
    PiecewiseLinear plastic_modulus{1e9};    ///< H(T), Pa
    PiecewiseLinear yield_stress{2.5e8};     ///< sigma_y(T), Pa
    double          poisson_ratio = 0.3;     ///< nu, -
    double          expansion     = 1.7e-5;  ///< alpha, 1/K (linear)
    double          density       = 7955.;   ///< rho, kg/m^3 (from Material)
    double          melt_temperature = 1670.; ///< solidus, K (from Material)
    /// Linear artificial bulk viscosity b1 (numerical, -): a viscous
    /// pressure q = b1 rho c h tr(D) added to the stress in the force
    /// computation (not stored), which damps the ringing behind stress
    /// fronts of the explicit scheme (von Neumann-Richtmyer, linear term).
    double          bulk_viscosity = 0.1;

    /// Declares the entries of subsection "Solid/Material".
    static void
    declare_parameters(ParameterHandler &prm);
    /// Reads subsection "Solid/Material"; density and solidus are taken from
    /// the thermal material by the caller.
    void
    parse_parameters(ParameterHandler &prm);

    /// Largest P-wave modulus M = E (1-nu) / ((1+nu)(1-2nu)) of the table, Pa.
    double
    max_p_wave_modulus() const;
    /// P-wave modulus at temperature @p T, Pa.
    double
    p_wave_modulus(const double T) const
    {
      const double nu = poisson_ratio;
      return youngs_modulus.value(T) * (1 - nu) / ((1 + nu) * (1 - 2 * nu));
    }
  };

  /// Stress state of one material point or one Gauss point.
  struct StressPoint
  {
    SymmetricTensor<2, 3> sigma;      ///< Cauchy stress, Pa
    double                eps_p = 0.; ///< equivalent plastic strain, -
  };

  /// Result of one increment, for the energy bookkeeping.
  struct StressIncrement
  {
    bool   yielded = false;
    double plastic_increment = 0.; ///< d_gamma
  };

  /// Advance @p state over one step: @p L_dt is the velocity gradient times
  /// the step (3x3; zero third row and column in 2D, plane strain),
  /// @p T_old and @p T_new the temperatures at the start and end of the step.
  StressIncrement
  update_stress(const SolidMaterial &m,
                const Tensor<2, 3> & L_dt,
                const double         T_old,
                const double         T_new,
                StressPoint &        state);

  /// von Mises equivalent stress q = sqrt(3/2 s:s), Pa.
  inline double
  von_mises(const SymmetricTensor<2, 3> &s)
  {
    const SymmetricTensor<2, 3> d = deviator(s);
    return std::sqrt(1.5 * (d * d));
  }
} // namespace femp

#endif
