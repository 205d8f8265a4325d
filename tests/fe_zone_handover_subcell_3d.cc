// The hand-over's test of dense metal in 3D, where a cell has 8 sub-cells
// (FeZoneHandover, fe_zone_handover.h; doc/builds.md "Handing cooled metal
// to finite elements", "Limits"). A 3D block, 0.6 m x 0.6 m x 1.0 m, cells
// of 0.1 m, solid points (2 x 2 x 2 per cell, on the unmoved lattice) up to
// z = 0.8 m, finite elements below z = 0.2 m; the rows may reach z = 0.7 m
// (a new layer's top at 1.0 m less a margin of 0.3 m).
// Checks, with 0, 1 and 2 points of the cell at x, y 0.3-0.4 m, z 0.4-0.5 m
// moved into the gas above the block (each leaves its sub-cell empty):
//   - the cell's metal fraction alpha (1, 0.875, 0.75) and its fill;
//   - the pore detector finds no pore (fused fraction above one half);
//   - none: the zone may rise to the limit, 0.7 m, and the handed points'
//     mass is the elements' at the full density;
//   - one empty sub-cell: alpha refuses the cells around it, but its
//     cell's fill (0.95) and theirs pass the 0.9 threshold, so the zone
//     still rises to the limit: the hand-over takes a void of an eighth of
//     a cell into the elements, and the handed points' mass falls short of
//     the elements' by that point's share (1 - 1/(8 x 180));
//   - two empty sub-cells: the cell's fill (0.89) fails: it stays points
//     (the reason names its row), the 179 cells around it are taken up
//     to the limit, and the handed points' mass is the elements' at the
//     full density.
// Runs on 1 and 2 ranks against one output.
#include <femp/builds/pore_detector.h>
#include <femp/grid/material_points.h>
#include <femp/solid/fe_zone_handover.h>
#include <femp/solid/solid_sub_cycle.h>

#include "handover_tools.h"

using namespace femp_test;

namespace
{
  constexpr int    dim = 3;
  constexpr double h   = 0.1;

  struct Scene : HandoverChoiceBlock<dim>
  {
    /// @p n_empty: how many sub-cells of the defect cell are emptied (their
    /// points moved 0.5 m up, into the gas above the block).
    Scene(MPI_Comm comm, const unsigned n_empty)
        : HandoverChoiceBlock<dim>(Point<dim>(0.6, 0.6, 1.0), h, comm)
    {
      for (auto &particle : block.points->particle_handler_for_update())
        {
          Point<dim> x = particle.get_location();
          if (!(x[0] > 0.3 && x[0] < 0.4 && x[1] > 0.3 && x[1] < 0.4 &&
                x[2] > 0.4 && x[2] < 0.5))
            continue;
          // The sub-cells of the defect cell, numbered by their lower
          // halves: (x, y, z) lower = 0, upper = 1; empty sub-cells 0 and 1.
          const unsigned sub = (x[0] > 0.35 ? 1 : 0) +
                               2 * (x[1] > 0.35 ? 1 : 0) +
                               4 * (x[2] > 0.45 ? 1 : 0);
          if (sub < n_empty)
            {
              x[2] += 0.5;
              particle.set_location(x);
            }
        }
      start_box_3d();
    }
  };
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  try
    {
      for (const unsigned n_empty : {0u, 1u, 2u})
        {
          const std::string name = std::to_string(n_empty) + " empty";
          Scene             s(comm, n_empty);
          const auto       &grid = s.block.grid;
          // alpha of the defect cell, on its owner.
          double a = -1;
          for (const auto c : grid.owned_cells())
            {
              const auto x = grid.cell_center(c);
              if (std::abs(x[0] - 0.35) < 1e-9 &&
                  std::abs(x[1] - 0.35) < 1e-9 && std::abs(x[2] - 0.45) < 1e-9)
                a = s.alpha[c];
            }
          a = Utilities::MPI::max(a, comm);
          checks.print(name + ": alpha of the cell", a, 6);
          checks.print(name + ": pores found", s.found.pores.size(), 6);
          std::string  reason;
          const double top = s.choose(reason);
          // Least fill of the row of the defect cell (z 0.4-0.5 m: the
          // third row the choice looked at, from 0.2 m).
          if (s.fill.size() > 2)
            checks.print(name + ": least fill of the row 0.4-0.5 m",
                         s.fill[2],
                         3);
          checks.print(name + ": the zone may rise to (m)", top, 6);
          print_stop(comm, name, reason);
          const double m_points = s.cells_mass;
          bool         taken    = false; // the defect cell
          for (const auto &c : s.cells)
            taken = taken || (c[0] == 3 && c[1] == 3 && c[2] == 4);
          checks.print(name + ": the defect cell taken (1 = yes)", taken, 6);
          const auto n = s.solid->hand_over_cells(s.cells);
          checks.print(name + ": elements added", n[0], 6);
          checks.print(name + ": points handed over", n[1], 6);
          const double expected = 1 - (taken ? n_empty / (8. * n[0]) : 0.);
          checks.print(name + ": points' mass / elements' mass",
                       m_points / (n[0] * s.block.material.density * h * h * h),
                       6);
          checks.in_range(name + ": ... over 1 - (empty sub-cells)/(8 "
                                 "elements)",
                          m_points /
                            (n[0] * s.block.material.density * h * h * h) /
                            expected,
                          1 - 1e-12,
                          1 + 1e-12);
        }
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
