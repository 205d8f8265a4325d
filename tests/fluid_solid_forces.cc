// Unit test of FluidSolidForces (the fluid forces on the solid's grid
// nodes): face forces put on the faces of solid cells must reach the
// nodes with their sum unchanged, component by component, when the cells
// are full of solid points (every corner takes its equal share); a cell
// holding only fluid points passes nothing on; inside the FE zone the
// shares are equal whatever the points. 2D and 3D, any number of ranks.

#include <femp/coupling/fluid_solid_forces.h>

#include "test_tools.h"

using namespace femp_test;

template <int dim>
void
run(Checks &checks, MPI_Comm comm)
{
  const double h = 1. / 8;
  Point<dim>   hi;
  for (int d = 0; d < dim; ++d)
    hi[d] = 1;
  BackgroundGrid<dim> grid(box<dim>(Point<dim>(), hi, h), comm);
  grid.create();
  const Material                           mat = unit_material();
  typename MaterialPoints<dim>::Parameters pp;
  pp.point_spacing   = h / 2;
  pp.subcells        = 2;
  pp.layer_thickness = 0;
  MaterialPoints<dim> points(pp, mat, grid);
  // Solid below x_last = 0.5, fluid above.
  points.create_region([](const Point<dim> &x) { return x[dim - 1] < 0.5; },
                       300.,
                       MaterialPoints<dim>::solid);
  typename SolidFEM<dim>::Parameters fe_zone; // no FE zone
  FluidSolidForces<dim>              forces(grid, points, mat.density, fe_zone);

  // A face force on every face of every owned cell: component e of the
  // force through face (d, side) = (1 + d + 2 side) 10^e, in solid cells
  // (centre below 0.5) and in fluid cells (above; they must pass nothing).
  typename FluidSolidForces<dim>::FaceForces F;
  for (auto &f : F)
    f.assign(grid.n_local(), 0.);
  std::array<double, dim> expected{};
  for (const auto c : grid.owned_cells())
    {
      const bool solid = grid.cell_center(c)[dim - 1] < 0.5;
      for (int d = 0; d < dim; ++d)
        for (int side = 0; side < 2; ++side)
          for (int e = 0; e < dim; ++e)
            {
              const double v = (1 + d + 2 * side) * std::pow(10., e);
              F[dim * (2 * d + side) + e][c] = v;
              if (solid)
                expected[e] += v;
            }
    }
  forces.spread(F);
  double worst = 0;
  for (int e = 0; e < dim; ++e)
    {
      double sum = 0;
      for (const double f : forces.nodal_forces()[e])
        sum += f;
      sum             = Utilities::MPI::sum(sum, comm);
      const double ex = Utilities::MPI::sum(expected[e], comm);
      worst           = std::max(worst, std::abs(sum - ex) / ex);
    }
  const std::string D = std::to_string(dim) + "D";
  checks.at_most(D + ": |sum of nodal forces - sum of face forces on solid "
                     "cells| / sum, next power of ten",
                 worst > 0 ? std::pow(10., std::ceil(std::log10(worst))) : 0.,
                 1e-12);

  // One face force on the upper face of the solid cell just below the
  // interface at the middle: only that face's 2^(dim-1) nodes take it, in
  // equal parts.
  for (auto &f : F)
    std::fill(f.begin(), f.end(), 0.);
  Point<dim> x;
  for (int d = 0; d < dim; ++d)
    x[d] = 0.5 - h / 2;
  unsigned int n_loaded = 0;
  double       f_min = 1e300, f_max = 0;
  for (const auto c : grid.owned_cells())
    if (grid.cell_center(c).distance(x) < 1e-12)
      F[dim * (2 * (dim - 1) + 1) + dim - 1][c] = -1.;
  forces.spread(F);
  for (const double f : forces.nodal_forces()[dim - 1])
    if (f != 0)
      {
        ++n_loaded;
        f_min = std::min(f_min, -f);
        f_max = std::max(f_max, -f);
      }
  n_loaded = Utilities::MPI::sum(n_loaded, comm);
  f_min    = Utilities::MPI::min(f_min, comm);
  f_max    = Utilities::MPI::max(f_max, comm);
  checks.in_range(D + ": nodes loaded by one face force",
                  n_loaded,
                  1u << (dim - 1),
                  1u << (dim - 1));
  checks.in_range(D + ": their share (smallest)",
                  f_min,
                  1. / (1u << (dim - 1)) - 1e-12,
                  1. / (1u << (dim - 1)) + 1e-12);
  checks.in_range(D + ": their share (largest)",
                  f_max,
                  1. / (1u << (dim - 1)) - 1e-12,
                  1. / (1u << (dim - 1)) + 1e-12);

  // Inside an FE zone covering the fluid half too, fluid cells take equal
  // shares: the whole sum arrives.
  fe_zone.enabled      = true;
  fe_zone.upper_corner = hi;
  FluidSolidForces<dim> fe_forces(grid, points, mat.density, fe_zone);
  for (auto &f : F)
    std::fill(f.begin(), f.end(), 0.);
  double total = 0;
  for (const auto c : grid.owned_cells())
    F[dim - 1][c] = 1., total += 1.;
  fe_forces.spread(F);
  double sum = 0;
  for (const double f : fe_forces.nodal_forces()[dim - 1])
    sum += f;
  checks.at_most(D + ": FE zone, |sum of nodal forces - sum of face forces|",
                 std::abs(Utilities::MPI::sum(sum, comm) -
                          Utilities::MPI::sum(total, comm)),
                 1e-9);
}

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  run<2>(checks, comm);
  run<3>(checks, comm);
  return checks.exit_code();
}
