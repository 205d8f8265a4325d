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

    // Plain arrays in the hot path: s[i][j] full 3x3 copy of the stress.
    double S[3][3];
    for (unsigned int i = 0; i < 3; ++i)
      for (unsigned int j = 0; j < 3; ++j)
        S[i][j] = state.sigma[i][j];

    // Objective rotation of the old stress (Jaumann, Hughes-Winget):
    // R = (I - W/2)^-1 (I + W/2) = I + (W + W^2/2) / (1 + |w|^2/4) (Cayley),
    // exactly orthogonal; W is the spin times the step.
    const double w01 = 0.5 * (L_dt[0][1] - L_dt[1][0]);
    const double w02 = 0.5 * (L_dt[0][2] - L_dt[2][0]);
    const double w12 = 0.5 * (L_dt[1][2] - L_dt[2][1]);
    if (w01 != 0 || w02 != 0 || w12 != 0)
      {
        const double W[3][3] = {{0, w01, w02}, {-w01, 0, w12}, {-w02, -w12, 0}};
        const double f = 1. / (1 + 0.25 * (w01 * w01 + w02 * w02 + w12 * w12));
        double       R[3][3];
        for (unsigned int i = 0; i < 3; ++i)
          for (unsigned int j = 0; j < 3; ++j)
            {
              double w2 = 0;
              for (unsigned int k = 0; k < 3; ++k)
                w2 += W[i][k] * W[k][j];
              R[i][j] = (i == j ? 1. : 0.) + f * (W[i][j] + 0.5 * w2);
            }
        double RS[3][3];
        for (unsigned int i = 0; i < 3; ++i)
          for (unsigned int j = 0; j < 3; ++j)
            RS[i][j] = R[i][0] * S[0][j] + R[i][1] * S[1][j] + R[i][2] * S[2][j];
        for (unsigned int i = 0; i < 3; ++i)
          for (unsigned int j = i; j < 3; ++j)
            S[i][j] = S[j][i] =
              RS[i][0] * R[j][0] + RS[i][1] * R[j][1] + RS[i][2] * R[j][2];
      }

    // Elastic predictor with the moduli at the new temperature. A point
    // that solidified in this step starts stress-free at the solidus.
    const double E      = m.youngs_modulus.value(T_new);
    const double nu     = m.poisson_ratio;
    const double mu     = E / (2 * (1 + nu));
    const double lambda = E * nu / ((1 + nu) * (1 - 2 * nu));
    const double dth = m.expansion * (T_new - std::min(T_old, m.melt_temperature));
    double       de[3][3];
    for (unsigned int i = 0; i < 3; ++i)
      for (unsigned int j = 0; j < 3; ++j)
        de[i][j] = 0.5 * (L_dt[i][j] + L_dt[j][i]) - (i == j ? dth : 0.);
    const double tr = de[0][0] + de[1][1] + de[2][2];
    for (unsigned int i = 0; i < 3; ++i)
      for (unsigned int j = 0; j < 3; ++j)
        S[i][j] += 2 * mu * de[i][j] + (i == j ? lambda * tr : 0.);

    // J2 radial return, linear isotropic hardening.
    const double p = (S[0][0] + S[1][1] + S[2][2]) / 3;
    for (unsigned int d = 0; d < 3; ++d)
      S[d][d] -= p;
    double ss = 0;
    for (unsigned int i = 0; i < 3; ++i)
      for (unsigned int j = 0; j < 3; ++j)
        ss += S[i][j] * S[i][j];
    const double q  = std::sqrt(1.5 * ss);
    const double sy = m.yield_stress.value(T_new);
    double       scale = 1;
    if (q > sy) // cheap test first: the hardening term only raises sy
      {
        const double H   = m.plastic_modulus.value(T_new);
        const double syh = sy + H * state.eps_p;
        if (q > syh)
          {
            const double dg = (q - syh) / (3 * mu + H);
            scale           = 1 - 3 * mu * dg / q;
            state.eps_p += dg;
            result.yielded           = true;
            result.plastic_increment = dg;
          }
      }
    SymmetricTensor<2, 3> sigma;
    for (unsigned int i = 0; i < 3; ++i)
      for (unsigned int j = i; j < 3; ++j)
        sigma[i][j] = scale * S[i][j] + (i == j ? p : 0.);
    state.sigma = sigma;
    return result;
  }
} // namespace femp
