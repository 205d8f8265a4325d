// The cell-to-cell alternation of the mean stress of the solid's material
// points with and without Solid/Pressure smoothing (SolidMPM::
// smooth_pressure_increment(); doc/solid.md "Pressure smoothing").
// A 3D block of material points, 0.6 m (x) x 1.2 m (y) x 0.6 m (z) in a
// box 0.8 m tall, cells of 0.1 m, 2 x 2 x 2 points per cell; bottom
// fixed, the four sides on rollers, top free; E(T) falling from 100 Pa at
// 300 K to 1 Pa at the solidus 600 K (total form, as femp's 316L data),
// nu = 0.3, alpha = 2e-5 1/K, yield stress 0.1 Pa, hardening 5 Pa.
// A "track" along x heats the block and goes away: T = 300 + 600 f(t)
// exp(-((y - 0.6)/0.25)^2) (z/0.6)^2, f rising from 0 to 1 over 1 s and
// falling back to 0 over the next 1 s. The top cells under the track pass
// the solidus (their points shed their stress and re-solidify
// stress-free), the metal around them yields in compression on heating
// and in tension on cooling, and at the end the block is back at 300 K
// with a residual stress that is smooth in y and z and uniform along x.
// The measure, on the lines along y (one per x column and row of cells
// below the top row): the cells' mean stress p = tr(sigma)/3 (the mean
// over a cell's points, as the grid output's cell fields), its largest
// alternation (at a cell whose steps to its two neighbours along y have
// opposite signs, the smaller step; zero on a monotone profile, small
// at a smooth extremum, the amplitude of a cell-to-cell alternation)
// and its largest jump between neighbours, both over the largest
// |mean of p| of a row of cells. Printed per setting: those, the row
// means of p, the alternation of von Mises, and the solid's energy
// balance over its stress work.
// Checks:
//   - smoothing off: the alternation is there (at least 0.5 of the
//     scale): the mode of the mean stress from cell to cell that the
//     points' nodal forces do not see;
//   - smoothing on: the alternation of p at most 0.1 of the scale; the row
//   means of p within 0.1 of the scale of those without
//     smoothing (the smoothing keeps the volume integral of each
//     increment); the energy balance within 0.05 of the stress work.
// Runs on 1 and 2 ranks against one output.
#include <femp/grid/material_points.h>
#include <femp/solid/solid_sub_cycle.h>

#include "solid_tools.h"

using namespace femp_test;

namespace
{
  constexpr int    dim = 3;
  constexpr double h   = 0.1;
  constexpr int    nx = 6, ny = 12, nz = 6;

  struct Result
  {
    std::vector<double> row_mean_p;
    double scale = 0, alt_p = 0, jump_p = 0, alt_vm = 0, balance = 0;
  };

  Result
  run(const bool         smoothing,
      const std::string &name,
      Checks            &checks,
      MPI_Comm           comm)
  {
    const Point<dim> size(nx * h, ny * h, (nz + 2) * h); // room to expand
    Material         thermal = unit_material();
    thermal.solidus          = 600;
    thermal.liquidus         = 700;
    SolidBlock<dim> block(size, h, nz * h, thermal, comm, 300.);

    SolidMaterial sm       = block_material("0:0.1", block.material);
    sm.poisson_ratio       = 0.3;
    sm.expansion           = 2e-5;
    sm.youngs_modulus      = PiecewiseLinear::parse("300:100, 600:1", "E");
    sm.pressure_smoothing  = smoothing;
    auto sp                = block_supports<dim>();
    sp.fixed_faces         = {"z-"};
    sp.roller_faces        = {"x-", "x+", "y-", "y+"};
    const auto          fp = fe_block<dim>(false, size, 0.);
    SolidSubCycle<dim>  solid(sp, fp, sm, block.grid, *block.points);
    std::vector<double> T = block.grid.make_field(300.);
    solid.initialize(T, "");
    const int n = 100;
    for (int s = 1; s <= n; ++s)
      {
        const double f = s <= n / 2 ? 2. * s / n : 2. - 2. * s / n;
        for (std::size_t c = 0; c < T.size(); ++c)
          {
            const Point<dim> x  = block.grid.cell_center(c);
            const double     dy = (x[1] - 0.6) / 0.25, z = x[2] / (nz * h);
            T[c] = 300. + 600. * f * std::exp(-dy * dy) * z * z;
          }
        solid.advance(2. * s / n, T, s == n);
      }

    // Cell means over the points (each cell's points are on the rank that
    // owns it): sums of p, von Mises and the count per cell.
    using P = typename MaterialPoints<dim>::PropertyIndex;
    std::vector<double> sums(3 * nx * ny * nz, 0.);
    for (const auto &particle : block.points->particle_handler())
      {
        const Point<dim> x = particle.get_location();
        const auto       q = particle.get_properties();
        int              ijk[dim];
        const int        nc[dim] = {nx, ny, nz};
        for (int d = 0; d < dim; ++d)
          ijk[d] = std::max(0, std::min(nc[d] - 1, int(std::floor(x[d] / h))));
        SymmetricTensor<2, dim> s;
        for (unsigned int c = 0; c < s.n_independent_components; ++c)
          s.access_raw_entry(c) = q[P::stress + c];
        const double  p  = trace(s) / 3;
        const auto    ds = deviator(s);
        double *const c =
          sums.data() + 3 * ((ijk[2] * ny + ijk[1]) * nx + ijk[0]);
        c[0] += p, c[1] += std::sqrt(1.5 * (ds * ds)), c[2] += 1;
      }
    Utilities::MPI::sum(sums, comm, sums);
    auto cell = [&](const int i, const int j, const int k, const int f) {
      const double *const c = sums.data() + 3 * ((k * ny + j) * nx + i);
      return c[f] / c[2];
    };
    Result r;
    r.row_mean_p.assign(nz, 0.);
    for (int k = 0; k < nz; ++k)
      {
        for (int j = 0; j < ny; ++j)
          for (int i = 0; i < nx; ++i)
            r.row_mean_p[k] += cell(i, j, k, 0) / (nx * ny);
        r.scale = std::max(r.scale, std::abs(r.row_mean_p[k]));
      }
    for (int k = 0; k + 1 < nz; ++k) // below the top row
      for (int i = 0; i < nx; ++i)
        for (int j = 0; j + 1 < ny; ++j)
          {
            r.jump_p =
              std::max(r.jump_p,
                       std::abs(cell(i, j + 1, k, 0) - cell(i, j, k, 0)));
            if (j == 0)
              continue;
            // The zig-zag at j: the smaller of the two steps to its
            // neighbours where they have opposite signs (a local extremum
            // of one cell), else 0.
            auto alternation = [&](const int f) {
              const double a = cell(i, j, k, f) - cell(i, j - 1, k, f);
              const double b = cell(i, j + 1, k, f) - cell(i, j, k, f);
              return a * b < 0 ? std::min(std::abs(a), std::abs(b)) : 0.;
            };
            r.alt_p  = std::max(r.alt_p, alternation(0));
            r.alt_vm = std::max(r.alt_vm, alternation(1));
          }
    checks.print(name + ": largest |row mean of p| (Pa)", r.scale, 4);
    for (int k = 0; k < nz; ++k)
      checks.print(name + ": row " + std::to_string(k) + " mean of p / scale",
                   r.row_mean_p[k] / r.scale,
                   3);
    checks.print(name + ": largest jump of p along y / scale",
                 r.jump_p / r.scale,
                 2);
    checks.print(name + ": largest alternation of von Mises along y / scale",
                 r.alt_vm / r.scale,
                 2);
    const auto e = solid.energies();
    checks.at_most(name + ": |energy balance| / |stress work|",
                   std::abs(e.balance()) / std::abs(e.internal),
                   0.05);
    return r;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  const Result                     off = run(false, "off", checks, comm);
  checks.in_range("off: largest alternation of p along y / scale",
                  off.alt_p / off.scale,
                  0.5,
                  1e3);
  const Result on = run(true, "on", checks, comm);
  checks.at_most("on: largest alternation of p along y / scale",
                 on.alt_p / on.scale,
                 0.1);
  double shift = 0;
  for (int k = 0; k < nz; ++k)
    shift = std::max(shift, std::abs(on.row_mean_p[k] - off.row_mean_p[k]));
  checks.at_most("on against off: largest change of a row mean of p / scale",
                 shift / off.scale,
                 0.1);
  return checks.exit_code();
}
