// Melt flow, the velocity transfer between points and grid (doc/flow.md,
// "Velocity transfer"; doc/verification.md, "Rotating disc"). A liquid disc
// of radius R = 0.25 m (rho = 1000 kg/m^3, inviscid, no gravity, no surface
// tension, free surface p = 0) in the middle of a box of 4 R rotates
// rigidly, v = omega x (x - c), omega = 1 rad/s; cells of R/8, four points
// per cell. 20, 80 and 320 steps of dt = 1e-5/omega: the disc turns by at
// most omega t = 3.2e-3 rad, so its angular momentum L about the centre
// and its kinetic energy E must stay at their initial values up to the
// rotation's own second-order terms, (omega t)^2 = 1e-5 (the free rim of a
// rotating liquid is unstable, Rayleigh-Taylor under the centrifugal
// acceleration, so a longer run measures that instead of the transfer).
// What changes them here is the round trip of the velocity through the
// grid at each step: the FLIP-PIC transfer at FLIP fraction 0.95 (femp's
// default) loses a share of L and E per step; APIC (Jiang et al. 2015; the
// points start with the exact C_p = grad v) carries the rigid rotation
// through P2G and G2P exactly. L and E are those of the points, with
// APIC's affine part (L_p = m_p [(x_p - c) x v_p + C_yx D_xx - C_xy D_yy],
// E_p = 1/2 m_p [|v_p|^2 + C_p : C_p D_p], D_p = diag(h^2 xi_d (1 - xi_d)),
// what the points hand to the grid in P2G).
// Printed: L/L_0 and E/E_0 of FLIP-PIC. Checks: with APIC, |L/L_0 - 1| and
// |E/E_0 - 1| at most 1e-4 (ten times (omega t)^2) after each step count.
// With the argument 3: the same in 3D, a liquid sphere of radius R in a box
// of 3 R rotating about the z axis (L the z component; the affine part
// C_yx D_xx - C_xy D_yy). 1 and 2 ranks give the same output.
#include <cmath>
#include <string>

#include "flow_tools.h"

using namespace femp_test;

namespace
{
  constexpr double R = 0.25, rho = 1000, omega = 1;
  constexpr double h = R / 8;
  /// The box's edge: 4 R in 2D, 3 R in 3D.
  template <int dim>
  constexpr double L = dim == 2 ? 4 * R : 3 * R;
  template <int dim>
  Point<dim>
  centre()
  {
    Point<dim> c;
    for (int d = 0; d < dim; ++d)
      c[d] = 0.5 * L<dim>;
    return c;
  }

  template <int dim>
  using Transfer =
    typename IncompressibleFlow<dim>::Parameters::VelocityTransfer;

  /// Angular momentum about the centre (its z component) and kinetic
  /// energy of the fluid points (with the affine part when @p affine),
  /// over all ranks.
  template <int dim>
  std::array<double, 2>
  momentum_energy(const FlowScene<dim> &scene, const bool affine)
  {
    using P               = typename MaterialPoints<dim>::PropertyIndex;
    const Point<dim> c    = centre<dim>();
    double           s[2] = {0, 0};
    for (const auto &particle : scene.points->particle_handler())
      {
        const auto v = particle.get_properties();
        const auto x = particle.get_location();
        if (v[P::state] != MaterialPoints<dim>::fluid)
          continue;
        const double m  = v[P::mass];
        const double rx = x[0] - c[0], ry = x[1] - c[1];
        const double vx = v[P::velocity], vy = v[P::velocity + 1];
        double       l = rx * vy - ry * vx, e2 = 0;
        for (int d = 0; d < dim; ++d)
          e2 += v[P::velocity + d] * v[P::velocity + d];
        if (affine)
          {
            double D[dim];
            for (int d = 0; d < dim; ++d)
              {
                const double xi = x[d] / h - std::floor(x[d] / h);
                D[d]            = h * h * xi * (1 - xi);
              }
            const double *C = &v[P::affine_velocity];
            l += C[dim] * D[0] - C[1] * D[1];
            for (int d = 0; d < dim; ++d)
              for (int e = 0; e < dim; ++e)
                e2 += C[d * dim + e] * C[d * dim + e] * D[e];
          }
        s[0] += m * l;
        s[1] += 0.5 * m * e2;
      }
    Utilities::MPI::sum(ArrayView<const double>(s, 2),
                        scene.grid.communicator(),
                        ArrayView<double>(s, 2));
    return {{s[0], s[1]}};
  }

  /// L and E after @p n steps of 1e-5/omega over their initial values.
  template <int dim>
  std::array<double, 2>
  revolution(const Transfer<dim> transfer, const unsigned int n, MPI_Comm comm)
  {
    using P = typename MaterialPoints<dim>::PropertyIndex;
    const Point<dim>                             c = centre<dim>();
    typename IncompressibleFlow<dim>::Parameters prm;
    prm.viscosity                 = 0;
    prm.gravity                   = Tensor<1, dim>();
    prm.surface_tension           = 0;
    prm.velocity_transfer         = transfer;
    prm.pressure.solver_tolerance = 1e-12;
    Point<dim> size;
    for (int d = 0; d < dim; ++d)
      size[d] = L<dim>;
    FlowScene<dim> scene(
      size,
      h,
      rho,
      [c](const Point<dim> &x) { return x.distance(c) < R; },
      prm,
      comm);
    const bool affine = transfer == Transfer<dim>::apic;
    for (auto &particle : scene.points->particle_handler_for_update())
      {
        const auto v       = particle.get_properties();
        const auto x       = particle.get_location();
        v[P::velocity]     = -omega * (x[1] - c[1]);
        v[P::velocity + 1] = omega * (x[0] - c[0]);
        if (affine)
          {
            // C = grad v: C_xy = -omega, C_yx = omega (row-major).
            for (unsigned int k = 0; k < dim * dim; ++k)
              v[P::affine_velocity + k] = 0;
            v[P::affine_velocity + 1]   = -omega;
            v[P::affine_velocity + dim] = omega;
          }
      }
    const auto   start = momentum_energy<dim>(scene, affine);
    const double dt    = 1e-5 / omega;
    for (unsigned int i = 0; i < n; ++i)
      scene.flow->step(dt);
    const auto end = momentum_energy<dim>(scene, affine);
    return {{end[0] / start[0], end[1] / start[1]}};
  }

  template <int dim>
  void
  run(Checks &checks, MPI_Comm comm)
  {
    for (const auto transfer : {Transfer<dim>::flip_pic, Transfer<dim>::apic})
      {
        const std::string name = transfer == Transfer<dim>::apic ?
                                   "APIC" :
                                   "FLIP-PIC, FLIP fraction 0.95";
        for (const unsigned int n : {20u, 80u, 320u})
          {
            const auto        r  = revolution<dim>(transfer, n, comm);
            const std::string at = name + ", " + std::to_string(n) + " steps: ";
            if (transfer == Transfer<dim>::apic)
              {
                checks.at_most(at + "|L/L_0 - 1|", std::abs(r[0] - 1), 1e-4);
                checks.at_most(at + "|E/E_0 - 1|", std::abs(r[1] - 1), 1e-4);
              }
            else
              {
                checks.print(at + "L/L_0", r[0], 3);
                checks.print(at + "E/E_0", r[1], 3);
              }
          }
      }
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  try
    {
      if (argc > 1 && std::string(argv[1]) == "3")
        run<3>(checks, comm);
      else
        run<2>(checks, comm);
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
