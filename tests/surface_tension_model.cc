// The temperature coefficient dsigma/dT of the Marangoni stress
// (SurfaceTension; doc/flow.md, "Surface tension model"):
//  1. surfactant model (Sahoo, DebRoy and McNallan 1988, Fe-S constants,
//     the activity a_s of prm/materials/316L.prm's study value): the
//     analytic dsigma/dT against a central difference of sigma(T)
//     (SurfaceTension::difference, step 0.1 K) at 1700-4000 K, error
//     relative to A below 1e-6;
//  2. its sign: positive at 1800 K, negative at 3000 K; the critical
//     temperature where dsigma/dT = 0 (bisection) is printed;
//  3. the secant slope (sigma(2200 K) - sigma(1700 K))/500 K, which the
//     activity reproduces from Pichler et al. 2022's linear fit of SRM
//     1155a, +1.9e-4 N/(m K), within 1e-7 (the a_s of the study is rounded
//     to 4 digits);
//  4. without solute (a_s = 0) dsigma/dT = -A at every temperature; the
//     linear model returns its constant bit for bit, and sigma(T1) -
//     sigma(T0) = dsigma/dT (T1 - T0) to round-off;
//  5. in the free surface: the Marangoni nodal forces of a flat 2D pool
//     with a small temperature gradient along it (1e-5 K across the pool,
//     over which dsigma/dT changes by less than 1e-7 of itself),
//     surfactant model against the linear model with the constant
//     dsigma/dT(T0), at T0 = 1900 K (inward) and 3000 K (outward): the same
//     forces (max difference relative to the largest, 1e-6), and the sign
//     of the total force along the surface follows dsigma/dT(T0).
// 1 and 2 ranks give the same output.
#include <femp/flow/free_surface.h>
#include <femp/flow/surface_tension.h>

#include <cmath>

#include "flow_tools.h"

using namespace femp_test;

namespace
{
  constexpr int dim = 2;

  SurfaceTension::Surfactant
  fe_s(const double activity)
  {
    SurfaceTension::Surfactant s; // Sahoo et al.'s Fe-S constants
    s.activity = activity;
    return s;
  }

  // The activity of 316L (SRM 1155a) from Pichler et al.'s slope, the lower
  // of the two roots (doc/studies/2026-12-04-surfactant-surface-tension.md).
  constexpr double a_316L = 0.02313;

  void
  analytic_against_difference(Checks &checks)
  {
    const SurfaceTension law(SurfaceTension::Model::surfactant,
                             0,
                             fe_s(a_316L));
    const double         A = fe_s(a_316L).pure_metal_gradient, dT = 0.1;
    double               err = 0;
    for (const double T :
         {1700., 1800., 2000., 2100., 2200., 2500., 3000., 3500., 4000.})
      {
        const double fd = law.difference(T - dT, T + dT) / (2 * dT);
        err             = std::max(err, std::abs(law.gradient(T) - fd) / A);
        checks.print("surfactant: dsigma/dT at " + std::to_string(int(T)) +
                       " K, N/(m K)",
                     law.gradient(T),
                     3);
      }
    checks.at_most("surfactant: max |dsigma/dT - central difference| / A",
                   err,
                   1e-6);

    checks.in_range("surfactant: dsigma/dT(1800 K) / A",
                    law.gradient(1800) / A,
                    1e-3,
                    10);
    checks.in_range("surfactant: dsigma/dT(3000 K) / A",
                    law.gradient(3000) / A,
                    -10,
                    -1e-3);
    double lo = 1800, hi = 3000;
    for (int i = 0; i < 60; ++i)
      {
        const double m                  = 0.5 * (lo + hi);
        (law.gradient(m) > 0 ? lo : hi) = m;
      }
    checks.print("surfactant: critical temperature (dsigma/dT = 0), K",
                 std::round(0.5 * (lo + hi)));

    const double secant = law.difference(1700, 2200) / 500;
    checks.print("surfactant: secant slope 1700-2200 K, N/(m K)", secant, 3);
    checks.at_most("surfactant: |secant slope - 1.9e-4| (Pichler et al.)",
                   std::abs(secant - 1.9e-4),
                   1e-7);
  }

  void
  limits(Checks &checks)
  {
    const SurfaceTension pure(SurfaceTension::Model::surfactant, 0, fe_s(0));
    const SurfaceTension linear(SurfaceTension::Model::linear,
                                1.9e-4,
                                fe_s(a_316L));
    double               pure_err = 0, linear_err = 0, difference_err = 0;
    for (const double T : {1000., 1730., 2500., 4000., 8000.})
      {
        pure_err = std::max(pure_err, std::abs(pure.gradient(T) + 4.3e-4));
        linear_err =
          std::max(linear_err, std::abs(linear.gradient(T) - 1.9e-4));
        difference_err =
          std::max(difference_err,
                   std::abs(linear.difference(1730, T) - 1.9e-4 * (T - 1730)));
      }
    checks.at_most("a_s = 0: max |dsigma/dT + A|, N/(m K)", pure_err, 1e-18);
    checks.at_most("linear: max |dsigma/dT - 1.9e-4|, N/(m K)", linear_err, 0);
    checks.at_most("linear: max |sigma(T) - sigma(1730 K) - 1.9e-4 (T - "
                   "1730 K)|, N/m",
                   difference_err,
                   1e-15);
    checks.print(
      "linear: Marangoni on with dsigma/dT = 0",
      SurfaceTension(SurfaceTension::Model::linear, 0, fe_s(1)).marangoni());
    checks.print("surfactant: Marangoni on",
                 SurfaceTension(SurfaceTension::Model::surfactant, 0, fe_s(0))
                   .marangoni());
  }

  void
  free_surface_forces(Checks &checks, MPI_Comm comm)
  {
    const double                        h = 0.025, rho = 1000, H = 0.3, W = 0.4;
    IncompressibleFlow<dim>::Parameters prm;
    prm.gravity          = Tensor<1, dim>();
    prm.gravity[dim - 1] = -9.81;
    FlowScene<dim> scene(
      Point<dim>(W, 0.4),
      h,
      rho,
      [&](const Point<dim> &x) { return x[dim - 1] < H; },
      prm,
      comm);
    std::vector<double> T = scene.grid.make_field(300.);
    CellFields<dim>     fields;
    fields.temperature = &T;
    scene.flow->step(1e-9, fields); // the cell classes
    const auto                &type = scene.flow->cell_type();
    std::vector<std::uint32_t> fluid_cells;
    for (const auto c : scene.grid.owned_cells())
      if (type[c] == IncompressibleFlow<dim>::fluid)
        fluid_cells.push_back(c);

    const SurfaceTension law(SurfaceTension::Model::surfactant,
                             0,
                             fe_s(a_316L));
    for (const double T0 : {1900., 3000.})
      {
        for (std::size_t i = 0; i < T.size(); ++i)
          T[i] = T0 + 2.5e-5 * scene.grid.cell_center(i)[0]; // 1e-5 K over W
        FreeSurface<dim>::Parameters surfactant, linear;
        surfactant.surface_tension_model = SurfaceTension::Model::surfactant;
        surfactant.surfactant            = fe_s(a_316L);
        linear.surface_tension_gradient  = law.gradient(T0);
        FreeSurface<dim> fs(surfactant,
                            scene.material,
                            scene.grid,
                            *scene.points);
        FreeSurface<dim> fl(linear, scene.material, scene.grid, *scene.points);
        fs.update(type, fluid_cells, &T);
        fl.update(type, fluid_cells, &T);
        double diff = 0, largest = 0, total = 0;
        for (int d = 0; d < dim; ++d)
          for (std::size_t n = 0; n < fs.marangoni_force()[d].size(); ++n)
            {
              diff    = std::max(diff,
                              std::abs(fs.marangoni_force()[d][n] -
                                       fl.marangoni_force()[d][n]));
              largest = std::max(largest, std::abs(fl.marangoni_force()[d][n]));
            }
        // Total force along the surface: each node once, from its owner
        // (the nodes of the owned cells' lower-left corners).
        for (const auto c : scene.grid.owned_cells())
          total += fs.marangoni_force()[0][scene.grid.first_node_of_cell(c)];
        diff                 = Utilities::MPI::max(diff, comm);
        largest              = Utilities::MPI::max(largest, comm);
        total                = Utilities::MPI::sum(total, comm);
        const std::string at = "T0 = " + std::to_string(int(T0)) + " K: ";
        checks.print(at + "dsigma/dT(T0), N/(m K)", law.gradient(T0), 3);
        checks.at_most(at + "max |F_surfactant - F_linear| / max |F_linear|",
                       diff / largest,
                       1e-6);
        checks.in_range(at + "sign of the total force along x x sign of "
                             "dsigma/dT(T0)",
                        (total > 0 ? 1. : -1.) *
                          (law.gradient(T0) > 0 ? 1. : -1.),
                        1,
                        1);
      }
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  analytic_against_difference(checks);
  limits(checks);
  free_surface_forces(checks, comm);
  return checks.exit_code();
}
