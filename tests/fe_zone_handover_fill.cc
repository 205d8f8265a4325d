// The row choice of the hand-over to finite elements on a point lattice
// moved against the grid, and the points left on the new top
// (FeZoneHandover, fe_zone_handover.h; SolidMPM::hold_on_zone_face();
// doc/builds.md "Handing cooled metal to finite elements"). A 2D block,
// 1.6 m x 1.0 m, cells of 0.1 m, solid points (2 x 2 per cell) up to
// y = 0.8 m, finite elements below y = 0.2 m. Every point is moved within
// its cell so that its two point rows lie 0.02 h and 0.48 h above the
// cell's bottom: both in the lower sub-cell row (alpha = 1/2, as in dense
// metal whose lattice moved by about half a spacing), the lower one just
// above each grid line. The rows may reach y = 0.7 m (a new layer's top at
// 1.0 m less a margin of 0.3 m).
// Checks:
//   - dense scene: alpha = 1/2 in every cell of the rows 0.2-0.7 m, their
//     fill (the points' volume under the hat of each cell's centre) 1: the
//     zone may rise to the limit, 0.7 m (5 rows);
//   - the same with a pore: the 4 points of the cell at x 0.8-0.9 m,
//     y 0.4-0.5 m moved into the gas above the block. The pore's lower
//     points lay on the face to the cell below, so that cell loses too
//     (fill 13/16); the reason names that row (at 0.3 m), and the cells
//     around the two are taken up to the limit: the zone's top may rise
//     to 0.7 m, the two cells left as points inside it;
//   - the dense scene handed over to 0.7 m (80 elements, 320 points), then
//     cooled from 300 K to 200 K in 0.5 s (alpha = 1e-4 1/K): the zone
//     contracts, and the points 0.02 h above its new top follow its top
//     nodes across the grid line. The run goes on: the points are held on
//     the top face (at least once; on no lateral face, the zone spans the
//     block's width), none leaves the solid, and the energy balance stays
//     within 0.05 of the stress work (the tolerance of fe_zone_handover);
//   - a zone that expands beneath dense metal: an elastic block (yield
//     stress 1e30 Pa), rows to 0.4 m handed over, the zone warmed by 350 K
//     in 0.5 s (the metal above stays at 300 K): its top face rises by
//     more than 0.1 h (SolidSubCycle::zone_top_lift()) and the points above
//     with it. With the zone's points where the hand-over left them the
//     row at 0.4 m reads a gap (0.87, printed); with the zone's top row
//     moved by the lift it reads 1 (0.97-1.03) and the zone may rise to
//     the limit, 0.7 m.
// Runs on 1 and 2 ranks against one output.
#include <femp/grid/material_points.h>
#include <femp/solid/fe_zone_handover.h>
#include <femp/solid/solid_sub_cycle.h>

#include "solid_tools.h"

using namespace femp_test;

namespace
{
  constexpr int    dim = 2;
  constexpr double h   = 0.1;

  /// The block with its point rows at 0.02 h and 0.48 h in each cell; with
  /// @p pore, the points of the cell (8, 4) moved 0.5 m up, into the gas;
  /// @p yield: the yield stress table (Pa over K).
  struct Scene
  {
    Scene(MPI_Comm           comm,
          const bool         pore,
          const std::string &yield = "300:0.02, 400:0.005")
        : block(Point<dim>(1.6, 1.0), h, 0.8, unit_material(), comm)
        , sm(block_material(yield, block.material))
    {
      sm.poisson_ratio = 0.3;
      for (auto &particle : block.points->particle_handler_for_update())
        {
          Point<dim>   x    = particle.get_location();
          const double cell = std::floor(x[1] / h);
          const double o    = x[1] / h - cell;
          x[1]              = (cell + (o < 0.5 ? 0.02 : 0.48)) * h;
          if (pore && cell == 4 && x[0] > 0.8 && x[0] < 0.9)
            x[1] += 0.5;
          particle.set_location(x);
        }
      block.points->points_moved();
      auto sp       = block_supports<dim>();
      sp.gravity[1] = -0.01;
      const auto fp = fe_zone(Point<dim>(0, 0), Point<dim>(1.6, 0.2));
      solid         = std::make_unique<SolidSubCycle<dim>>(
        sp, fp, sm, block.grid, *block.points);
      T = block.grid.make_field(300.);
      solid->initialize(T, "");
    }
    /// The new top the hand-over may rise to under a layer top of 1.0 m,
    /// margin 0.3 m; @p reason: why the choice stopped below the limit.
    /// The powder top's line alone ('Hand-over surface limit = false'):
    /// the block's metal top, 0.8 m, lies 0.2 m under the layer top with
    /// no melt observed, so that the surface line (0.8 m less the margin)
    /// would stop the choice below the rows this test reads
    /// (fe_zone_handover_surface tests the surface line).
    double
    choose(std::string &reason)
    {
      typename FeZoneHandover<dim>::Parameters hp;
      hp.enabled       = true;
      hp.temperature   = 1000;
      hp.margin        = 0.3;
      hp.surface_limit = false;
      FeZoneHandover<dim> choice(hp, block.grid, block.material.solidus, 0.8);
      const double        top = choice.choose_top(1.0,
                                           *block.points,
                                           solid->fe_zone_cells(),
                                           with_lift ? solid->zone_top_lift() :
                                                              std::vector<double>(),
                                           block.points->metal_fraction(),
                                           std::vector<double>());
      reason                  = choice.stop_reason();
      fill                    = choice.least_fill();
      return top;
    }
    /// Whether choose() reads the zone's top-face displacement (false: the
    /// zone's points where the hand-over left them).
    bool with_lift = true;
    /// The least fill of each row the last choose() looked at.
    std::vector<double>                 fill;
    SolidBlock<dim>                     block;
    SolidMaterial                       sm; ///< reads block.material
    std::unique_ptr<SolidSubCycle<dim>> solid;
    std::vector<double>                 T;
  };
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  const bool root = Utilities::MPI::this_mpi_process(comm) == 0;
  try
    {
      Scene       dense(comm, false);
      const auto &grid = dense.block.grid;
      // alpha in the candidate rows.
      const auto alpha = dense.block.points->metal_fraction();
      double     half = 0, cells = 0;
      for (const auto c : grid.owned_cells())
        {
          const double y = grid.cell_center(c)[1];
          if (y > 0.2 && y < 0.7)
            cells += 1, half += std::abs(alpha[c] - 0.5) < 1e-12;
        }
      checks.print("dense, moved lattice: cells of the rows 0.2-0.7 m",
                   Utilities::MPI::sum(cells, comm),
                   6);
      checks.print("  of them with alpha = 1/2",
                   Utilities::MPI::sum(half, comm),
                   6);
      std::string reason;
      checks.print("dense: the zone may rise to (m)", dense.choose(reason), 6);
      if (root)
        std::cout << "dense: stopped by: "
                  << (reason.empty() ? "the limit" : reason) << std::endl;

      {
        Scene pore(comm, true);
        checks.print("pore: the zone may rise to (m)", pore.choose(reason), 6);
        if (root)
          std::cout << "pore: stopped by: " << reason << std::endl;
      }

      // The dense rows handed over, then cooled.
      const auto moved = dense.solid->hand_over_rows(0.7);
      checks.print("elements added", moved[0], 6);
      checks.print("points handed over", moved[1], 6);
      const double n0 = dense.solid->sizes()[0];
      for (int s = 1; s <= 10; ++s)
        {
          const double t = 0.05 * s;
          dense.T        = grid.make_field(300. - 10. * s);
          dense.solid->advance(t, dense.T, s == 10);
        }
      const double n1 = dense.solid->sizes()[0];
      checks.print("solid points after the hand-over", n0, 6);
      checks.at_most("|solid points after cooling - before|",
                     std::abs(n1 - n0),
                     0);
      checks.in_range("points held on the zone's top face (times, >= 1)",
                      std::min<double>(dense.solid->n_points_held_at_zone_top(),
                                       1.),
                      1,
                      1);
      checks.at_most("points held on a lateral face (the zone spans the "
                     "block's width: none)",
                     dense.solid->n_points_held_at_zone_lateral(),
                     0);
      const auto e = dense.solid->energies();
      checks.at_most("energy balance / stress work",
                     std::abs(e.balance() / e.internal),
                     0.05);

      // A zone that expands beneath dense metal: an elastic block (yield
      // stress 1e30 Pa), rows to 0.4 m handed over, then the zone warmed
      // from 300 K to 650 K in 0.5 s (the metal above stays at 300 K). The
      // zone's top moves up and the points above with it; the zone's points
      // stay where the hand-over left them.
      {
        Scene       warm(comm, false, "1e30");
        const auto &grid  = warm.block.grid;
        const auto  moved = warm.solid->hand_over_rows(0.4);
        checks.print("warm: elements added", moved[0], 6);
        for (int s = 1; s <= 10; ++s)
          {
            for (std::size_t c = 0; c < warm.T.size(); ++c)
              warm.T[c] = grid.cell_center(c)[1] < 0.4 ? 300. + 35. * s : 300.;
            warm.solid->advance(0.05 * s, warm.T, s == 10);
          }
        const auto lift  = warm.solid->zone_top_lift();
        double     least = 1e9, most = 0;
        for (const double l : lift)
          least = std::min(least, l), most = std::max(most, l);
        checks.in_range("warm: least lift of the zone's top / h (> 0.1)",
                        least / h,
                        0.1,
                        1);
        checks.print("warm: largest lift of the zone's top / h", most / h, 2);
        std::string reason;
        warm.with_lift = false;
        warm.choose(reason);
        checks.print(
          "warm, the zone's points unmoved: fill of the row at 0.4 m",
          warm.fill.at(0),
          2);
        warm.with_lift = true;
        checks.print("warm: the zone may rise to (m)", warm.choose(reason), 6);
        if (root)
          std::cout << "warm: stopped by: "
                    << (reason.empty() ? "the limit" : reason) << std::endl;
        checks.in_range("warm: fill of the row at 0.4 m (dense: 1)",
                        warm.fill.at(0),
                        0.97,
                        1.03);
      }
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
