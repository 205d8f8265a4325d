// Melt-pool size measurement on a prescribed temperature field of known
// size. A 3D box of metal below z_s = 0 (the original substrate top) with a
// bead of metal above it (a strip |y - y_c| < 0.35 of two cells' height)
// and a quadratic temperature dome
//   T = T0 + (Tp - T0) max(0, 1 - r^2),
//   r^2 = ((x - x_c)/a)^2 + ((y - y_c)/b)^2 + (z/c)^2,
// whose isotherm T_iso is the ellipsoid r^2 = s^2, s^2 = 1 - (T_iso - T0)/
// (Tp - T0): half-width b s and depth c s. The bead is held just above the
// solidus (but below the liquidus) over its whole width, wider than the
// pool: it must not count in the fusion zone (solidus, inside the
// substrate), and the liquidus box must not see it either. Checks:
// liquidus width and depth, solidus width and depth inside the substrate,
// each within 1 % of the ellipsoid's (the cell-centre sampling and the
// linear interpolation of a quadratic profile err by O(h^2)).
// Runs on 1 and 2 ranks with the same output.
#include <femp/heat/melt_pool.h>

#include "test_tools.h"

using namespace femp_test;

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);

  constexpr int dim = 3;
  const double  h   = 0.02;
  const auto    gp = box<dim>(Point<dim>(0, 0, -0.6), Point<dim>(1, 1, 0.1), h);
  BackgroundGrid<dim> grid(gp, comm);
  grid.create();

  // Pool centre on a cell centre in x and y.
  const double        xc = 0.51, yc = 0.51, a = 0.35, b = 0.3, c = 0.2;
  const double        T0 = 300, Tp = 3000, Ts = 1650, Tl = 2100;
  const double        bead_half_width = 0.35, bead_top = 2 * h;
  std::vector<double> alpha = grid.make_field(0.);
  std::vector<double> T     = grid.make_field(T0);
  for (std::size_t i = 0; i < T.size(); ++i)
    {
      const auto x = grid.cell_center(i);
      if (x[2] < 0)
        {
          alpha[i]        = 1;
          const double r2 = std::pow((x[0] - xc) / a, 2) +
                            std::pow((x[1] - yc) / b, 2) +
                            std::pow(x[2] / c, 2);
          T[i] = T0 + (Tp - T0) * std::max(0., 1 - r2);
        }
      else if (x[2] < bead_top && std::abs(x[1] - yc) < bead_half_width)
        {
          alpha[i] = 1;
          T[i]     = Ts + 50;
        }
    }

  const auto pool = measure_melt_pool(grid, T, alpha, Tl, 0., Ts);
  const auto s    = [&](const double Tiso) {
    return std::sqrt(1 - (Tiso - T0) / (Tp - T0));
  };
  const double wl = 2 * b * s(Tl), dl = c * s(Tl);
  const double ws = 2 * b * s(Ts), ds = c * s(Ts);
  checks.print("liquidus width (exact)", wl);
  checks.print("liquidus depth (exact)", dl);
  checks.print("solidus width in the substrate (exact)", ws);
  checks.print("solidus depth in the substrate (exact)", ds);
  checks.at_most("liquidus width relative error",
                 std::abs(pool.width - wl) / wl,
                 0.01);
  checks.at_most("liquidus depth relative error",
                 std::abs(pool.depth - dl) / dl,
                 0.01);
  checks.at_most("solidus width relative error",
                 std::abs(pool.solidus_width - ws) / ws,
                 0.01);
  checks.at_most("solidus depth relative error",
                 std::abs(pool.solidus_depth - ds) / ds,
                 0.01);
  // With the bead counted, the solidus width would be the bead's.
  checks.print("bead width (excluded)", 2 * bead_half_width);
  return checks.exit_code();
}
