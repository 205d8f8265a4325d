// femp: thermo-elasto-plastic stress update (paper eq. 5): Jaumann rate by
// the Hughes-Winget rotation, thermal strain, J2 radial return with linear
// isotropic hardening, temperature tables for E, H and sigma_y.
#include <femp/base/parameter_table.h>
#include <femp/solid/constitutive.h>

#include <cmath>

namespace femp
{
  void
  SolidMaterial::add_parameters(ParameterTable &table)
  {
    ParameterHandler &prm = table.handler();
    table.enter_subsection("Solid");
    table.add("Bulk viscosity",
              bulk_viscosity,
              Patterns::Double(),
              "Linear artificial bulk viscosity b1, -: the viscous "
              "pressure q = b1 rho c h tr(D) (c: P-wave speed, h: cell "
              "size) is added to the stress in the nodal forces and "
              "damps the ringing behind stress fronts; the stable step "
              "shrinks by sqrt(1 + b1^2) - b1. Range [0, 1]; 0 is off.");
    table.add("Velocity transfer",
              velocity_transfer,
              {{VelocityTransfer::flip, "FLIP"},
               {VelocityTransfer::apic, "APIC"}},
              "How material points of the solid MPM exchange "
              "velocities with the grid nodes: APIC (affine "
              "particle-in-cell: points take the nodal velocities and "
              "carry their gradient C_p; with one point per cell it "
              "restores the nodal velocities exactly and meets case "
              "3.1; with several points per cell its transfers "
              "dissipate kinetic energy, booked in the energy file) "
              "or FLIP (points add the nodal accelerations; smooths "
              "the nodal velocities, misses case 3.1; its booked "
              "transfer term is unreliable where nodes carry little "
              "point mass; see doc/solid.md). "
              "One of FLIP, APIC.");
    table.add("Volumetric strain rate",
              volumetric_strain_rate,
              {{VolumetricStrainRate::point, "point"},
               {VolumetricStrainRate::centroid, "centroid"}},
              "Where material points of the solid MPM take the "
              "volumetric part (the trace, 1/s) of their velocity "
              "gradient: point (the divergence of the cell's "
              "multilinear nodal velocity field at each point's "
              "position) or centroid (every point of a cell takes the "
              "divergence at the volume centroid of the cell's points, "
              "in 2D the volume-weighted mean of the points' "
              "divergences; the deviatoric part stays the point's, and "
              "the points' pressure enters the nodal forces through "
              "the tent gradients at the centroid: a B-bar "
              "treatment). With point the divergence varies across a "
              "cell with the nodal velocities' hourglass mode, and on "
              "irregular point sets the pressure of neighbouring "
              "points drifts apart by up to GPa in plastic metal; "
              "centroid gives the points of a cell one volumetric "
              "strain rate; it costs a pass over the points per step, "
              "and the P2G runs as a pass of its own instead of with "
              "the stress update (doc/solid.md \"Volumetric strain "
              "rate\"). "
              "One of point, centroid.");
    table.add("Pressure smoothing",
              pressure_smoothing,
              "Whether the material points of the solid MPM smooth "
              "their mean-stress increment over the grid nodes: after "
              "each stress update the increment of tr(sigma)/3 of "
              "every solid point is replaced by its volume-weighted "
              "average at the nodes of its cell, interpolated back to "
              "the point with the tents (the volume integral of the "
              "increment is kept, the deviator stays the point's). "
              "Without it the cells' mean stress can carry a "
              "checkerboard from cell to cell (up to GPa in cooled "
              "re-solidified metal) that the nodal forces do not see; "
              "with it that mode does not build up. Costs a scatter "
              "and a gather of one value per point and step, and the "
              "P2G runs as a pass of its own (doc/solid.md "
              "\"Pressure smoothing\").");
    table.enter_subsection("Material");
    if (table.declaring())
      prm.declare_entry(
        "Young's modulus",
        "1.93e11",
        Patterns::Anything(),
        "E(T), Pa: a constant or a table 'T1:E1, T2:E2, ...' "
        "(K : Pa, T increasing, held constant outside). Every "
        "value must be positive. The elasticity is of total "
        "form (sigma = C(T) : eps_e), so the stress falls with "
        "E: in scenes that melt the substrate give a table that "
        "falls to a small value at the solidus (doc/solid.md "
        "\"Material data of 316L\").");
    if (table.declaring())
      prm.declare_entry("Plastic modulus",
                        "1e9",
                        Patterns::Anything(),
                        "Linear isotropic hardening modulus H(T) = d sigma_y / "
                        "d eps_p, Pa: a constant or a table as for Young's "
                        "modulus. Range [0, inf).");
    if (table.declaring())
      prm.declare_entry("Yield stress",
                        "2.5e8",
                        Patterns::Anything(),
                        "Initial yield stress sigma_y(T), Pa: a constant or a "
                        "table as for Young's modulus. Range (0, inf); use a "
                        "huge value for a purely elastic solid.");
    table.add("Poisson's ratio",
              poisson_ratio,
              Patterns::Double(),
              "nu, -; range [0, 0.5).");
    table.add("Thermal expansion coefficient",
              expansion,
              Patterns::Double(),
              "Linear thermal expansion alpha, 1/K; range [0, inf). "
              "The thermal stress modulus is beta = E alpha / (1 - 2 "
              "nu); in a bar in uniaxial strain with nu = 0, beta = E "
              "alpha.");
    table.leave_subsection();
    table.leave_subsection();
  }

  void
  SolidMaterial::declare_parameters(ParameterHandler &prm)
  {
    const Material thermal;
    SolidMaterial  defaults(thermal);
    ParameterTable table(prm, ParameterTable::Mode::declare);
    defaults.add_parameters(table);
  }

  void
  SolidMaterial::parse_parameters(ParameterHandler &prm)
  {
    ParameterTable table(prm, ParameterTable::Mode::parse);
    add_parameters(table);
    prm.enter_subsection("Solid");
    prm.enter_subsection("Material");
    const std::string p = "Solid/Material/";
    youngs_modulus =
      PiecewiseLinear::parse(prm.get("Young's modulus"), p + "Young's modulus");
    plastic_modulus =
      PiecewiseLinear::parse(prm.get("Plastic modulus"), p + "Plastic modulus");
    yield_stress =
      PiecewiseLinear::parse(prm.get("Yield stress"), p + "Yield stress");
    prm.leave_subsection();
    prm.leave_subsection();
    require(youngs_modulus.min_value() > 0,
            p + "Young's modulus",
            youngs_modulus.min_value(),
            "every value must be positive (Pa)");
    require(plastic_modulus.min_value() >= 0,
            p + "Plastic modulus",
            plastic_modulus.min_value(),
            "every value must be >= 0 (Pa)");
    require(yield_stress.min_value() > 0,
            p + "Yield stress",
            yield_stress.min_value(),
            "every value must be positive (Pa)");
    require(poisson_ratio >= 0 && poisson_ratio < 0.5,
            p + "Poisson's ratio",
            poisson_ratio,
            "it must lie in [0, 0.5)");
    require(bulk_viscosity >= 0 && bulk_viscosity <= 1,
            "Solid/Bulk viscosity",
            bulk_viscosity,
            "it must lie in [0, 1]");
    require(expansion >= 0,
            p + "Thermal expansion coefficient",
            expansion,
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
                const Tensor<2, 3>  &L_dt,
                const double         T_old,
                const double         T_new,
                StressPoint         &state)
  {
    // The array kernel of constitutive.h does the work (one code path for
    // material points and finite elements).
    double L[3][3], sv[6];
    for (unsigned int i = 0; i < 3; ++i)
      for (unsigned int j = 0; j < 3; ++j)
        L[i][j] = L_dt[i][j];
    sv[0] = state.sigma[0][0], sv[1] = state.sigma[1][1],
    sv[2] = state.sigma[2][2];
    sv[3] = state.sigma[0][1], sv[4] = state.sigma[0][2],
    sv[5] = state.sigma[1][2];
    StressIncrement result;
    result.plastic_increment =
      update_stress_array(m, L, T_old, T_new, sv, state.eps_p);
    result.yielded    = result.plastic_increment > 0;
    state.sigma[0][0] = sv[0], state.sigma[1][1] = sv[1],
    state.sigma[2][2] = sv[2];
    state.sigma[0][1] = sv[3], state.sigma[0][2] = sv[4],
    state.sigma[1][2] = sv[5];
    return result;
  }
} // namespace femp
