// femp benchmark of the solid step (not a test; doc/performance.md): cost per
// point-step of the material point method (P2G, grid update, G2P, MUSL
// re-map, constitutive update) and per element-step of the finite elements
// (internal and hourglass forces, node update, constitutive update), on a
// 3D block heated by a slowly rising, non-uniform temperature field so that
// the constitutive update does real work (thermal strain, plasticity at the
// hot end). One run with every cell full of material points (2 x 2 x 2 per
// cell), one with every cell a finite element; the MPM with the FLIP
// transfer, and sub-cycled also with APIC (the default transfer).
//
//   build/contrib/solid_benchmark [cells per direction, default 32] [steps]
//                                 [fe | mpm | apic | flip | mpmcheck |
//                                  constitutive:
//                                  only that part]
//                                 [centroid]
//   (centroid: the MPM with Solid/Volumetric strain rate = centroid;
//   mpmcheck: the final energies and stress sums of the sub-cycled MPM
//   runs, FLIP and APIC, not timed, to compare code versions;
//   constitutive: the scalar update_stress and the SIMD update_stress_block
//   on the same states; fe also prints the final energies and
//   stress sums of both runs, to compare code versions)
//
// Run on one core (no mpirun) with a Release build. Prints ns of process CPU
// time per point-step and per element-step (the grid node work of a step is
// included in both: it is part of what a step costs).
#include <deal.II/base/mpi.h>

#include <femp/grid/material_points.h>
#include <femp/solid/solid_sub_cycle.h>

#include <cmath>
#include <ctime>
#include <iomanip>
#include <iostream>
#include <sstream>

using namespace dealii;
using namespace femp;

namespace
{
  constexpr int dim = 3;
  /// Solid/Volumetric strain rate of the MPM runs (argument 4).
  SolidMaterial::VolumetricStrainRate volumetric =
    SolidMaterial::VolumetricStrainRate::point;

  double
  run(const unsigned int                    n,
      const unsigned int                    steps,
      const bool                            fe,
      const bool                            subcycled,
      double                               &n_objects,
      const SolidMaterial::VelocityTransfer transfer =
        SolidMaterial::VelocityTransfer::flip,
      std::ostream *check = nullptr)
  {
    const double                             h = 1e-5;
    typename BackgroundGrid<dim>::Parameters gp;
    gp.lower_corner = Point<dim>();
    gp.upper_corner = Point<dim>(n * h, n * h, n * h / 2);
    gp.cell_size    = h;
    BackgroundGrid<dim> grid(gp, MPI_COMM_WORLD);
    grid.create();
    Material mat; // 316L-like defaults
    mat.solidus  = 1e6;
    mat.liquidus = 2e6;
    typename MaterialPoints<dim>::Parameters pp;
    pp.point_spacing   = h / 2;
    pp.substrate_top   = n * h / 2;
    pp.layer_thickness = 0;
    MaterialPoints<dim> points(pp, mat, grid);
    points.create(300.);

    SolidMaterial sm(mat); // defaults: steel, E 193 GPa, sigma_y 250 MPa
    sm.yield_stress = PiecewiseLinear::parse("300:2.5e8, 1500:2e7", "yield");
    sm.velocity_transfer      = transfer;
    sm.volumetric_strain_rate = volumetric;
    typename SolidSubCycle<dim>::Parameters sp;
    sp.fixed_faces = {"z-"};
    sp.energy_file = "";
    typename SolidFEM<dim>::Parameters fp;
    fp.enabled      = fe;
    fp.lower_corner = gp.lower_corner;
    fp.upper_corner = gp.upper_corner;
    SolidSubCycle<dim>  solid(sp, fp, sm, grid, points);
    std::vector<double> T = grid.make_field(300.);
    solid.initialize(T, "");
    const auto sizes = solid.sizes();
    n_objects        = fe ? sizes[1] : sizes[0];

    // Temperature: rises by up to 1000 K over the run near x = 0.
    auto set_T = [&](const double t) {
      for (const auto c : grid.owned_cells())
        {
          const double x = grid.cell_center(c)[0] / (n * h);
          T[c]           = 300 + 1000 * t * std::exp(-4 * x);
        }
    };
    const double dt = solid.time_step();
    // Warm-up step, then timed steps (advance one solid step per call, as
    // when the temperature step is the smaller one).
    set_T(0.01);
    solid.advance(dt, T, true);
    const std::clock_t start = std::clock();
    if (subcycled) // all steps inside one temperature step
      {
        set_T(1.);
        solid.advance((steps + 1) * dt, T, true);
      }
    else // one call (and one gather/scatter of the points) per step
      for (unsigned int s = 1; s <= steps; ++s)
        {
          set_T(double(s) / steps);
          solid.advance((s + 1) * dt, T, true);
        }
    // Process CPU time, not wall time: on a shared machine the wall time
    // also counts the time other processes hold the core.
    const double cpu = double(std::clock() - start) / CLOCKS_PER_SEC;
    if (check != nullptr)
      {
        // Final state (to compare code versions; not timed): energies and
        // sums of sigma_xx and the von Mises stress over the cells.
        const auto          e   = solid.energies();
        std::vector<double> sxx = grid.make_field(0.), vm = grid.make_field(0.);
        solid.cell_stress_fields(sxx, vm);
        double ssum = 0, vsum = 0;
        for (const auto c : grid.owned_cells())
          ssum += sxx[c], vsum += vm[c];
        ssum = Utilities::MPI::sum(ssum, MPI_COMM_WORLD);
        vsum = Utilities::MPI::sum(vsum, MPI_COMM_WORLD);
        if (Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0)
          *check << std::setprecision(12) << "  check: external " << e.external
                 << " internal " << e.internal << " kinetic " << e.kinetic
                 << " hourglass " << e.hourglass << " sum sigma_xx " << ssum
                 << " sum von Mises " << vsum << "\n";
      }
    return cpu / steps / n_objects * 1e9;
  }
  /// The constitutive update alone (eq. 5), as the FE calls it: ns per
  /// call over @p n states, with a velocity gradient of a heated element
  /// (thermal strain, spin) and a temperature rising by 1000 K.
  std::vector<StressPoint> states; // of constitutive_only()
  std::vector<StressBlock> blocks; // of constitutive_block()

  double
  constitutive_only(const unsigned int n, const unsigned int steps)
  {
    Material thermal; // 316L-like defaults, no melting
    thermal.solidus = 1e6;
    SolidMaterial sm(thermal);
    sm.yield_stress = PiecewiseLinear::parse("300:2.5e8, 1500:2e7", "yield");
    states.assign(n, StressPoint());
    double             sum   = 0;
    const std::clock_t start = std::clock();
    for (unsigned int s = 0; s < steps; ++s)
      {
        const double T0 = 300 + 1000. * s / steps,
                     T1 = 300 + 1000. * (s + 1) / steps;
        for (unsigned int i = 0; i < n; ++i)
          {
            Tensor<2, 3> L;
            const double x = 1e-6 * (1 + (i % 7));
            L[0][0]        = x;
            L[0][1]        = 0.3 * x;
            L[1][0]        = -0.1 * x;
            L[1][1]        = 0.5 * x;
            L[2][2]        = -0.2 * x;
            update_stress(
              sm, L, T0 - 100. * (i % 5), T1 - 100. * (i % 5), states[i]);
          }
        sum += states[n / 2].sigma[0][0];
      }
    const double cpu = double(std::clock() - start) / CLOCKS_PER_SEC;
    if (sum == 42) // keep the loop
      std::cout << "";
    return cpu / steps / n * 1e9;
  }
  /// The same states and loading through update_stress_block (the SIMD
  /// kernel of the FE and MPM loops, simd_lanes states per call): ns per
  /// state.
  double
  constitutive_block(const unsigned int n, const unsigned int steps)
  {
    Material thermal; // 316L-like defaults, no melting
    thermal.solidus = 1e6;
    SolidMaterial sm(thermal);
    sm.yield_stress = PiecewiseLinear::parse("300:2.5e8, 1500:2e7", "yield");
    constexpr unsigned int W = simd_lanes;
    blocks.resize(n / W);
    for (auto &b : blocks)
      {
        for (auto &c : b.s)
          c = simd_double{};
        b.eps_p = simd_double{};
      }
    double             sum   = 0;
    const std::clock_t start = std::clock();
    for (unsigned int s = 0; s < steps; ++s)
      {
        const double T0 = 300 + 1000. * s / steps,
                     T1 = 300 + 1000. * (s + 1) / steps;
        for (std::size_t k = 0; k < blocks.size(); ++k)
          {
            StressBlock &b = blocks[k];
            for (unsigned int l = 0; l < W; ++l)
              {
                const unsigned int i = W * k + l;
                const double       x = 1e-6 * (1 + (i % 7));
                for (auto &row : b.L)
                  for (auto &c : row)
                    c[l] = 0;
                b.L[0][0][l] = x;
                b.L[0][1][l] = 0.3 * x;
                b.L[1][0][l] = -0.1 * x;
                b.L[1][1][l] = 0.5 * x;
                b.L[2][2][l] = -0.2 * x;
                b.T_old[l]   = T0 - 100. * (i % 5);
                b.T_new[l]   = T1 - 100. * (i % 5);
                b.E[l]       = sm.youngs_modulus.value(b.T_new[l]);
                b.E_old[l]   = sm.youngs_modulus.value(b.T_old[l]);
              }
            update_stress_block(sm, b);
          }
        sum += blocks[n / W / 2].s[0][0];
      }
    const double cpu = double(std::clock() - start) / CLOCKS_PER_SEC;
    if (sum == 42) // keep the loop
      std::cout << "";
    return cpu / steps / (W * blocks.size()) * 1e9;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  const unsigned int               n     = argc > 1 ? std::atoi(argv[1]) : 32;
  const unsigned int               steps = argc > 2 ? std::atoi(argv[2]) : 50;
  double                           n_points = 0, n_elements = 0;
  const std::string                only = argc > 3 ? argv[3] : "";
  if (argc > 4 && std::string(argv[4]) == "centroid")
    volumetric = SolidMaterial::VolumetricStrainRate::centroid;
  if (only == "constitutive")
    {
      std::cout << "update_stress alone: "
                << constitutive_only(n * n * n / 2, steps) << " ns per call\n"
                << "update_stress_block (SIMD, " << simd_lanes
                << " states per call): "
                << constitutive_block(n * n * n / 2, steps)
                << " ns per state\n";
      // The two kernels on the same states: the same arithmetic per state,
      // so the stresses agree up to round-off (multiply-adds contracted
      // differently by the compiler).
      double diff = 0, smax = 0, eps_p = 0;
      for (std::size_t k = 0; k < blocks.size(); ++k)
        for (unsigned int l = 0; l < simd_lanes; ++l)
          {
            const StressPoint &st = states[simd_lanes * k + l];
            eps_p                 = std::max(eps_p, st.eps_p);
            for (unsigned int c = 0; c < 6; ++c)
              {
                smax = std::max(smax, std::abs(st.sigma.access_raw_entry(c)));
                diff = std::max(diff,
                                std::abs(st.sigma.access_raw_entry(c) -
                                         blocks[k].s[c][l]));
              }
          }
      std::cout << "max |sigma_block - sigma_scalar| / max |sigma| = "
                << diff / smax << " (max eps_p " << eps_p << ")\n";
      return 0;
    }
  if (only == "mpmcheck")
    {
      // Final state of the MPM runs (FLIP and APIC sub-cycled; not timed),
      // to compare code versions.
      using VT                 = SolidMaterial::VelocityTransfer;
      double             n_obj = 0;
      std::ostringstream check;
      run(n, steps, false, true, n_obj, VT::flip, &check);
      run(n, steps, false, true, n_obj, VT::apic, &check);
      std::cout << "MPM FLIP, APIC, sub-cycled:\n" << check.str();
      return 0;
    }
  if (only == "mpm" || only == "apic" || only == "flip")
    {
      // MPM only: FLIP and APIC sub-cycled, FLIP one advance() per step
      // ("apic" / "flip": that transfer sub-cycled alone, for perf).
      using VT     = SolidMaterial::VelocityTransfer;
      double n_obj = 0, a = 0, f = 0, f1 = 0;
      if (only != "apic")
        f = run(n, steps, false, true, n_obj, VT::flip);
      if (only != "flip")
        a = run(n, steps, false, true, n_obj, VT::apic);
      if (only == "mpm")
        f1 = run(n, steps, false, false, n_obj, VT::flip);
      std::cout << std::setprecision(4) << "MPM: " << n_obj
                << " points, sub-cycled: " << a << " ns per point-step (APIC), "
                << f << " (FLIP); one advance() per step: " << f1
                << " (FLIP)\n";
      return 0;
    }
  if (!only.empty())
    {
      const bool         fe    = only == "fe";
      double             n_obj = 0;
      std::ostringstream check;
      const double       a = run(n,
                           steps,
                           fe,
                           false,
                           n_obj,
                           SolidMaterial::VelocityTransfer::flip,
                           fe ? &check : nullptr);
      const double       b = run(n,
                           steps,
                           fe,
                           true,
                           n_obj,
                           SolidMaterial::VelocityTransfer::flip,
                           fe ? &check : nullptr);
      std::cout << std::setprecision(4) << (fe ? "FE: " : "MPM: ") << n_obj
                << (fe ? " elements, " : " points, ") << a
                << " ns per step (one advance() per step), " << b
                << " ns per step (sub-cycled)\n"
                << check.str();
      return 0;
    }
  const double mpm  = run(n, steps, false, false, n_points);
  const double fe   = run(n, steps, true, false, n_elements);
  const double mpm1 = run(n, steps, false, true, n_points);
  const double fe1  = run(n, steps, true, true, n_elements);
  const double apic1 =
    run(n, steps, false, true, n_points, SolidMaterial::VelocityTransfer::apic);
  std::cout << std::setprecision(4) << "grid " << n << " x " << n << " x "
            << n / 2 << " cells, " << steps << " steps, "
            << Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD) << " rank(s)\n"
            << "one advance() per solid step (points gathered every step):\n"
            << "  MPM: " << n_points << " points, " << mpm
            << " ns per point-step\n"
            << "  FE:  " << n_elements << " elements, " << fe
            << " ns per element-step\n"
            << "all steps sub-cycled in one advance() (one gather):\n"
            << "  MPM: " << mpm1 << " ns per point-step (FLIP), " << apic1
            << " (APIC)\n"
            << "  FE:  " << fe1 << " ns per element-step\n"
            << "cost per cell, 8 points vs one element: " << 8 * mpm / fe
            << " (per step), " << 8 * mpm1 / fe1 << " (sub-cycled)\n";
}
