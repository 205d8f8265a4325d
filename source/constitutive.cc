// femp: thermo-elasto-plastic stress update (paper eq. 5): Jaumann rate by
// the Hughes-Winget rotation, thermal strain, J2 radial return with linear
// isotropic hardening, temperature tables for E, H and sigma_y.
#include <femp/constitutive.h>

#include <cmath>

namespace femp
{
  void
  SolidMaterial::declare_parameters(ParameterHandler &prm)
  {
    prm.enter_subsection("Solid");
    prm.declare_entry("Bulk viscosity", "0.1", Patterns::Double(),
                      "Linear artificial bulk viscosity b1, -: the viscous "
                      "pressure q = b1 rho c h tr(D) (c: P-wave speed, h: cell "
                      "size) is added to the stress in the nodal forces and "
                      "damps the ringing behind stress fronts; the stable step "
                      "shrinks by sqrt(1 + b1^2) - b1. Range [0, 1]; 0 is off.");
    prm.enter_subsection("Material");
    prm.declare_entry("Young's modulus", "1.93e11", Patterns::Anything(),
                      "E(T), Pa: a constant or a table 'T1:E1, T2:E2, ...' "
                      "(K : Pa, T increasing, held constant outside). Every "
                      "value must be positive.");
    prm.declare_entry("Plastic modulus", "1e9", Patterns::Anything(),
                      "Linear isotropic hardening modulus H(T) = d sigma_y / "
                      "d eps_p, Pa: a constant or a table as for Young's "
                      "modulus. Range [0, inf).");
    prm.declare_entry("Yield stress", "2.5e8", Patterns::Anything(),
                      "Initial yield stress sigma_y(T), Pa: a constant or a "
                      "table as for Young's modulus. Range (0, inf); use a "
                      "huge value for a purely elastic solid.");
    prm.declare_entry("Poisson's ratio", "0.3", Patterns::Double(),
                      "nu, -; range [0, 0.5).");
    prm.declare_entry("Thermal expansion coefficient", "1.7e-5",
                      Patterns::Double(),
                      "Linear thermal expansion alpha, 1/K; range [0, inf). "
                      "The thermal stress modulus is beta = E alpha / (1 - 2 "
                      "nu); in a bar in uniaxial strain with nu = 0, beta = E "
                      "alpha.");
    prm.leave_subsection();
    prm.leave_subsection();
  }


  void
  SolidMaterial::parse_parameters(ParameterHandler &prm)
  {
    prm.enter_subsection("Solid");
    bulk_viscosity = prm.get_double("Bulk viscosity");
    prm.enter_subsection("Material");
    const std::string p = "Solid/Material/";
    youngs_modulus =
      PiecewiseLinear::parse(prm.get("Young's modulus"), p + "Young's modulus");
    plastic_modulus =
      PiecewiseLinear::parse(prm.get("Plastic modulus"), p + "Plastic modulus");
    yield_stress =
      PiecewiseLinear::parse(prm.get("Yield stress"), p + "Yield stress");
    poisson_ratio = prm.get_double("Poisson's ratio");
    expansion     = prm.get_double("Thermal expansion coefficient");
    prm.leave_subsection();
    prm.leave_subsection();
    require(youngs_modulus.min_value() > 0, p + "Young's modulus",
            youngs_modulus.min_value(), "every value must be positive (Pa)");
    require(plastic_modulus.min_value() >= 0, p + "Plastic modulus",
            plastic_modulus.min_value(), "every value must be >= 0 (Pa)");
    require(yield_stress.min_value() > 0, p + "Yield stress",
            yield_stress.min_value(), "every value must be positive (Pa)");
    require(poisson_ratio >= 0 && poisson_ratio < 0.5, p + "Poisson's ratio",
            poisson_ratio, "it must lie in [0, 0.5)");
    require(bulk_viscosity >= 0 && bulk_viscosity <= 1, "Solid/Bulk viscosity",
            bulk_viscosity, "it must lie in [0, 1]");
    require(expansion >= 0, p + "Thermal expansion coefficient", expansion,
            "it must be >= 0 (1/K)");
  }


  double
  SolidMaterial::max_p_wave_modulus() const
  {
    const double nu = poisson_ratio;
    return youngs_modulus.max_value() * (1 - nu) / ((1 + nu) * (1 - 2 * nu));
  }


  StressIncrement
  update_stress(const SolidMaterial &m,
                const Tensor<2, 3> & L_dt,
                const double         T_old,
                const double         T_new,
                StressPoint &        state)
  {
    StressIncrement result;
    if (T_new >= m.melt_temperature)
      {
        // Melted: no stress, no hardening memory.
        state.sigma = SymmetricTensor<2, 3>();
        state.eps_p = 0;
        return result;
      }

    // Objective rotation of the old stress (Jaumann, Hughes-Winget).
    const double w01 = 0.5 * (L_dt[0][1] - L_dt[1][0]);
    const double w02 = 0.5 * (L_dt[0][2] - L_dt[2][0]);
    const double w12 = 0.5 * (L_dt[1][2] - L_dt[2][1]);
    SymmetricTensor<2, 3> sigma = state.sigma;
    if (w01 != 0 || w02 != 0 || w12 != 0)
      {
        Tensor<2, 3> W;
        W[0][1] = w01, W[1][0] = -w01;
        W[0][2] = w02, W[2][0] = -w02;
        W[1][2] = w12, W[2][1] = -w12;
        const Tensor<2, 3> I  = unit_symmetric_tensor<3>();
        const Tensor<2, 3> R  = invert(I - 0.5 * W) * (I + 0.5 * W);
        const Tensor<2, 3> s  = sigma;
        const Tensor<2, 3> rs = R * s * transpose(R);
        sigma                 = symmetrize(rs);
      }

    // Elastic predictor with the moduli at the new temperature.
    const double E      = m.youngs_modulus.value(T_new);
    const double nu     = m.poisson_ratio;
    const double mu     = E / (2 * (1 + nu));
    const double lambda = E * nu / ((1 + nu) * (1 - 2 * nu));
    SymmetricTensor<2, 3> de = symmetrize(L_dt);
    // A point that solidified in this step starts stress-free at the solidus.
    const double dth =
      m.expansion * (T_new - std::min(T_old, m.melt_temperature));
    for (unsigned int d = 0; d < 3; ++d)
      de[d][d] -= dth;
    const double tr = trace(de);
    sigma += 2 * mu * de;
    for (unsigned int d = 0; d < 3; ++d)
      sigma[d][d] += lambda * tr;

    // J2 radial return, linear isotropic hardening.
    const double          H   = m.plastic_modulus.value(T_new);
    const double          sy  = m.yield_stress.value(T_new) + H * state.eps_p;
    const double          p   = trace(sigma) / 3;
    SymmetricTensor<2, 3> s   = sigma;
    for (unsigned int d = 0; d < 3; ++d)
      s[d][d] -= p;
    const double q = std::sqrt(1.5 * (s * s));
    if (q > sy)
      {
        const double dg = (q - sy) / (3 * mu + H);
        s *= 1 - 3 * mu * dg / q;
        state.eps_p += dg;
        result.yielded           = true;
        result.plastic_increment = dg;
        sigma                    = s;
        for (unsigned int d = 0; d < 3; ++d)
          sigma[d][d] += p;
      }
    state.sigma = sigma;
    return result;
  }
} // namespace femp
