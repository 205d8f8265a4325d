// The hand-over's test of the cells next to a pore in 3D, where a cell has
// 26 neighbours and 8 sub-cells (FeZoneHandover, fe_zone_handover.h;
// doc/builds.md "Handing cooled metal to finite elements", "Dense metal").
// A 3D block, 0.6 m x 0.6 m x 1.0 m, cells of 0.1 m, solid points (2 x 2 x 2
// per cell) up to z = 0.8 m, finite elements below z = 0.2 m; the rows may
// reach z = 0.7 m (a new layer's top at 1.0 m less a margin of 0.3 m).
// Above the zone the points lie as a melt flow leaves them: in each
// direction the two points of a cell lie 0.02 h and 0.98 h from its lower
// face in even cells (spread apart) and 0.26 h and 0.74 h in odd ones
// (close together). Each point stays in its sub-cell, so alpha reads 1,
// while the fill is the product of 0.76 (even) and 1.24 (odd) per
// direction: below 0.9 in every cell with two or three even indices, so
// that those cells are dense by alpha alone.
// Checks:
//   - a pore: 7 of the 8 points of the cell at x, y 0.3-0.4 m, z 0.4-0.5 m
//     moved 0.3 m up, into the block's top row above the limit (alpha 1/8
//     in the pore's cell); the pore detector finds one pore of one cell.
//     The pore's cell stays points; its 26 neighbours, whose own sub-cells
//     are all occupied, are taken (16 of them read a fill below 0.9, so
//     they are taken only because the pore's cell is left out of their
//     neighbourhood): 179 of the 180 cells of the rows up to the limit,
//     the zone's top may rise to the limit, 0.7 m. The same choice without
//     the detector's pores keeps those 16 as points and takes the pore's
//     cell, whose fill reads 0.906 with its close-packed neighbours' points
//     under its hat (164 cells): its own openness keeps it. Handed over, the
//     pore's cell is an island of points inside the zone, and the handed
//     points' mass is the elements' at the full density;
//   - the pore's gas reaching a neighbour: the same, and the point of the
//     face neighbour at x 0.4-0.5 m nearest the pore moved up as well
//     (alpha 7/8 there, its fill below 0.9): that neighbour stays points
//     with the pore's cell, and so do the 10 cells around it whose fill
//     reads below 0.9 (alpha 7/8 in their neighbourhood): 168 cells taken.
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

  /// Whether @p x lies in the cell with indices @p c.
  bool
  in_cell(const Point<dim> &x, const std::array<int, dim> &c)
  {
    for (int d = 0; d < dim; ++d)
      if (x[d] < c[d] * h || x[d] > (c[d] + 1) * h)
        return false;
    return true;
  }

  const std::array<int, dim> pore_cell{{3, 3, 4}}, gas_cell{{4, 3, 4}};

  struct Scene : HandoverChoiceBlock<dim>
  {
    /// @p gas: the pore's gas reaches the neighbour gas_cell by one
    /// sub-cell.
    Scene(MPI_Comm comm, const bool gas)
        : HandoverChoiceBlock<dim>(Point<dim>(0.6, 0.6, 1.0), h, comm)
    {
      for (auto &particle : block.points->particle_handler_for_update())
        {
          Point<dim> x = particle.get_location();
          if (x[2] < 0.2)
            continue;
          // The pore's cell keeps its point nearest its lower corner; the
          // gas cell loses its point nearest the pore's lower corner.
          bool up = false;
          if (in_cell(x, pore_cell))
            up = x[0] > 0.35 || x[1] > 0.35 || x[2] > 0.45;
          if (gas && in_cell(x, gas_cell))
            up = x[0] < 0.45 && x[1] < 0.35 && x[2] < 0.45;
          for (int d = 0; d < dim; ++d)
            x[d] = melt_flow_placement(x[d], h);
          if (up)
            x[2] += 0.3;
          particle.set_location(x);
        }
      start_box_3d();
    }
    /// Of the cells the last choose() took: whether @p c is one.
    bool
    taken(const std::array<int, dim> &c) const
    {
      return std::find(cells.begin(), cells.end(), c) != cells.end();
    }
    /// Of the 26 neighbours of the pore's cell: how many the last choose()
    /// took, and of them how many have two or three even indices (a fill
    /// below 0.9: dense by alpha alone).
    std::array<double, 2>
    pore_neighbours_taken() const
    {
      std::array<double, 2> n{{0, 0}};
      for (int i = -1; i <= 1; ++i)
        for (int j = -1; j <= 1; ++j)
          for (int k = -1; k <= 1; ++k)
            {
              const std::array<int, dim> c{
                {pore_cell[0] + i, pore_cell[1] + j, pore_cell[2] + k}};
              if ((i == 0 && j == 0 && k == 0) || !taken(c))
                continue;
              n[0] += 1;
              n[1] += (c[0] % 2 == 0) + (c[1] % 2 == 0) + (c[2] % 2 == 0) >= 2;
            }
      return n;
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
      std::string reason;
      {
        Scene pore(comm, false);
        checks.print("pore: pores found", pore.found.pores.size(), 6);
        checks.print("pore: its cells",
                     pore.found.pores.empty() ? 0 : pore.found.pores[0].n_cells,
                     6);
        checks.print("pore, the detector's pores not read: the zone may rise "
                     "to (m)",
                     pore.choose(reason, false),
                     6);
        print_stop(comm, "pore, the detector's pores not read", reason);
        checks.in_range("pore, the detector's pores not read: cells taken "
                        "(180 less the 16 neighbours of a fill below 0.9)",
                        pore.cells.size(),
                        164,
                        164);
        checks.in_range("pore, the detector's pores not read: of them the "
                        "pore's cell (its fill reads 0.9 or more)",
                        pore.taken(pore_cell),
                        1,
                        1);
        checks.print("pore: the zone may rise to (m)", pore.choose(reason), 6);
        print_stop(comm, "pore", reason);
        checks.in_range("pore: cells taken", pore.cells.size(), 179, 179);
        checks.in_range("pore: of them the pore's cell (x, y 0.3-0.4 m, z "
                        "0.4-0.5 m)",
                        pore.taken(pore_cell),
                        0,
                        0);
        const auto nb = pore.pore_neighbours_taken();
        checks.in_range("pore: of them its 26 neighbours", nb[0], 26, 26);
        checks.in_range("pore: ... of them with a fill below 0.9 (two or "
                        "three even indices)",
                        nb[1],
                        16,
                        16);
        checks.in_range("pore: cells kept as points for a pore",
                        pore.kept[FeZoneHandover<dim>::pore],
                        1,
                        1);
        const auto m = pore.solid->hand_over_cells(pore.cells);
        checks.print("pore: elements added", m[0], 6);
        checks.print("pore: points handed over", m[1], 6);
        checks.in_range("pore: points' mass / elements' mass",
                        pore.cells_mass /
                          (m[0] * pore.block.material.density * h * h * h),
                        1 - 1e-12,
                        1 + 1e-12);
        checks.in_range("pore: the zone is a box (1 = yes)",
                        pore.solid->fe_zone()->is_box(),
                        0,
                        0);
        checks.in_range("pore: the island's cell in the zone",
                        pore.solid->fe_zone()->contains_cell(pore_cell),
                        0,
                        0);
      }
      {
        Scene gas(comm, true);
        checks.print("gas: pores found", gas.found.pores.size(), 6);
        checks.print("gas: the zone may rise to (m)", gas.choose(reason), 6);
        print_stop(comm, "gas", reason);
        checks.in_range("gas: cells taken (180 less the pore's cell, the "
                        "gas cell and its 10 neighbours of a fill below 0.9)",
                        gas.cells.size(),
                        168,
                        168);
        checks.in_range("gas: of them the pore's cell",
                        gas.taken(pore_cell),
                        0,
                        0);
        checks.in_range("gas: of them the neighbour the gas reaches (x "
                        "0.4-0.5 m, y 0.3-0.4 m, z 0.4-0.5 m)",
                        gas.taken(gas_cell),
                        0,
                        0);
        checks.print("gas: of them the pore's other 25 neighbours",
                     gas.pore_neighbours_taken()[0],
                     6);
        checks.print("gas: cells kept as points for a pore (the pore's "
                     "cell and its neighbours not dense)",
                     gas.kept[FeZoneHandover<dim>::pore],
                     6);
      }
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
