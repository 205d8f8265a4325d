// Material points that cross a face of a finite-element zone narrower than
// the domain (SolidMPM::hold_on_zone_face(), solid_mpm.h; doc/solid.md
// "Points that change cells", doc/builds.md "Points on the zone's faces").
// A 2D domain of 1.6 m x 0.8 m, cells of 0.1 m, solid points 2 x 2 per cell
// (spacing 0.05 m: a point is held on a face up to 0.025 m inside the
// zone), the zone x = 0.6-1.0 m, y = 0-0.4 m (a box of cells, as
// SolidFEM's), and in one scene a zone with a step (the box and
// x = 1.0-1.2 m, y = 0-0.2 m: a lower face beside the box's lateral face
// and a concave edge). Each scene gathers a block of points beside the
// zone with a stress, a plastic strain and a mass per point, prescribes a
// uniform grid velocity u (no velocity gradient: the stress does not
// change) and takes one MPM step (G2P, stress update and move), so that
// each point moves by u dt, then writes the points back (re-sorting them
// on 2 ranks when they changed rank).
// The reference is computed here, independently of SolidMPM: a point that
// ends in a cell of the zone is projected on the nearest cell outside the
// zone among its cell's 3^dim - 1 neighbours (clamped into that cell); if
// that distance is at most half the point spacing it is expected on that
// projection, a millionth of a cell outside, with the velocity components
// into the zone across each face it was moved through removed and the
// others unchanged; any other point at x0 + u dt with velocity u. Checks
// per scene: the holds counted on the top face and on a lateral face (a
// point held on both at the concave edge counts on each), the kinetic
// energy they removed (the mass times the velocity components removed),
// the largest position error (/ h), velocity error (/ |u|), the largest
// change of stress (/ its largest value), of the plastic strain and of the
// mass (exactly zero), no point lost.
// Scenes: the zone's right lateral face (points moving left and up; the
// top row of them near the zone's corner, nearer to the lateral face than
// to the top), its left lateral face (moving right and down), its top face
// with the corner (moving left and down: points near the corner are held
// on the nearer face), the step (held on the step's top, on the raised
// box's lateral face above it, and at the concave edge on both faces), and
// a point pushed 0.035 m into the zone: not held, the step reports it lost
// with its position and depth (0.035 m), and through SolidSubCycle the run
// stops with the diagnostic naming the depth. Runs on 1 and 2 ranks
// against one output.
#include <femp/grid/material_points.h>
#include <femp/solid/fe_zone.h>
#include <femp/solid/solid_mpm.h>
#include <femp/solid/solid_sub_cycle.h>

#include <functional>
#include <map>

#include "test_tools.h"

using namespace femp_test;

namespace
{
  constexpr int    dim = 2;
  constexpr double h   = 0.1;
  constexpr double dt  = 0.01;
  using Cell           = std::array<int, dim>;
  using Mask           = std::function<bool(const Cell &)>;
  using P              = MaterialPoints<dim>::PropertyIndex;

  /// The zone x = 0.6-1.0 m, y = 0-0.4 m.
  bool
  box_zone(const Cell &c)
  {
    return c[0] >= 6 && c[0] < 10 && c[1] >= 0 && c[1] < 4;
  }
  /// The box with a step: also x = 1.0-1.2 m, y = 0-0.2 m.
  bool
  step_zone(const Cell &c)
  {
    return box_zone(c) || (c[0] >= 10 && c[0] < 12 && c[1] >= 0 && c[1] < 2);
  }

  const Point<dim> domain(1.6, 0.8);

  Cell
  cell_of(const Point<dim> &x)
  {
    return {int(std::floor(x[0] / h)), int(std::floor(x[1] / h))};
  }

  /// The expected end of a point that moved to @p x1 with velocity @p u:
  /// position, velocity, whether it is held on the zone and whether it
  /// lies deeper in the zone (lost), and its distance to the nearest cell
  /// outside the zone.
  struct Expected
  {
    Point<dim>     x;
    Tensor<1, dim> v;
    bool           held = false, lost = false;
    bool           top = false, lateral = false; ///< the faces held on
    double         depth = 0;
  };

  Expected
  expected_end(const Mask &zone, const Point<dim> &x1, const Tensor<1, dim> &u)
  {
    const double tol = 0.25 * h; // half the point spacing h/2
    Expected     e;
    e.x          = x1;
    e.v          = u;
    const Cell c = cell_of(x1);
    if (!zone(c))
      return e;
    double     best = 1e300;
    Point<dim> q_best;
    for (int a = -1; a <= 1; ++a)
      for (int b = -1; b <= 1; ++b)
        {
          const Cell n{c[0] + a, c[1] + b};
          if ((a == 0 && b == 0) || n[0] < 0 || n[1] < 0 ||
              n[0] >= int(domain[0] / h + 0.5) ||
              n[1] >= int(domain[1] / h + 0.5) || zone(n))
            continue;
          // The nearest point of the closed cell n.
          Point<dim> q;
          for (int d = 0; d < dim; ++d)
            q[d] = std::min(std::max(x1[d], n[d] * h), (n[d] + 1) * h);
          const double r = q.distance(x1);
          if (r < best)
            best = r, q_best = q;
        }
    e.depth = best;
    if (best > tol)
      {
        e.lost = true;
        return e;
      }
    e.held = true;
    for (int d = 0; d < dim; ++d)
      if (q_best[d] != x1[d])
        {
          if (q_best[d] > x1[d])
            e.x[d] = q_best[d] + 1e-6 * h, e.v[d] = std::max(u[d], 0.);
          else
            e.x[d] = q_best[d] - 1e-6 * h, e.v[d] = std::min(u[d], 0.);
          (d == dim - 1 ? e.top : e.lateral) = true;
        }
    return e;
  }

  /// A point's state at the start (sent between the ranks).
  struct State
  {
    Point<dim> x;
    double     mass = 0, eps_p = 0;
    double     sigma[4] = {}; // xx, yy, xy, zz

    template <class Archive>
    void
    serialize(Archive &ar, const unsigned int)
    {
      ar &x &mass &eps_p &sigma;
    }
  };

  /// One MPM step of the points of @p region with the uniform grid
  /// velocity @p u, the zone @p zone excluded; checks against
  /// expected_end().
  void
  scene(const std::string                             &name,
        const Mask                                    &zone,
        const std::function<bool(const Point<dim> &)> &region,
        const Tensor<1, dim>                          &u,
        Checks                                        &checks,
        MPI_Comm                                       comm)
  {
    const auto          gp = box<dim>(Point<dim>(0, 0), domain, h);
    BackgroundGrid<dim> grid(gp, comm);
    grid.create();
    Material                                 mat = unit_material();
    typename MaterialPoints<dim>::Parameters pp;
    pp.point_spacing   = h / 2;
    pp.layer_thickness = 0;
    pp.subcells        = 2;
    MaterialPoints<dim> points(pp, mat, grid);
    points.create_region(region, 300., MaterialPoints<dim>::solid);
    // A stress, plastic strain and mass of each point's own, and u.
    std::map<types::particle_index, State> start;
    for (auto &p : points.particle_handler())
      {
        const double k = 1 + p.get_id() % 7;
        auto         q = p.get_properties();
        q[P::mass] *= 1 + 0.01 * k;
        for (int d = 0; d < dim; ++d)
          q[P::velocity + d] = u[d];
        q[P::stress + 0]     = 1.5 * k;
        q[P::stress + 1]     = -0.7 * k;
        q[P::stress + 2]     = 0.3 * k;
        q[P::stress_zz]      = 0.2 * k;
        q[P::plastic_strain] = 1e-3 * k;
        State s;
        s.x               = p.get_location();
        s.mass            = q[P::mass];
        s.eps_p           = q[P::plastic_strain];
        s.sigma[0]        = q[P::stress + 0];
        s.sigma[1]        = q[P::stress + 1];
        s.sigma[2]        = q[P::stress + 2];
        s.sigma[3]        = q[P::stress_zz];
        start[p.get_id()] = s;
      }
    {
      std::vector<std::pair<types::particle_index, State>> mine(start.begin(),
                                                                start.end());
      for (const auto &g : Utilities::MPI::all_gather(comm, mine))
        for (const auto &e : g)
          start.insert(e);
    }
    const double n0 = points.n_global_points();

    SolidMaterial sm   = SolidMaterial(mat); // density 1, solidus 1e6
    sm.youngs_modulus  = PiecewiseLinear(100.);
    sm.plastic_modulus = PiecewiseLinear(0.);
    sm.yield_stress    = PiecewiseLinear(1e30);
    sm.poisson_ratio   = 0.3;
    sm.expansion       = 0;
    SolidMPM<dim>             mpm(grid, sm, points);
    std::vector<std::uint8_t> mask(grid.n_local(), 0);
    for (std::size_t c = 0; c < mask.size(); ++c)
      mask[c] = zone(grid.global_index(c));
    mpm.gather(mask, 1.);
    SolidNodeFields<dim> nodes;
    nodes.resize(grid.n_local_nodes());
    for (int d = 0; d < dim; ++d)
      std::fill(nodes.velocity[d].begin(), nodes.velocity[d].end(), u[d]);
    const std::vector<double> T = grid.make_field(300.);
    mpm.g2p(nodes, dt);
    mpm.update_stresses(nodes, dt, T, T);

    // The expected ends; the points expected lost.
    std::map<types::particle_index, Expected> expected;
    double                                    n_held = 0, n_lost = 0;
    double                                    n_top = 0, n_lateral = 0;
    double                                    depth_lost = 0, k_held = 0;
    for (const auto &[id, s] : start)
      {
        const auto e = expected_end(zone, s.x + dt * u, u);
        expected[id] = e;
        n_held += e.held;
        n_top += e.top;
        n_lateral += e.lateral;
        k_held += 0.5 * s.mass * (u.norm_square() - e.v.norm_square());
        n_lost += e.lost;
        if (e.lost)
          depth_lost = e.depth;
      }
    const bool lost = Utilities::MPI::max(mpm.point_lost() ? 1 : 0, comm) > 0;
    checks.print(name + ": points held on a face expected", n_held, 6);
    if (n_held > 0)
      {
        checks.print(name + ":   on the top face", n_top, 6);
        checks.print(name + ":   on a lateral face", n_lateral, 6);
      }
    if (n_lost > 0)
      {
        // Deeper than half a point spacing: the step reports it lost, at
        // the position and depth of one of the points expected lost.
        double err_x = 0, err_depth = 0, found = 0;
        if (mpm.point_lost())
          {
            found         = 1;
            const auto &x = mpm.escaped_point();
            double      r = 1e300;
            for (const auto &[id, s] : start)
              if (expected[id].lost)
                r = std::min(r, (s.x + dt * u).distance(x));
            err_x = r;
            err_depth =
              std::abs(mpm.escaped_depth() - expected_end(zone, x, u).depth);
          }
        checks.print(name + ": points expected deeper than half a spacing",
                     n_lost,
                     6);
        checks.in_range(name + ": step reports a point lost (1 = yes)",
                        lost,
                        1,
                        1);
        checks.print(name + ": depth of the points lost (m)", depth_lost, 6);
        checks.at_most(name + ": |escaped point - expected| / h",
                       Utilities::MPI::max(err_x, comm) / h,
                       1e-12);
        checks.at_most(name + ": |depth reported - expected| / h",
                       Utilities::MPI::max(err_depth, comm) / h,
                       1e-12);
        checks.in_range(name + ": ranks that found it (>= 1)",
                        Utilities::MPI::sum(found, comm),
                        1,
                        2);
        return;
      }
    checks.at_most(name + ": step reports a point lost (1 = yes)", lost, 0);
    if (Utilities::MPI::sum(double(mpm.n_left_rank()), comm) > 0)
      mpm.resort();
    else
      mpm.scatter();

    double err_x = 0, err_v = 0, err_s = 0, err_e = 0, err_m = 0, max_s = 0;
    double wrong_cell = 0;
    for (const auto &[idx, cell] : points.occupied_cells())
      for (const auto &p : points.particle_handler().particles_in_cell(cell))
        {
          const auto  x = p.get_location();
          const auto &e = expected.at(p.get_id());
          const auto &s = start.at(p.get_id());
          const auto  q = p.get_properties();
          if (grid.cell_of(x) != grid.global_index(idx))
            wrong_cell += 1;
          err_x = std::max(err_x, x.distance(e.x));
          for (int d = 0; d < dim; ++d)
            err_v = std::max(err_v, std::abs(q[P::velocity + d] - e.v[d]));
          const double now[4] = {q[P::stress + 0],
                                 q[P::stress + 1],
                                 q[P::stress + 2],
                                 q[P::stress_zz]};
          for (int c = 0; c < 4; ++c)
            {
              err_s = std::max(err_s, std::abs(now[c] - s.sigma[c]));
              max_s = std::max(max_s, std::abs(s.sigma[c]));
            }
          err_e = std::max(err_e, std::abs(q[P::plastic_strain] - s.eps_p));
          err_m = std::max(err_m, std::abs(q[P::mass] - s.mass));
        }
    checks.at_most(
      name + ": |top-face holds counted - expected|",
      std::abs(Utilities::MPI::sum(double(mpm.n_held_at_zone_top()), comm) -
               n_top),
      0);
    checks.at_most(
      name + ": |lateral-face holds counted - expected|",
      std::abs(Utilities::MPI::sum(double(mpm.n_held_at_zone_lateral()), comm) -
               n_lateral),
      0);
    checks.at_most(
      name + ": |kinetic energy removed - expected| / expected",
      std::abs(Utilities::MPI::sum(mpm.held_at_zone_kinetic(), comm) - k_held) /
        k_held,
      1e-12);
    checks.at_most(name + ": points lost",
                   std::abs(n0 - points.n_global_points()),
                   0);
    checks.at_most(name + ": points outside their handler cell",
                   Utilities::MPI::sum(wrong_cell, comm),
                   0);
    checks.at_most(name + ": max |x - expected| / h",
                   Utilities::MPI::max(err_x, comm) / h,
                   1e-12);
    checks.at_most(name + ": max |v - expected| / |u|",
                   Utilities::MPI::max(err_v, comm) / u.norm(),
                   1e-12);
    checks.at_most(name + ": max |sigma - sigma0| / max |sigma0|",
                   Utilities::MPI::max(err_s, comm) /
                     Utilities::MPI::max(max_s, comm),
                   1e-12);
    checks.at_most(name + ": max |plastic strain - before|",
                   Utilities::MPI::max(err_e, comm),
                   0);
    checks.at_most(name + ": max |mass - before| (kg/m)",
                   Utilities::MPI::max(err_m, comm),
                   0);
  }

  /// Through SolidSubCycle: a block beside the zone's right lateral face
  /// thrown into it (12 m/s over a solid step of 0.01 s; the zone's nodes
  /// at rest halve the speed of the first column, which still moves about
  /// three times the half spacing): the run stops at solid step 1 with the
  /// diagnostic that names the depth.
  void
  deep_entry(Checks &checks, MPI_Comm comm)
  {
    const auto          gp = box<dim>(Point<dim>(0, 0), domain, h);
    BackgroundGrid<dim> grid(gp, comm);
    grid.create();
    Material                                 mat = unit_material();
    typename MaterialPoints<dim>::Parameters pp;
    pp.point_spacing   = h / 2;
    pp.layer_thickness = 0;
    pp.subcells        = 2;
    MaterialPoints<dim> points(pp, mat, grid);
    points.create_region(
      [](const Point<dim> &x) {
        return x[0] > 1.0 && x[0] < 1.2 && x[1] > 0.1 && x[1] < 0.3;
      },
      300.,
      MaterialPoints<dim>::solid);
    for (auto &p : points.particle_handler())
      p.get_properties()[P::velocity + 0] = -12.;
    SolidMaterial sm(mat);
    sm.youngs_modulus = PiecewiseLinear(1.);
    typename SolidSubCycle<dim>::Parameters sp;
    sp.energy_file = "";
    sp.time_step   = dt;
    typename SolidFEM<dim>::Parameters fp;
    fp.enabled      = true;
    fp.lower_corner = Point<dim>(0.6, 0);
    fp.upper_corner = Point<dim>(1.0, 0.4);
    // The points push the zone's nodes far in this one step; only the
    // entry is looked at here.
    fp.hourglass_distortion_limit = 1e9;
    SolidSubCycle<dim>  solid(sp, fp, sm, grid, points);
    std::vector<double> T = grid.make_field(300.);
    solid.initialize(T, "");
    std::string what;
    try
      {
        solid.advance(dt, T, true);
      }
    catch (const std::exception &e)
      {
        what = e.what();
        if (Utilities::MPI::this_mpi_process(comm) == 0)
          std::cerr << what << std::endl;
      }
    checks.in_range("thrown into the zone: run stopped at solid step 1 "
                    "(1 = yes)",
                    what.find("at solid step 1,") != std::string::npos,
                    1,
                    1);
    checks.in_range("thrown into the zone: the message names the zone and "
                    "the depth (1 = yes)",
                    what.find("entered the finite-element zone") !=
                        std::string::npos &&
                      what.find(" m deep") != std::string::npos,
                    1,
                    1);
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
      scene(
        "right lateral face",
        box_zone,
        [](const Point<dim> &x) {
          return x[0] > 1.0 && x[0] < 1.3 && x[1] < 0.6;
        },
        Tensor<1, dim>({-3.5, 1.2}),
        checks,
        comm);
      scene(
        "left lateral face",
        box_zone,
        [](const Point<dim> &x) {
          return x[0] > 0.3 && x[0] < 0.6 && x[1] < 0.6;
        },
        Tensor<1, dim>({4.0, -1.1}),
        checks,
        comm);
      scene(
        "top face and corner",
        box_zone,
        [](const Point<dim> &x) {
          return x[0] > 0.8 && x[0] < 1.2 && x[1] > 0.4 && x[1] < 0.6;
        },
        Tensor<1, dim>({-3.0, -3.5}),
        checks,
        comm);
      scene(
        "step",
        step_zone,
        [](const Point<dim> &x) {
          return x[0] > 1.0 && x[0] < 1.3 && x[1] > 0.2 && x[1] < 0.5;
        },
        Tensor<1, dim>({-3.0, -3.5}),
        checks,
        comm);
      scene(
        "deep",
        box_zone,
        [](const Point<dim> &x) {
          return x[0] > 1.0 && x[0] < 1.1 && x[1] > 0.1 && x[1] < 0.3;
        },
        Tensor<1, dim>({-6.0, 0.5}),
        checks,
        comm);
      deep_entry(checks, comm);
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
