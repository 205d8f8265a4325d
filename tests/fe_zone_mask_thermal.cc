// A finite-element zone that is not a box (fe_zone.h, solid_fem.h: the
// zone a set of grid cells, the mesh its bounding box, the cells outside
// it no elements) in a coupled FE + MPM solid run through SolidSubCycle,
// against the closed form of a free plate heated uniformly (plane strain).
//
// A 2D plate, 1.2 m x 0.8 m, cells of 0.1 m, filled with solid points
// (2 x 2 per cell). The FE zone: the cells below y = 0.6 m for x < 0.6 m
// and below y = 0.4 m for x >= 0.6 m (a step), less the four cells
// x = 0.2-0.4 m, y = 0.2-0.4 m (an island of material points inside the
// zone, as a pore and the metal around it left behind by a hand-over); the
// points above the step and in the island are the MPM's. Elastic
// (E = 100 Pa, nu = 0.3, no yield), alpha = 1e-4 1/K; rollers at x = 0 and
// y = 0, the other faces free. All cells heat by dT = 10 K, smoothly
// (T = 300 K + dT (1 - cos(pi t / 8 s)) / 2 up to 8 s; about twenty
// periods of the plate's slowest mode, so that the heating is
// quasi-static), then hold to 12 s.
//
// Closed form (plane strain, free in-plane expansion; the constitutive
// model's eps_zz = 0): eps_xx = eps_yy = (1 + nu) alpha dT, sigma_xx =
// sigma_yy = sigma_xy = 0, sigma_zz = -E alpha dT; the displacement from
// the rollers u = (1 + nu) alpha dT x. Checks (the errors printed, each
// failing above its tolerance):
//   - the zone is not a box, has the expected number of elements;
//   - the displacement of the material points (above the step and in the
//     island, their positions against the start) from the closed form,
//     over (1 + nu) alpha dT times the plate's width;
//   - the in-plane stresses of the FE cells and of the MPM cells over
//     E alpha dT, and sigma_zz against -E alpha dT (cell fields): an
//     element that did not expand freely, or a transition node held
//     wrongly at the island's or the step's faces, shows here;
//   - negative check: the same displacements against alpha dT x (the
//     plane-stress answer, 23 % smaller) miss by far more than the
//     tolerance, so the displacement check can tell the two apart.
// Runs on 1 and 2 ranks against one output.
#include <femp/solid/solid_sub_cycle.h>

#include <cmath>
#include <map>

#include "solid_tools.h"

using namespace femp_test;

namespace
{
  constexpr int    dim   = 2;
  constexpr double h     = 0.1;
  constexpr double E     = 100;
  constexpr double nu    = 0.3;
  constexpr double alpha = 1e-4;
  constexpr double dT    = 10;
  constexpr double width = 1.2;

  /// The zone's cells: the step less the island (structured indices).
  bool
  in_zone(const int i, const int j)
  {
    const bool step   = i < 6 ? j < 6 : j < 4;
    const bool island = i >= 2 && i < 4 && j >= 2 && j < 4;
    return step && !island;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  try
    {
      SolidBlock<dim> block(
        Point<dim>(width, 0.8), h, 0.8, unit_material(), comm);
      SolidMaterial sm = block_material("1e30", block.material);
      sm.poisson_ratio = nu;
      sm.expansion     = alpha;
      typename SolidSubCycle<dim>::Parameters sp;
      sp.roller_faces = {"x-", "y-"};
      sp.energy_file  = "";
      // The bounding box x = 0-1.2 m, y = 0-0.6 m and its mask.
      const std::array<int, dim> first{{0, 0}}, n{{12, 6}};
      std::vector<std::uint8_t>  mask(12 * 6);
      for (int j = 0; j < 6; ++j)
        for (int i = 0; i < 12; ++i)
          mask[12 * j + i] = in_zone(i, j);
      const FeZone<dim>  zone(first, n, mask, block.grid.origin(), h);
      const auto         fp = fe_zone(Point<dim>(0, 0), Point<dim>(width, 0.6));
      SolidSubCycle<dim> solid(sp, fp, sm, block.grid, *block.points);
      solid.set_fe_zone(zone);

      // The points' start positions, by id, on every rank.
      std::vector<double> start;
      for (const auto &p : block.points->particle_handler())
        {
          start.push_back(p.get_id());
          for (int d = 0; d < dim; ++d)
            start.push_back(p.get_location()[d]);
        }
      std::map<types::particle_index, Point<dim>> X;
      for (const auto &part : Utilities::MPI::all_gather(comm, start))
        for (std::size_t i = 0; i < part.size(); i += dim + 1)
          X[types::particle_index(part[i])] =
            Point<dim>(part[i + 1], part[i + 2]);

      std::vector<double> T = block.grid.make_field(300.);
      solid.initialize(T, "");
      const double t_ramp = 8, t_end = 12, dt = 0.2;
      const int    n_steps = int(std::round(t_end / dt));
      for (int s = 1; s <= n_steps; ++s)
        {
          const double t = s * dt;
          const double f =
            t < t_ramp ? 0.5 * (1 - std::cos(M_PI * t / t_ramp)) : 1.;
          std::fill(T.begin(), T.end(), 300. + dT * f);
          solid.advance(t, T, s == n_steps);
        }

      const FeZone<dim> *z = solid.fe_zone();
      checks.in_range("the zone is a box (1 = yes)", z->is_box(), 0, 0);
      const auto sizes = solid.sizes();
      checks.in_range("finite elements", sizes[1], 56, 56);

      // Displacements of the material points outside the zone.
      const double eps = (1 + nu) * alpha * dT;
      double       err = 0, err_ps = 0, n_mpm = 0;
      for (const auto &p : block.points->particle_handler())
        {
          const Point<dim> x  = p.get_location();
          const Point<dim> x0 = X.at(p.get_id());
          const auto       c  = block.grid.cell_of(x0);
          if (z->contains_cell(c))
            continue;
          n_mpm += 1;
          for (int d = 0; d < dim; ++d)
            {
              const double u = x[d] - x0[d];
              err            = std::max(err, std::abs(u - eps * x0[d]));
              err_ps = std::max(err_ps, std::abs(u - alpha * dT * x0[d]));
            }
        }
      n_mpm  = Utilities::MPI::sum(n_mpm, comm);
      err    = Utilities::MPI::max(err, comm) / (eps * width);
      err_ps = Utilities::MPI::max(err_ps, comm) / (eps * width);
      checks.in_range("material points outside the zone", n_mpm, 160, 160);
      checks.at_most("max |u - (1 + nu) alpha dT x| / ((1 + nu) alpha dT "
                     "width), material points",
                     err,
                     0.005);
      checks.in_range("negative check: max |u - alpha dT x| / ((1 + nu) "
                      "alpha dT width) (plane stress answer, must miss)",
                      err_ps,
                      0.1,
                      1);

      // Stresses per cell: FE cells and MPM cells.
      std::vector<std::vector<double>> f;
      solid.cell_fields(f);
      const double          s0 = E * alpha * dT;
      std::array<double, 4> e{{0., 0., 0., 0.}}; // in-plane, zz; FE, MPM
      for (const auto c : block.grid.owned_cells())
        {
          const bool fe = z->contains_cell(block.grid.global_index(c));
          double    &ip = e[fe ? 0 : 2], &zz = e[fe ? 1 : 3];
          ip = std::max({ip, std::abs(f[0][c]), std::abs(f[1][c])});
          zz = std::max(zz, std::abs(f[2][c] + s0));
        }
      for (auto &v : e)
        v = Utilities::MPI::max(v, comm) / s0;
      checks.at_most("FE cells: max |sigma_xx|, |sigma_yy| / (E alpha dT)",
                     e[0],
                     0.005);
      checks.at_most("FE cells: max |sigma_zz + E alpha dT| / (E alpha dT)",
                     e[1],
                     0.005);
      checks.at_most("MPM cells: max |sigma_xx|, |sigma_yy| / (E alpha dT)",
                     e[2],
                     0.005);
      checks.at_most("MPM cells: max |sigma_zz + E alpha dT| / (E alpha dT)",
                     e[3],
                     0.005);
    }
  catch (const std::exception &e)
    {
      std::cerr << "error: " << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
