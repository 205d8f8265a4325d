// The hand-over's re-heating rule (FeZoneHandover, 'Build/Hand-over rule =
// re-heating'; doc/builds.md "Handing cooled metal to finite elements"):
// a dense, solid cell is handed over only if its hottest point plus the
// largest temperature rise seen at its depth below the top in the finished
// layers stays below the solidus less 'Re-heating margin'.
// A 2D block, 1.6 m x 1.2 m, cells of 0.1 m, solid points (2 x 2 per cell)
// filling it, finite elements below y = 0.2 m; solidus 1700 K, margin
// 100 K; the depth line (no melt, margin 0) lies at the new top, 1.0 m.
//   - a first layer of top 0.9 m is observed: its cells start at
//     T0 = 400 + 100 y/m K and rise by R(k) g(x), R(k) = 1500 / (1 + k) K
//     at k whole cells below its top (the cell's centre), g = 1 in one
//     column, 1/2 elsewhere, then cool to T0 + 0.7 R(k) g(x): the largest
//     rise per depth is R(k), relative to each cell's own start;
//   - at the second layer's start (top 1.0 m) the points read
//     300 + 600 y/m + 200 x/m K (hotter upwards and to the right);
//   - the test computes each cell's predicted peak, its hottest point plus
//     R at its depth below the new top, and replays the first layer's
//     rise on the cells one cell deeper (the new layer's melt as the
//     old's): the cells the rule hands over must all stay below the
//     solidus less the margin under that replay, and every cell whose
//     peak stays 1 K or more below that line (all connected to the zone:
//     the temperatures rise upwards in every column) must be handed over;
//   - the temperature rule at 1000 K on the same scene hands over cells
//     that the replay heats to or above that line (printed);
//   - a negative re-heating margin is refused naming the parameter.
// Runs on 1 and 2 ranks against one output.
#include <femp/base/input_checks.h>
#include <femp/grid/material_points.h>
#include <femp/solid/fe_zone_handover.h>
#include <femp/solid/solid_sub_cycle.h>

#include <set>

#include "solid_tools.h"

using namespace femp_test;

namespace
{
  constexpr int    dim      = 2;
  constexpr double h        = 0.1;
  constexpr double solidus  = 1700;
  constexpr double margin   = 100;
  constexpr double top_1    = 0.9;
  constexpr double top_2    = 1.0;
  constexpr int    n_column = 16;

  /// The largest rise k whole cells below a layer's top, K.
  double
  rise(const int k)
  {
    return 1500. / (1 + k);
  }

  /// A cell's temperature at the second layer's start, K.
  double
  now(const double x, const double y)
  {
    return 300 + 600 * y + 200 * x;
  }

  /// Whole cells from the cell centre @p y below @p top (-1: above it).
  int
  depth_below(const double top, const double y)
  {
    const double below = (top - y) / h;
    return below < 0 ? -1 : int(std::floor(below + 1e-9));
  }
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
      SolidBlock<dim> block(
        Point<dim>(1.6, 1.2), h, 1.2, unit_material(), comm);
      SolidMaterial sm = block_material("300:0.02, 400:0.005", block.material);
      sm.poisson_ratio = 0.3;
      const auto         fp = fe_zone(Point<dim>(0, 0), Point<dim>(1.6, 0.2));
      SolidSubCycle<dim> solid(
        block_supports<dim>(), fp, sm, block.grid, *block.points);
      std::vector<double> T = block.grid.make_field(300.);
      solid.initialize(T, "");
      const auto  alpha = block.points->metal_fraction();
      const auto &grid  = block.grid;

      // The points' temperatures at the second layer's start.
      using P = typename MaterialPoints<dim>::PropertyIndex;
      for (auto &particle : block.points->particle_handler_for_update())
        {
          const Point<dim> x  = particle.get_location();
          const double     cx = (std::floor(x[0] / h) + 0.5) * h,
                       cy     = (std::floor(x[1] / h) + 0.5) * h;
          particle.get_properties()[P::temperature] = now(cx, cy);
        }

      // The first layer: its start, its peak, its cooling.
      auto layer_1 = [&](FeZoneHandover<dim> &choice) {
        std::vector<double> T0 = grid.make_field(0.), Tl = T0;
        for (const auto c : grid.owned_cells())
          T0[c] = 400 + 100 * grid.cell_center(c)[1];
        choice.observe(T0, alpha);
        for (const double share : {1., 0.7})
          {
            for (const auto c : grid.owned_cells())
              {
                const auto   x = grid.cell_center(c);
                const int    k = depth_below(top_1, x[1]);
                const double g = x[0] > 0.8 && x[0] < 0.9 ? 1. : 0.5;
                Tl[c]          = T0[c] + (k >= 0 ? share * rise(k) * g : 0.);
              }
            choice.observe(Tl, alpha);
          }
      };
      auto make = [&](const bool reheat) {
        typename FeZoneHandover<dim>::Parameters hp;
        hp.enabled       = true;
        hp.temperature   = 1000;
        hp.margin        = 0;
        hp.reheat_margin = margin;
        hp.rule = reheat ? FeZoneHandover<dim>::Parameters::Rule::reheating :
                           FeZoneHandover<dim>::Parameters::Rule::temperature;
        hp.check(solidus, true, true, true, true);
        return hp;
      };

      // The test's own prediction per cell of the rows 0.2-1.0 m: the
      // replayed peak of the new layer (a cell k cells below the new top
      // rises as the cells k cells below the old one did, by at most
      // R(k)).
      auto peak = [&](const std::array<int, dim> &c) {
        const double x = (c[0] + 0.5) * h, y = (c[1] + 0.5) * h;
        return now(x, y) + rise(depth_below(top_2, y));
      };
      for (const bool reheat : {true, false})
        {
          const std::string   rule = reheat ? "re-heating" : "temperature";
          const auto          hp   = make(reheat);
          FeZoneHandover<dim> choice(hp, grid, solidus, top_1);
          layer_1(choice);
          const double                   new_top = choice.choose_top(top_2,
                                                   *block.points,
                                                   solid.fe_zone_cells(),
                                                   std::vector<double>(),
                                                   alpha,
                                                   std::vector<double>());
          std::set<std::array<int, dim>> taken(choice.chosen_cells().begin(),
                                               choice.chosen_cells().end());
          double                         melts = 0, hottest = 0, missed = 0;
          for (int j = 2; j < 10; ++j)
            for (int i = 0; i < n_column; ++i)
              {
                const std::array<int, dim> c{{i, j}};
                const double               p = peak(c);
                if (taken.count(c))
                  {
                    melts += p >= solidus - margin;
                    hottest = std::max(hottest, p);
                  }
                else if (p < solidus - margin - 1)
                  missed += 1;
              }
          if (root)
            std::cout << rule << ": "
                      << (choice.stop_reason().empty() ?
                            std::string("stopped by the limit") :
                            choice.stop_reason())
                      << std::endl;
          checks.print(rule + ": cells taken", taken.size(), 6);
          checks.print(rule + ": the zone may rise to (m)", new_top, 6);
          checks.print(rule + ": hottest replayed peak of a cell taken (K)",
                       hottest,
                       6);
          if (reheat)
            {
              checks.in_range("re-heating: the envelope 1 cell below the "
                              "top (K), R(1)",
                              choice.rise_envelope()[1],
                              rise(1) - 1e-9,
                              rise(1) + 1e-9);
              checks.in_range("re-heating: the envelope 5 cells below the "
                              "top (K), R(5)",
                              choice.rise_envelope()[5],
                              rise(5) - 1e-9,
                              rise(5) + 1e-9);
              checks.at_most("re-heating: cells taken whose replayed peak "
                             "reaches the solidus less the margin",
                             melts,
                             0);
              checks.at_most("re-heating: cells kept whose replayed peak "
                             "stays 1 K or more below it",
                             missed,
                             0);
              checks.in_range("re-heating: the rule's largest prediction "
                              "of a cell taken against the test's (K)",
                              choice.handed_peak_prediction() - hottest,
                              -1e-9,
                              1e-9);
            }
          else
            checks.in_range("temperature: cells taken whose replayed peak "
                            "reaches the solidus less the margin (> 0)",
                            melts,
                            1,
                            1e9);
        }

      // Bad input.
      auto hp          = make(true);
      hp.reheat_margin = -5;
      std::string error;
      try
        {
          hp.check(solidus, true, true, true, true);
        }
      catch (const std::exception &e)
        {
          error = e.what();
        }
      checks.in_range("a negative re-heating margin refused naming "
                      "'Build/Re-heating margin' (1 = yes)",
                      error.find("Build/Re-heating margin") !=
                        std::string::npos,
                      1,
                      1);
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
