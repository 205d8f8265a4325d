// Hand-over of cooled rows from material points to finite elements
// (SolidSubCycle::hand_over_rows(), doc/builds.md "Handing cooled metal to
// finite elements"): a 2D substrate block, 1.6 m x 0.8 m, cells of 0.1 m,
// finite elements below y = 0.2 m, material points above (2 x 2 per cell).
// Bottom fixed, sides on rollers, gravity. A hot spot centred in the rows
// that are handed over later heats to 400 K in 1 s (the yield stress
// softens with temperature: the rows yield) and cools back to 300 K in the
// next second (prescribed cell temperatures, no heat solver), leaving
// residual stress and plastic strain. Then the rows 0.2 m <= y < 0.4 m are
// handed over (the zone's top rises to 0.4 m), and the run goes on for 0.5 s
// at 300 K, beside the same run without the hand-over.
// Checks:
//   - every cell of the rows becomes one element and its 4 points leave the
//     solid: 32 elements added, 128 points handed over;
//   - the cell fields of those cells (sigma_xx, sigma_yy, sigma_zz, the
//     equivalent plastic strain) after the hand-over against before: each
//     element takes the mean of its cell's points, the value the cell field
//     shows for the points, so the difference is the round-off of the
//     averaging: at most 1e-12 of the largest |sigma| (plastic strain: of
//     the largest plastic strain);
//   - the von Mises stress of a cell changes by the averaging itself (the
//     mean of the points' von Mises stresses against that of the mean
//     stress): printed;
//   - 0.5 s later, sigma_xx at probes in the handed rows, the rows above
//     and below: the largest difference from the run without the hand-over,
//     over the largest |sigma_xx| of the probes, at most 0.05 (the FE and
//     MPM discretizations of the same rows differ; the state handed over
//     is in equilibrium, so the stresses move little);
//   - the energy balance of the run with the hand-over (the handed points'
//     kinetic energy booked as removed), at most 0.05 of the stress work.
// Runs on 1 and 2 ranks against one output.
#include <femp/grid/material_points.h>
#include <femp/solid/solid_sub_cycle.h>

#include "solid_tools.h"

using namespace femp_test;

namespace
{
  constexpr int dim = 2;

  /// The hot spot's rise above 300 K at time @p t: 100 K at t = 1 s, back
  /// to 0 at t = 2 s.
  double
  rise(const double t)
  {
    const double a = t <= 1 ? t : std::max(0., 2 - t);
    return 100 * a;
  }

  struct Scene : HandoverBlock
  {
    Scene(MPI_Comm comm)
        : HandoverBlock(comm, rise)
    {
      solid->initialize(T, "");
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
      Scene a(comm), b(comm);
      a.run(0, 40);
      b.run(0, 40);
      const auto &grid = a.block.grid;

      std::vector<std::vector<double>> before, after;
      a.solid->cell_fields(before);
      const auto sizes0 = a.solid->sizes();
      const auto moved  = a.solid->hand_over_rows(0.4);
      const auto sizes1 = a.solid->sizes();
      a.solid->cell_fields(after);
      checks.print("elements added", moved[0], 6);
      checks.print("points handed over", moved[1], 6);
      checks.print("finite elements before, after", sizes0[1], 6);
      checks.print("  after", sizes1[1], 6);
      checks.print("material points before", sizes0[0], 6);
      checks.print("  after", sizes1[0], 6);

      // The handed cells: 0.2 <= y < 0.4.
      double ds = 0, s_max = 0, dp = 0, p_max = 0, dvm = 0, vm_max = 0;
      for (const auto c : grid.owned_cells())
        {
          const double y = grid.cell_center(c)[1];
          if (y < 0.2 || y > 0.4)
            continue;
          for (unsigned int k = 0; k < 3; ++k)
            {
              ds    = std::max(ds, std::abs(after[k][c] - before[k][c]));
              s_max = std::max(s_max, std::abs(before[k][c]));
            }
          dvm    = std::max(dvm, std::abs(after[3][c] - before[3][c]));
          vm_max = std::max(vm_max, before[3][c]);
          dp     = std::max(dp, std::abs(after[4][c] - before[4][c]));
          p_max  = std::max(p_max, before[4][c]);
        }
      ds     = Utilities::MPI::max(ds, comm);
      s_max  = Utilities::MPI::max(s_max, comm);
      dp     = Utilities::MPI::max(dp, comm);
      p_max  = Utilities::MPI::max(p_max, comm);
      dvm    = Utilities::MPI::max(dvm, comm);
      vm_max = Utilities::MPI::max(vm_max, comm);
      checks.print("handed rows: largest |sigma_ii| / 1e-3", s_max / 1e-3, 4);
      checks.print("handed rows: largest plastic strain / 1e-3",
                   p_max / 1e-3,
                   4);
      checks.at_most(
        "hand-over: max |sigma_ii after - before| / max |sigma_ii|",
        ds / s_max,
        1e-12);
      checks.at_most("hand-over: max |eps_p after - before| / max eps_p",
                     p_max > 0 ? dp / p_max : 1.,
                     1e-12);
      checks.print(
        "hand-over: max |von Mises after - before| / max von Mises (averaging)",
        dvm / vm_max,
        1);

      // Both runs on at 300 K.
      a.run(40, 50);
      b.run(40, 50);
      std::vector<Point<dim>> probes;
      for (const double x : {0.25, 0.75, 0.85, 1.35})
        for (const double y : {0.15, 0.25, 0.35, 0.45, 0.75})
          probes.emplace_back(x, y);
      const auto pa = a.solid->probe(probes), pb = b.solid->probe(probes);
      double     diff = 0, peak = 0;
      for (std::size_t i = 0; i < probes.size(); ++i)
        {
          diff = std::max(diff, std::abs(pa[i][0] - pb[i][0]));
          peak = std::max(peak, std::abs(pb[i][0]));
        }
      checks.print("0.5 s later: largest |sigma_xx| at the probes / 1e-3",
                   peak / 1e-3,
                   4);
      checks.at_most(
        "0.5 s later: max |sigma_xx, hand-over - without| / max |sigma_xx|",
        diff / peak,
        0.05);
      const auto e = a.solid->energies();
      checks.at_most("energy balance / stress work (with the hand-over)",
                     std::abs(e.balance() / e.internal),
                     0.05);
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
