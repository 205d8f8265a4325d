// The mass of the hand-over's new elements when their cells' points carry
// more or less mass than the full density (SolidSubCycle::hand_over_cells(),
// SolidFEM::mass(); doc/builds.md "Handing cooled metal to finite elements",
// "Mass"). A 2D block, 1.6 m x 1.0 m, cells of 0.1 m, solid points (2 x 2
// per cell) up to y = 0.8 m, finite elements below y = 0.2 m, the unit
// material (density 1). The points are moved as a melt
// flow leaves re-solidified metal: in every even column of cells the
// lower left point of the cell at y 0.4-0.5 m moves down into the cell
// below (5 points there: bunched), in the columns 1, 5, 9 and 13 the upper
// left point of the cell at y 0.3-0.4 m moves up into the cell above (3
// points there). The rows y 0.2-0.4 m (32 cells) are handed over.
// Checks:
//   - the handed points' mass over that of the elements at the full
//     density, both from the points (132 of 128 lattice points: 1.03125);
//   - the zone's mass before, over 32 cells at the full density: 1;
//   - the zone's mass added (SolidFEM::mass(), the lumped masses over the
//     mass-scaling factor) over the elements added at the full density: 1
//     to round-off, whatever the points' mass: each element carries the
//     material's density over its cell, the bunched cell as the sparse one
//     (the solid's stable step, set by the material's density, holds for
//     every element); the solid's mass changes by the difference (printed);
//   - the solid runs on (0.25 s, the block under gravity) with its points
//     and elements unchanged in number.
// Runs on 1 and 2 ranks against one output.
#include <femp/grid/material_points.h>
#include <femp/solid/solid_sub_cycle.h>

#include "solid_tools.h"

using namespace femp_test;

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  constexpr int                    dim = 2;
  constexpr double                 h   = 0.1;
  const bool root = Utilities::MPI::this_mpi_process(comm) == 0;
  try
    {
      SolidBlock<dim> block(
        Point<dim>(1.6, 1.0), h, 0.8, unit_material(), comm);
      SolidMaterial sm = block_material("300:0.02, 400:0.005", block.material);
      sm.poisson_ratio = 0.3;
      using P          = typename MaterialPoints<dim>::PropertyIndex;
      for (auto &particle : block.points->particle_handler_for_update())
        {
          Point<dim>   x    = particle.get_location();
          const int    i    = int(std::floor(x[0] / h));
          const double left = x[0] - i * h;
          if (left > 0.5 * h)
            continue;
          if (i % 2 == 0 && std::abs(x[1] - 0.425) < 1e-9)
            x[1] = 0.39; // into the cell below: 5 points there
          else if (i % 4 == 1 && std::abs(x[1] - 0.375) < 1e-9)
            x[1] = 0.41; // into the cell above: 3 points left below
          else
            continue;
          particle.set_location(x);
        }
      block.points->points_moved();
      auto sp                = block_supports<dim>();
      sp.gravity[1]          = -0.01;
      const auto          fp = fe_zone(Point<dim>(0, 0), Point<dim>(1.6, 0.2));
      SolidSubCycle<dim>  solid(sp, fp, sm, block.grid, *block.points);
      std::vector<double> T = block.grid.make_field(300.);
      solid.initialize(T, "");

      const double                      rho_h = block.material.density * h * h;
      std::vector<std::array<int, dim>> cells;
      for (int j = 2; j < 4; ++j)
        for (int i = 0; i < 16; ++i)
          cells.push_back({{i, j}});
      // The points' mass of the handed cells (and the bunched and sparse
      // cells among them).
      double m_points = 0, bunched = 0, sparse = 0;
      {
        std::map<std::pair<int, int>, int> per_cell;
        for (const auto &particle : block.points->particle_handler())
          {
            const Point<dim> x = particle.get_location();
            if (x[1] > 0.2 && x[1] < 0.4)
              {
                m_points += particle.get_properties()[P::mass];
                per_cell[{int(std::floor(x[0] / h)),
                          int(std::floor(x[1] / h))}] += 1;
              }
          }
        for (const auto &[c, n] : per_cell)
          bunched += n > 4, sparse += n < 4;
      }
      m_points = Utilities::MPI::sum(m_points, comm);
      checks.print("cells of 5 points among the handed",
                   Utilities::MPI::sum(bunched, comm),
                   6);
      checks.print("cells of 3 points among the handed",
                   Utilities::MPI::sum(sparse, comm),
                   6);
      const double m0 = solid.fe_zone_mass();
      checks.in_range("the zone's mass before / (32 cells x rho h^2)",
                      m0 / (32 * rho_h),
                      1 - 1e-12,
                      1 + 1e-12);
      const double n0 = solid.sizes()[0];
      const auto   n  = solid.hand_over_cells(cells);
      checks.print("elements added", n[0], 6);
      checks.print("points handed over", n[1], 6);
      checks.in_range("the handed points' mass / (elements x rho h^2)",
                      m_points / (n[0] * rho_h),
                      1.03125 - 1e-12,
                      1.03125 + 1e-12);
      const double added = solid.fe_zone_mass() - m0;
      checks.in_range("the zone's mass added / (elements x rho h^2)",
                      added / (n[0] * rho_h),
                      1 - 1e-12,
                      1 + 1e-12);
      checks.print("the solid's mass change (zone added - points handed) / "
                   "(rho h^2)",
                   (added - m_points) / rho_h,
                   6);
      std::string error;
      try
        {
          for (int s = 1; s <= 5; ++s)
            solid.advance(0.05 * s, T, s == 5);
        }
      catch (const std::exception &e)
        {
          error = e.what();
          if (root)
            std::cerr << error << std::endl;
        }
      checks.at_most("the run after the hand-over stopped (1 = yes)",
                     !error.empty(),
                     0);
      const auto sizes = solid.sizes();
      checks.at_most("|points after the run - before the hand-over less "
                     "those handed over|",
                     std::abs(sizes[0] - (n0 - n[1])),
                     0);
      checks.print("elements after the run", sizes[1], 6);
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
