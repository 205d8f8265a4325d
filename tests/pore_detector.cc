// The pore detector (PoreDetector, doc/builds.md "Porosity") on prescribed
// voids in a block of solid points (3D, 32 x 16 x 24 cells of h = 10 um,
// points on the lattice of spacing h/2, the solid below z = 16 h, unfused
// powder from 16 h to 18.5 h, gas above):
//   - a sphere of radius 3 h;
//   - a channel between two tracks: a tube of 2.5 h x 2.5 h along y, closed
//     at both ends;
//   - an L-shaped void along x over nearly the whole domain and up
//     towards the surface, which crosses the ranks' boundaries;
//   - a box void whose lower half holds unfused powder points;
//   - a crack one cell wide from the surface down into the solid, open to
//     the gas through the powder: not a pore.
// References from the points: the gas volume of each void is the number of
// lattice points missing there times (h/2)^3, its powder the number of
// powder points inside; the sphere is also compared with 4/3 pi R^3 and
// its centroid with its centre, the channel's centroid with its centre to
// the resolution of the cells; the relative density of the region above
// z = 2 h is (M + P_s) / (M + P_s + P_g) from the counts. Runs on 1 and 2
// ranks with the same output; on 2 the L-shaped void must lie on both.
#include <femp/builds/pore_detector.h>

#include "test_tools.h"

using namespace femp_test;

namespace
{
  constexpr int    dim = 3;
  constexpr double h   = 1e-5;

  struct Box
  {
    Point<dim> lo, hi; // in units of h
    bool
    inside(const Point<dim> &x) const
    {
      for (int d = 0; d < dim; ++d)
        if (x[d] < lo[d] * h || x[d] > hi[d] * h)
          return false;
      return true;
    }
  };

  const Point<dim> sphere_centre(6, 4.5, 6);
  const double     sphere_radius = 3;
  const Box        channel{{14, 2, 10}, {16.5, 14, 12.5}};
  const Box        l_long{{1.5, 10, 4}, {30.5, 12, 5.5}};
  const Box        l_up{{28, 10, 4}, {30, 12, 14.5}};
  const Box        powder_box{{20, 3, 6}, {24, 6, 9}};
  const double     powder_fill_top = 7.5;
  const Box        crack{{10, 1, 12}, {11, 15, 16}};

  /// Which void holds x (1 sphere, 2 channel, 3 L, 4 powder box, 5 crack),
  /// 0 none.
  int
  void_of(const Point<dim> &x)
  {
    if ((x / h - sphere_centre).norm() < sphere_radius)
      return 1;
    if (channel.inside(x))
      return 2;
    if (l_long.inside(x) || l_up.inside(x))
      return 3;
    if (powder_box.inside(x))
      return 4;
    if (crack.inside(x))
      return 5;
    return 0;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  const unsigned int n_ranks = Utilities::MPI::n_mpi_processes(comm);

  BackgroundGrid<dim> grid(
    box<dim>(Point<dim>(0, 0, 0), Point<dim>(32 * h, 16 * h, 24 * h), h), comm);
  grid.create();
  const Material                           mat = unit_material();
  typename MaterialPoints<dim>::Parameters pp;
  pp.point_spacing   = h / 2;
  pp.subcells        = 2;
  pp.layer_thickness = 0;
  MaterialPoints<dim> points(pp, mat, grid);
  const double        solid_top = 16 * h, powder_top = 18.5 * h;
  const auto          is_powder = [&](const Point<dim> &x) {
    return x[dim - 1] > solid_top ||
           (void_of(x) == 4 && x[dim - 1] < powder_fill_top * h);
  };
  points.create_region(
    [&](const Point<dim> &x) {
      if (x[dim - 1] > powder_top)
        return false;
      return is_powder(x) || (x[dim - 1] < solid_top && void_of(x) == 0);
    },
    300.,
    MaterialPoints<dim>::solid);
  using P = MaterialPoints<dim>::PropertyIndex;
  for (auto &particle : points.particle_handler_for_update())
    if (is_powder(particle.get_location()))
      particle.get_properties()[P::state] = MaterialPoints<dim>::powder;

  // Reference counts over the lattice (the same on every rank).
  const double s3     = std::pow(h / 2, 3);
  double       gas[6] = {0, 0, 0, 0, 0, 0}, powder_in_box = 0;
  double       metal_above = 0;
  const double bottom      = 2 * h;
  for (int k = 0; k < 2 * 24; ++k)
    for (int j = 0; j < 2 * 16; ++j)
      for (int i = 0; i < 2 * 32; ++i)
        {
          const Point<dim> x((i + 0.5) * h / 2,
                             (j + 0.5) * h / 2,
                             (k + 0.5) * h / 2);
          if (x[dim - 1] > solid_top)
            continue;
          const int v = void_of(x);
          if (v == 0)
            metal_above += x[dim - 1] >= bottom ? s3 : 0;
          else if (is_powder(x))
            powder_in_box += s3;
          else
            gas[v] += s3;
        }

  typename PoreDetector<dim>::Parameters prm;
  prm.bottom       = bottom;
  prm.bottom_given = true;
  PoreDetector<dim> detector(prm, grid, 0.);
  const auto        alpha = points.metal_fraction();
  const auto        share =
    PoreDetector<dim>::powder_shares(grid, points, 1e6, 2e6).first;
  const auto r = detector.find(alpha, &share);

  checks.print("pores found (sphere, channel, L, powder box; not the crack)",
               r.pores.size());
  checks.at_most("|pores found - 4|", std::abs(double(r.pores.size()) - 4), 0);
  if (r.pores.size() != 4)
    return checks.exit_code();

  // The pores come in the order of their smallest global cell number:
  // the L (lowest z), the sphere, the powder box, the channel. Identify
  // each by its centroid's void instead of relying on that order.
  const char *names[5] = {
    "", "sphere", "channel", "L-shaped void", "powder box"};
  std::vector<int> found(5, -1);
  for (unsigned int p = 0; p < r.pores.size(); ++p)
    {
      // The void whose reference volume is nearest.
      int    best = 0;
      double err  = 1e300;
      for (int v = 1; v <= 4; ++v)
        {
          const double e = std::abs(r.pores[p].volume - gas[v]);
          if (e < err)
            {
              err  = e;
              best = v;
            }
        }
      found[best] = p;
    }
  for (int v = 1; v <= 4; ++v)
    {
      const std::string name = names[v];
      if (found[v] < 0)
        {
          checks.at_most(name + " found (1 = no)", 1, 0);
          continue;
        }
      const auto &pore = r.pores[found[v]];
      checks.print(name + ": gas volume / h^3", pore.volume / std::pow(h, 3));
      checks.at_most(name + ": |volume - missing points| / missing points",
                     std::abs(pore.volume - gas[v]) / gas[v],
                     1e-12);
      if (v == 4)
        {
          checks.print(name + ": enclosed powder / h^3",
                       pore.powder / std::pow(h, 3));
          checks.at_most(name + ": |powder - powder points| / powder points",
                         std::abs(pore.powder - powder_in_box) / powder_in_box,
                         1e-12);
        }
      // The ranks holding cells of this pore.
      unsigned int here = 0;
      for (const auto i : grid.owned_cells())
        here = here || r.pore_number[i] == found[v] + 1;
      const unsigned int ranks = Utilities::MPI::sum(here, comm);
      if (Utilities::MPI::this_mpi_process(comm) == 0)
        std::cerr << name << ": on " << ranks << " of " << n_ranks << " ranks"
                  << std::endl;
      if (v == 3)
        checks.at_most(name + ": lies on one rank of several (1 = yes)",
                       n_ranks > 1 && ranks < 2 ? 1 : 0,
                       0);
    }
  {
    const auto  &s     = r.pores[found[1]];
    const double exact = 4. / 3 * M_PI * std::pow(sphere_radius * h, 3);
    checks.at_most("sphere: |volume - 4/3 pi R^3| / (4/3 pi R^3)",
                   std::abs(s.volume - exact) / exact,
                   0.03);
    checks.at_most("sphere: |centroid - centre| / h",
                   (s.centroid / h - sphere_centre).norm(),
                   1e-9);
    checks.at_most("sphere: |equivalent diameter - 2R| / 2R",
                   std::abs(s.diameter - 2 * sphere_radius * h) /
                     (2 * sphere_radius * h),
                   0.01);
    const auto &c = r.pores[found[2]];
    Point<dim>  mid;
    for (int d = 0; d < dim; ++d)
      mid[d] = 0.5 * (channel.lo[d] + channel.hi[d]);
    checks.at_most("channel: |volume - 2.5 x 12 x 2.5 h^3| / volume",
                   std::abs(c.volume - 2.5 * 12 * 2.5 * std::pow(h, 3)) /
                     c.volume,
                   1e-12);
    // Each cell's gas counts at the cell's centre: the channel's faces
    // at x = 16.5 h and z = 12.5 h cut cells in half, which moves the
    // centroid by (0.25 h) (1 h^2 x 12 h) / 75 h^3 = 0.04 h along x and z.
    checks.at_most("channel: |centroid - centre| / h",
                   (c.centroid / h - mid).norm(),
                   0.1);
  }
  const double pores_gas = gas[1] + gas[2] + gas[3] + gas[4];
  const double rho_ref =
    (metal_above + powder_in_box) / (metal_above + powder_in_box + pores_gas);
  checks.print("relative density above z = 2 h", r.relative_density, 6);
  checks.at_most("|relative density - reference|",
                 std::abs(r.relative_density - rho_ref),
                 1e-12);
  return checks.exit_code();
}
