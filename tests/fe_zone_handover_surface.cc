// The hand-over's surface line on a ragged metal surface (FeZoneHandover,
// fe_zone_handover.h; doc/builds.md "Handing cooled metal to finite
// elements"). A 2D block, 1.6 m x 1.0 m, cells of 0.1 m, solid points
// (2 x 2 per cell, 300 K) up to y = 0.8 m, finite elements below
// y = 0.2 m. The column x 0.7-0.8 m holds a hollow of the new layer's
// powder from y = 0.5 m up (its points made powder): there the metal
// surface lies 0.5 m below the new powder top (1.0 m), deeper than the
// deepest fusion plus the margin (0.4 m).
// The first layer (powder top 0.8 m on a metal surface at 0.6 m) melts
// the cells 0.5-0.8 m of every column (temperature above the solidus):
// its fusion depth D = 0.3 m, its penetration below the surface it met
// P = 0.1 m. At the second layer's start (powder top 1.0 m, margin
// 0.1 m, surface window 0.1 m: one column each side):
//   - the powder top's line alone ('Hand-over surface limit = false'):
//     rows up to 1.0 - 0.3 - 0.1 = 0.6 m; in the hollow's column it takes
//     the cells 0.2-0.5 m, whose top cell is the metal surface under the
//     powder (the melt of the new layer, as deep as P below the surface,
//     reaches it);
//   - with the surface line (the default): the lowest surface within the
//     window is 0.5 m for the columns x 0.6-0.9 m, so they take rows up
//     to 0.5 - 0.1 - 0.1 = 0.3 m only: no cell of the hollow's column
//     above 0.3 m is taken, the other columns reach 0.6 m as before;
//     the cells of the three columns at 0.3-0.6 m count as kept above
//     the limit.
// Runs on 1 and 2 ranks against one output.
#include <femp/solid/fe_zone_handover.h>

#include "handover_tools.h"

using namespace femp_test;

namespace
{
  constexpr int    dim = 2;
  constexpr double h   = 0.1;
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  try
    {
      HandoverChoiceBlock<dim> scene(Point<dim>(1.6, 1.0), h, comm);
      using P = typename MaterialPoints<dim>::PropertyIndex;
      for (auto &particle : scene.block.points->particle_handler_for_update())
        {
          const Point<dim> x = particle.get_location();
          if (x[0] > 0.7 && x[0] < 0.8 && x[1] > 0.5)
            particle.get_properties()[P::state] = MaterialPoints<dim>::powder;
        }
      auto sp       = block_supports<dim>();
      sp.gravity[1] = -0.01;
      scene.start(sp, fe_zone(Point<dim>(0, 0), Point<dim>(1.6, 0.2)));
      const auto &grid = scene.block.grid;

      for (const bool surface : {false, true})
        {
          const std::string what =
            surface ? "surface line" : "powder top's line alone";
          typename FeZoneHandover<dim>::Parameters hp;
          hp.enabled        = true;
          hp.temperature    = 1000;
          hp.margin         = 0.1;
          hp.surface_limit  = surface;
          hp.surface_window = 0.1;
          FeZoneHandover<dim> choice(
            hp, grid, scene.block.material.solidus, 0.8, 0.6);
          // The first layer melts the cells 0.5-0.8 m of every column.
          std::vector<double> T = grid.make_field(300.);
          for (const auto c : grid.owned_cells())
            {
              const double y = grid.cell_center(c)[1];
              if (y > 0.5 && y < 0.8)
                T[c] = scene.block.material.solidus + 10;
            }
          choice.observe(T, scene.alpha);
          const double top = choice.choose_top(1.0,
                                               *scene.block.points,
                                               scene.solid->fe_zone_cells(),
                                               std::vector<double>(),
                                               scene.alpha,
                                               std::vector<double>());
          checks.print(what + ": deepest fusion D (m)",
                       choice.deepest_fusion(),
                       6);
          checks.print(what + ": penetration depth P (m)",
                       choice.kept_penetration(),
                       6);
          checks.print(what + ": the powder top's line (m)", choice.limit(), 6);
          const auto &s = choice.metal_surface();
          checks.print(what + ": metal surface within the window, column "
                              "x 0.4-0.5 m (m)",
                       s.at(4),
                       6);
          checks.print(what + ": metal surface within the window, column "
                              "x 0.6-0.7 m (m)",
                       s.at(6),
                       6);
          checks.print(what + ": metal surface within the window, column "
                              "x 0.7-0.8 m (m)",
                       s.at(7),
                       6);
          checks.print(what + ": the zone may rise to (m)", top, 6);
          print_stop(comm, what, choice.stop_reason());
          const auto &cells = choice.chosen_cells();
          checks.print(what + ": cells taken", cells.size(), 6);
          checks.print(what + ": of them in the hollow's column x 0.7-0.8 m",
                       count_in(cells, 7, 8, 0, 10),
                       6);
          checks.print(what + ": of them in the columns x 0.6-0.9 m above "
                              "0.3 m",
                       count_in(cells, 6, 9, 3, 10),
                       6);
          checks.print(what + ": of them in the columns x 0.9-1.6 m",
                       count_in(cells, 9, 16, 0, 10),
                       6);
          checks.print(what + ": cells kept above the limit",
                       choice.kept_cells()[FeZoneHandover<dim>::above_limit],
                       6);
          if (surface)
            {
              checks.in_range(
                "surface line: the hollow's metal surface cell "
                "(x 0.7-0.8 m, y 0.4-0.5 m) and the cell under it kept",
                count_in(cells, 7, 8, 3, 5),
                0,
                0);
              checks.in_range("surface line: the columns x 0.6-0.9 m take "
                              "the row 0.2-0.3 m only",
                              count_in(cells, 6, 9, 2, 10),
                              3,
                              3);
              checks.in_range("surface line: the columns x 0.9-1.6 m reach "
                              "the powder top's line (4 rows)",
                              count_in(cells, 9, 16, 2, 6),
                              28,
                              28);
            }
        }
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
