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
// Second field, the width at the surface: on a coarse grid (about 7 cells
// across the pool) the dome's centre lies above the substrate top,
// z_0 = c/3, so the isotherm meets the surface at an angle and is narrower
// below it: its width at the surface z = 0 is 2 b sqrt(s^2 - (z_0/c)^2),
// h/2 below it 8 % (solidus) and 15 % (liquidus) less: the cell-centre
// reading's first-order error. The length and the widths at the solidus
// (in the substrate) and the liquidus (at the free surface, gas above)
// must be within the error bound of the surface reading: T extrapolated
// linearly from the two top rows overshoots the quadratic profile by
// 0.75 h^2/c^2 in s^2, a relative width error of 0.75 h^2/c^2 /
// (2 (s^2 - (z_0/c)^2)) (2.7 % solidus, 4.7 % liquidus); the lateral
// interpolation between cell centres errs the other way, by less.
// Third field, the track's start left out: a second dome near
// x = 0 (peak between the solidus and the liquidus, wider than the pool
// at the solidus), as a plate's start face close behind a track's start
// keeps that metal hot. Over the whole domain the fusion zone's width is
// the second dome's; with x_min = 0.3 (beyond the second dome) the
// solidus and liquidus widths and depths are the pool's within 1 % again.
// Runs on 1 and 2 ranks with the same output.
#include <femp/heat/melt_pool.h>

#include <array>
#include <string>
#include <tuple>

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
  // The widths and depths of a measured pool against the exact ones, each
  // within 1 %.
  const auto check_sizes = [&](const std::string  &prefix,
                               const MeltPoolSize &p) {
    const std::array<std::tuple<std::string, double, double>, 4> sizes = {
      {{"liquidus width", p.width, wl},
       {"liquidus depth", p.depth, dl},
       {"solidus width", p.solidus_width, ws},
       {"solidus depth", p.solidus_depth, ds}}};
    for (const auto &[name, measured, exact] : sizes)
      checks.at_most(prefix + name + " relative error",
                     std::abs(measured - exact) / exact,
                     0.01);
  };
  check_sizes("", pool);
  // With the bead counted, the solidus width would be the bead's.
  checks.print("bead width (excluded)", 2 * bead_half_width);

  {
    // The width at the surface: the dome's centre above the substrate top
    // (z = 0, on a cell face), the track's axis on a cell face in y.
    const double hc = 0.05;
    const auto   gpc =
      box<dim>(Point<dim>(0, 0, -0.6), Point<dim>(1, 1, 0.1), hc);
    BackgroundGrid<dim> coarse(gpc, comm);
    coarse.create();
    const double        x0 = 0.52, y0 = 0.5, z0 = 0.1, cc = 0.3;
    std::vector<double> a2 = coarse.make_field(0.);
    std::vector<double> T2 = coarse.make_field(T0);
    for (std::size_t i = 0; i < T2.size(); ++i)
      {
        const auto x = coarse.cell_center(i);
        if (x[2] < 0)
          {
            a2[i]           = 1;
            const double r2 = std::pow((x[0] - x0) / a, 2) +
                              std::pow((x[1] - y0) / b, 2) +
                              std::pow((x[2] - z0) / cc, 2);
            T2[i] = T0 + (Tp - T0) * std::max(0., 1 - r2);
          }
      }
    const auto at_surface = measure_melt_pool(coarse, T2, a2, Tl, 0., Ts);
    // The isotherm's half-axis factor at height z.
    const auto s_at = [&](const double Tiso, const double z) {
      return std::sqrt(s(Tiso) * s(Tiso) - std::pow((z - z0) / cc, 2));
    };
    const double wl0 = 2 * b * s_at(Tl, 0), ll0 = 2 * a * s_at(Tl, 0);
    const double ws0 = 2 * b * s_at(Ts, 0);
    checks.print("coarse: liquidus width at the surface (exact)", wl0);
    checks.print("coarse: liquidus length at the surface (exact)", ll0);
    checks.print("coarse: solidus width at the surface (exact)", ws0);
    // The reading h/2 below the surface falls short by this much.
    const auto short_below = [&](const double Tiso) {
      return 1 - s_at(Tiso, -0.5 * hc) / s_at(Tiso, 0);
    };
    checks.print("coarse: liquidus width h/2 below, relative shortfall",
                 short_below(Tl));
    checks.print("coarse: solidus width h/2 below, relative shortfall",
                 short_below(Ts));
    // The surface reading's error bound (above).
    const auto bound = [&](const double Tiso) {
      return 0.75 * hc * hc / (cc * cc) / (2 * std::pow(s_at(Tiso, 0), 2));
    };
    checks.at_most("coarse: liquidus width relative error",
                   std::abs(at_surface.width - wl0) / wl0,
                   bound(Tl));
    checks.at_most("coarse: liquidus length relative error",
                   std::abs(at_surface.length - ll0) / ll0,
                   bound(Tl));
    checks.at_most("coarse: solidus width relative error",
                   std::abs(at_surface.solidus_width - ws0) / ws0,
                   bound(Ts));
  }
  {
    // The track's start left out (third field, above).
    const double        xs = 0.05, as = 0.2, bs = 0.6, cs = 0.4, Tps = 2050;
    std::vector<double> T3 = T;
    for (std::size_t i = 0; i < T3.size(); ++i)
      {
        const auto x = grid.cell_center(i);
        if (x[2] < 0)
          {
            const double r2 = std::pow((x[0] - xs) / as, 2) +
                              std::pow((x[1] - yc) / bs, 2) +
                              std::pow(x[2] / cs, 2);
            T3[i] = std::max(T3[i], T0 + (Tps - T0) * std::max(0., 1 - r2));
          }
      }
    const double x_min = 0.3;
    const double wstart =
      2 * bs * std::sqrt(1 - (Ts - T0) / (Tps - T0)); // start dome, solidus
    const auto whole = measure_melt_pool(grid, T3, alpha, Tl, 0., Ts);
    const auto from_x =
      measure_melt_pool(grid, T3, alpha, Tl, 0., Ts, nullptr, x_min);
    checks.print("start: solidus width of the start's dome (exact)", wstart);
    checks.at_most("start: whole domain, solidus width against the start's "
                   "dome, relative",
                   std::abs(whole.solidus_width - wstart) / wstart,
                   0.01);
    check_sizes("start: from x = 0.3, ", from_x);
    checks.in_range("start: from x = 0.3, lower x of the pool",
                    from_x.lower[0],
                    x_min,
                    xc);
  }
  return checks.exit_code();
}
