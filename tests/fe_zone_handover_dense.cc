// The hand-over's test of dense metal on re-solidified metal, a pore and
// unfused powder (FeZoneHandover, fe_zone_handover.h; doc/builds.md
// "Handing cooled metal to finite elements"). A 2D block, 1.6 m x 1.0 m,
// cells of 0.1 m, solid points (2 x 2 per cell) up to y = 0.8 m, finite
// elements below y = 0.2 m; the rows may reach y = 0.7 m (a new layer's
// top at 1.0 m less a margin of 0.3 m).
// Above the zone the points are moved as a melt flow leaves them: in every
// second column of cells the two points of each row lie 0.02 h and 0.98 h
// from the cell's left face (spread apart), in the others 0.26 h and
// 0.74 h (close together), and the same in y by rows. Each point stays in
// its sub-cell, so alpha reads 1 everywhere, while the fill (the points'
// volume under the hat of each cell's centre) alternates between about
// 0.58 and 1.54.
// Checks:
//   - irregular: alpha = 1 in every candidate cell (count), cells with a
//     fill below 0.9 (count, least fill): the fill alone would stop at the
//     zone's top; the choice takes them dense and the zone may rise to the
//     limit, 0.7 m; the points' mass of the handed rows is that of the
//     elements at the full density (1: every point keeps its mass);
//   - a pore: 3 of the 4 points of the cell at x 0.8-0.9 m, y 0.4-0.5 m
//     moved 0.3 m up, into the cell of the block's top row above the
//     limit (not into the gas above: 3 points alone in a cell of gas are
//     no stable body), alpha 1/4 in the pore's cell; the pore
//     detector finds one pore of one cell there. The pore's cell stays
//     points, though its point is solid, below the hand-over temperature
//     and every other cell of its neighbourhood reads alpha = 1 (it would
//     be taken if its own openness were not read); its eight neighbours
//     (x 0.7-1.0 m, y 0.3-0.6 m), whose own sub-cells are all occupied,
//     are taken: 79 of the 80 cells of the rows up to the limit, the
//     zone's top rises to the limit, 0.7 m, the reason names the pore's
//     row (the lowest row above the zone's top with a cell left). Handed
//     over, they leave an island of one cell of points inside the zone
//     (the zone is no longer a box); the solid then runs on (0.25 s, the
//     block under gravity) with its points and elements unchanged in
//     number (the island's coupling against a closed form:
//     fe_zone_mask_thermal). The same choice without the detector's
//     pores is printed: the pore's cell and the neighbours whose fill
//     reads below 0.9 stay points (alpha 1/4 in their neighbourhood);
//   - unfused powder: the points of the cell at x 0.5-0.6 m, y 0.5-0.6 m
//     made powder: the detector takes the cell, enclosed unfused powder
//     (fused fraction 0), for a pore; it stays points (its powder), its
//     eight neighbours are taken (79 of 80 cells, the zone may rise to
//     0.7 m; the reason names the powder cell's row).
// Runs on 1 and 2 ranks against one output.
#include <femp/builds/pore_detector.h>
#include <femp/grid/material_points.h>
#include <femp/solid/fe_zone_handover.h>
#include <femp/solid/solid_sub_cycle.h>

#include "handover_tools.h"

using namespace femp_test;

namespace
{
  constexpr int    dim = 2;
  constexpr double h   = 0.1;

  enum class Defect
  {
    none,
    pore,
    powder
  };

  struct Scene : HandoverChoiceBlock<dim>
  {
    Scene(MPI_Comm comm, const Defect defect)
        : HandoverChoiceBlock<dim>(Point<dim>(1.6, 1.0), h, comm)
    {
      using P = typename MaterialPoints<dim>::PropertyIndex;
      for (auto &particle : block.points->particle_handler_for_update())
        {
          Point<dim> x = particle.get_location();
          if (x[1] < 0.2)
            continue;
          // The pore's cell keeps its point nearest its lower left corner.
          const bool pore_cell = x[0] > 0.8 && x[0] < 0.9 && x[1] > 0.4 &&
                                 x[1] < 0.5 && (x[0] > 0.85 || x[1] > 0.45);
          const bool powder_cell =
            x[0] > 0.5 && x[0] < 0.6 && x[1] > 0.5 && x[1] < 0.6;
          x[0] = melt_flow_placement(x[0], h);
          x[1] = melt_flow_placement(x[1], h);
          if (defect == Defect::pore && pore_cell)
            x[1] += 0.3;
          particle.set_location(x);
          if (defect == Defect::powder && powder_cell)
            particle.get_properties()[P::state] = MaterialPoints<dim>::powder;
        }
      auto sp       = block_supports<dim>();
      sp.gravity[1] = -0.01;
      const auto fp = fe_zone(Point<dim>(0, 0), Point<dim>(1.6, 0.2));
      start(sp, fp);
    }
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
      Scene       dense(comm, Defect::none);
      const auto &grid  = dense.block.grid;
      double      cells = 0, one = 0;
      for (const auto c : grid.owned_cells())
        {
          const double y = grid.cell_center(c)[1];
          if (y > 0.2 && y < 0.7)
            cells += 1, one += std::abs(dense.alpha[c] - 1) < 1e-12;
        }
      checks.print("irregular: cells of the rows 0.2-0.7 m",
                   Utilities::MPI::sum(cells, comm),
                   6);
      checks.print("  of them with alpha = 1",
                   Utilities::MPI::sum(one, comm),
                   6);
      std::string  reason;
      const double top   = dense.choose(reason);
      double       least = 1e9;
      for (const double f : dense.fill)
        least = std::min(least, f);
      checks.in_range("irregular: least fill of the rows 0.2-0.7 m (< 0.9)",
                      least,
                      0.3,
                      0.89);
      checks.print("irregular: the zone may rise to (m)", top, 6);
      print_stop(comm, "irregular", reason);
      // The points' mass of the rows 0.2-0.7 m against the elements' at
      // the full density (the unit material: density 1).
      double m_points = 0;
      for (std::size_t r = 0; r < 5 && r < dense.mass.size(); ++r)
        m_points += dense.mass[r];
      const auto n = dense.solid->hand_over_rows(top);
      checks.print("irregular: elements added", n[0], 6);
      checks.print("irregular: points handed over", n[1], 6);
      checks.in_range("irregular: points' mass / elements' mass",
                      m_points / (n[0] * dense.block.material.density * h * h),
                      1 - 1e-12,
                      1 + 1e-12);

      {
        Scene pore(comm, Defect::pore);
        checks.print("pore: pores found", pore.found.pores.size(), 6);
        checks.print("pore: its cells",
                     pore.found.pores.empty() ? 0 : pore.found.pores[0].n_cells,
                     6);
        checks.print("pore, the detector's pores not read: the zone may rise "
                     "to (m)",
                     pore.choose(reason, false),
                     6);
        print_stop(comm, "pore, the detector's pores not read", reason);
        checks.print("pore, the detector's pores not read: cells taken",
                     pore.cells.size(),
                     6);
        checks.print("pore: the zone may rise to (m)", pore.choose(reason), 6);
        print_stop(comm, "pore", reason);
        checks.in_range("pore: cells taken", pore.cells.size(), 79, 79);
        checks.in_range("pore: of them the pore's cell (x 0.8-0.9 m, y "
                        "0.4-0.5 m)",
                        count_in(pore.cells, 8, 9, 4, 5),
                        0,
                        0);
        checks.in_range("pore: of them its eight neighbours (x 0.7-1.0 m, "
                        "y 0.3-0.6 m)",
                        count_in(pore.cells, 7, 10, 3, 6),
                        8,
                        8);
        checks.in_range("pore: of them above it (x 0.7-1.0 m, y 0.6-0.7 m)",
                        count_in(pore.cells, 7, 10, 6, 7),
                        3,
                        3);
        checks.in_range("pore: cells kept as points for a pore",
                        pore.kept[FeZoneHandover<dim>::pore],
                        1,
                        1);
        const double n0 = pore.solid->sizes()[0];
        const auto   m  = pore.solid->hand_over_cells(pore.cells);
        checks.print("pore: elements added", m[0], 6);
        checks.print("pore: points handed over", m[1], 6);
        checks.in_range("pore: the zone is a box (1 = yes)",
                        pore.solid->fe_zone()->is_box(),
                        0,
                        0);
        checks.in_range("pore: the island's cell in the zone",
                        pore.solid->fe_zone()->contains_cell({{8, 4}}),
                        0,
                        0);
        std::string error;
        try
          {
            for (int s = 1; s <= 5; ++s)
              pore.solid->advance(0.05 * s, pore.T, s == 5);
          }
        catch (const std::exception &e)
          {
            error = e.what();
            if (root)
              std::cerr << error << std::endl;
          }
        checks.at_most("pore: the run after the hand-over stopped (1 = yes)",
                       !error.empty(),
                       0);
        const auto sizes = pore.solid->sizes();
        checks.at_most("pore: |points after the run - before the hand-over "
                       "less those handed over|",
                       std::abs(sizes[0] - (n0 - m[1])),
                       0);
        checks.print("pore: elements after the run", sizes[1], 6);
      }
      {
        Scene powder(comm, Defect::powder);
        checks.print("powder: the zone may rise to (m)",
                     powder.choose(reason),
                     6);
        print_stop(comm, "powder", reason);
        checks.in_range("powder: cells taken", powder.cells.size(), 79, 79);
        checks.in_range("powder: of them the powder cell (x 0.5-0.6 m, "
                        "y 0.5-0.6 m)",
                        count_in(powder.cells, 5, 6, 5, 6),
                        0,
                        0);
        checks.in_range("powder: of them its eight neighbours (x 0.4-0.7 m, "
                        "y 0.4-0.7 m)",
                        count_in(powder.cells, 4, 7, 4, 7),
                        8,
                        8);
      }
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
