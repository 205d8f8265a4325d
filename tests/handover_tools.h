// femp tests: the set-up shared by the tests of the hand-over's choice on a
// block whose points the test has placed (fe_zone_handover_dense,
// fe_zone_handover_subcell_3d, fe_zone_handover_pore_3d,
// fe_zone_handover_surface): the block and its test material, the solid
// with its finite-element zone at 300 K, alpha and the pore detector's
// pores, one choice of FeZoneHandover with what it read, the melt-flow
// placement of a cell's points and a count of chosen cells in a 2D box.
#ifndef femp_handover_tools_h
#define femp_handover_tools_h

#include <femp/builds/pore_detector.h>
#include <femp/grid/material_points.h>
#include <femp/solid/fe_zone_handover.h>
#include <femp/solid/solid_sub_cycle.h>

#include <array>
#include <cmath>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "solid_tools.h"

namespace femp_test
{
  /// Coordinate @p x of a point in cells of size @p h, moved as a melt
  /// flow leaves the points: a cell's two point rows 0.02 h and 0.98 h
  /// from its lower face in even cells (spread apart), 0.26 h and 0.74 h
  /// in odd ones (close together).
  inline double
  melt_flow_placement(const double x, const double h)
  {
    const double cell = std::floor(x / h);
    const double o    = x / h - cell;
    const bool   even = int(cell) % 2 == 0;
    return (cell + (o < 0.5 ? (even ? 0.02 : 0.26) : (even ? 0.98 : 0.74))) * h;
  }

  /// Of the 2D @p cells, those inside the cells [@p i0, @p i1) x
  /// [@p j0, @p j1).
  inline double
  count_in(const std::vector<std::array<int, 2>> &cells,
           const int                              i0,
           const int                              i1,
           const int                              j0,
           const int                              j1)
  {
    double n = 0;
    for (const auto &c : cells)
      n += c[0] >= i0 && c[0] < i1 && c[1] >= j0 && c[1] < j1;
    return n;
  }

  /// On rank 0 of @p comm: why the choice @p what stopped below its
  /// limit (@p reason; empty: it reached the limit).
  inline void
  print_stop(MPI_Comm comm, const std::string &what, const std::string &reason)
  {
    if (Utilities::MPI::this_mpi_process(comm) == 0)
      std::cout << what
                << ": stopped by: " << (reason.empty() ? "the limit" : reason)
                << std::endl;
  }

  /// A block of @p size, cells of @p h, solid points up to 0.8 m of the
  /// elastic-plastic test material (yield 0.02 Pa at 300 K, 0.005 Pa at
  /// 400 K, Poisson 0.3). The test places its points, then calls start().
  template <int dim>
  struct HandoverChoiceBlock
  {
    HandoverChoiceBlock(const Point<dim> &size, const double h, MPI_Comm comm)
        : block(size, h, 0.8, unit_material(), comm)
        , sm(block_material("300:0.02, 400:0.005", block.material))
    {
      sm.poisson_ratio = 0.3;
    }

    /// After the points were placed: the solid with supports @p sp and
    /// the FE zone @p fp at 300 K, alpha, and the pore detector's pores.
    void
    start(const typename SolidSubCycle<dim>::Parameters &sp,
          const typename SolidFEM<dim>::Parameters      &fp)
    {
      block.points->points_moved();
      solid = std::make_unique<SolidSubCycle<dim>>(
        sp, fp, sm, block.grid, *block.points);
      T = block.grid.make_field(300.);
      solid->initialize(T, "");
      alpha = block.points->metal_fraction();
      typename PoreDetector<dim>::Parameters pp;
      PoreDetector<dim>                      detector(pp, block.grid, 0.2);
      const auto                             shares =
        PoreDetector<dim>::powder_shares(block.grid,
                                         *block.points,
                                         block.material.solidus,
                                         block.material.liquidus);
      found = detector.find(alpha, &shares.first);
    }

    /// start() for the 3D blocks 0.6 m x 0.6 m: the bottom fixed, rollers
    /// on the four sides, gravity 0.01 m/s^2 down, the FE zone below
    /// z = 0.2 m.
    void
    start_box_3d()
    {
      static_assert(dim == 3, "a 3D block");
      auto sp         = block_supports<dim>();
      sp.fixed_faces  = {"z-"};
      sp.roller_faces = {"x-", "x+", "y-", "y+"};
      sp.gravity[2]   = -0.01;
      start(sp, fe_zone(Point<dim>(0, 0, 0), Point<dim>(0.6, 0.6, 0.2)));
    }

    /// The new top the hand-over may rise to under a layer top of 1.0 m,
    /// margin 0.3 m (hand-over temperature 1000 K), with or without the
    /// detector's pores; @p reason: why the choice stopped below the
    /// limit. What the choice read is kept below. The powder top's line
    /// alone ('Hand-over surface limit = false'): the block's metal top,
    /// 0.8 m, lies 0.2 m under the layer top with no melt observed, so that
    /// the surface line (0.8 m less the margin) would stop the choice below
    /// the rows these tests of dense metal read
    /// (fe_zone_handover_surface tests the surface line).
    double
    choose(std::string &reason, const bool pores = true)
    {
      typename FeZoneHandover<dim>::Parameters hp;
      hp.enabled       = true;
      hp.temperature   = 1000;
      hp.margin        = 0.3;
      hp.surface_limit = false;
      FeZoneHandover<dim> choice(hp, block.grid, block.material.solidus, 0.8);
      const double        top =
        choice.choose_top(1.0,
                          *block.points,
                          solid->fe_zone_cells(),
                          std::vector<double>(),
                          alpha,
                          pores ? found.pore_number : std::vector<double>());
      reason     = choice.stop_reason();
      fill       = choice.least_fill();
      mass       = choice.row_point_mass();
      cells      = choice.chosen_cells();
      cells_mass = choice.chosen_point_mass();
      kept       = choice.kept_cells();
      return top;
    }

    SolidBlock<dim>                     block;
    SolidMaterial                       sm; ///< reads block.material
    std::unique_ptr<SolidSubCycle<dim>> solid;
    std::vector<double>                 T, alpha;
    typename PoreDetector<dim>::Result  found;
    /// The least fill and the points' mass of each row the last choose()
    /// looked at.
    std::vector<double> fill, mass;
    /// The cells the last choose() took and their points' mass, and the
    /// cells it kept as points, per class.
    std::vector<std::array<int, dim>>               cells;
    double                                          cells_mass = 0;
    std::array<double, FeZoneHandover<dim>::n_kept> kept{};
  };
} // namespace femp_test

#endif
