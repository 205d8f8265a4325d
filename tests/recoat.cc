// The recoater (builds/recoater.h, doc/builds.md "Recoating") in 3D, on a
// substrate with a re-solidified track (a half cylinder of solid points of
// radius 35 um along x), recoated up to 70 um above the substrate:
//   1. on the bare substrate and track: the mass of the new powder against
//      rho x packing fraction x the volume between the surface and the
//      layer's top, from the geometry (box less the half cylinder), within
//      8 %: the bed is periodic across the lateral faces, so the grains
//      placed (their volume reaches the target within one grain, < 1 %)
//      all lie inside, but each of the ~150 grains, 2.5 to 3.75 point
//      spacings in radius, is the set of lattice points inside it (a ball
//      of radius 2.5 spacings holds 57 to 81 points for a volume of 65.4);
//   2. with the first layer's powder beside the track (30 um, packing
//      0.35): no new point on a lattice site that a point already holds,
//      none below the surface of its column, all powder; the new points
//      the same on every rank count: their number and a hash of their
//      sorted positions, printed, agree between the runs on 1 and 2 ranks
//      (one expected output). Its mass per nominal layer volume (40 um x
//      the area) is printed: above the packing fraction, since the new
//      grains also fill the hollows between the first layer's grains.
// Also the layer schedule: listed times, and the refusal of a layer above
// the domain.
#include <femp/base/input_checks.h>
#include <femp/builds/recoater.h>

#include <algorithm>
#include <cstring>

#include "test_tools.h"

using namespace femp_test;

namespace
{
  constexpr int dim = 3;

  /// All point positions (x, y, z) and states, on rank 0.
  std::vector<std::array<double, 4>>
  gather_points(const MaterialPoints<dim> &points, MPI_Comm comm)
  {
    using P = MaterialPoints<dim>::PropertyIndex;
    std::vector<std::array<double, 4>> mine;
    for (const auto &p : points.particle_handler())
      {
        const auto x = p.get_location();
        mine.push_back({{x[0], x[1], x[2], p.get_properties()[P::state]}});
      }
    const auto all = Utilities::MPI::gather(comm, mine, 0);
    std::vector<std::array<double, 4>> out;
    for (const auto &a : all)
      out.insert(out.end(), a.begin(), a.end());
    std::sort(out.begin(), out.end());
    return out;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  const bool root = Utilities::MPI::this_mpi_process(comm) == 0;

  const double        h = 8e-6, s = 4e-6;
  const double        Lx = 30 * h, Ly = 20 * h, Lz = 24 * h;
  BackgroundGrid<dim> grid(
    box<dim>(Point<dim>(0, 0, 0), Point<dim>(Lx, Ly, Lz), h), comm);
  grid.create();
  Material mat = unit_material();
  mat.density  = 7900;
  typename MaterialPoints<dim>::Parameters pp;
  pp.point_spacing    = s;
  pp.subcells         = 2;
  pp.substrate_top    = 8 * h;
  pp.layer_thickness  = 30e-6;
  pp.mean_diameter    = 20e-6;
  pp.std_diameter     = 5e-6;
  pp.min_diameter     = 10e-6;
  pp.max_diameter     = 30e-6;
  pp.packing_fraction = 0.35;
  pp.seed             = 3;
  using P             = MaterialPoints<dim>::PropertyIndex;
  const double R = 35e-6, y_c = 10 * h, z_c = pp.substrate_top;
  const auto   in_bead = [&](const Point<dim> &x) {
    return x[2] > z_c && std::hypot(x[1] - y_c, x[2] - z_c) < R;
  };

  // The schedule: two layers by times, 40 um each.
  typename LayerSchedule<dim>::Parameters lp;
  lp.source                    = LayerSource::times;
  lp.thickness                 = 40e-6;
  lp.start_times               = {1e-3, 2e-3};
  const double       first_top = pp.substrate_top + pp.layer_thickness;
  LayerSchedule<dim> schedule(lp, {}, first_top, Lz, h);
  checks.print("layers scheduled after the first", schedule.layers().size());
  checks.print("layer 2 top (um)", schedule.layers()[0].top * 1e6, 6);
  // A third listed layer would reach 64 + 30 + 120 = 214 um, above 192 -
  // 16 um: refused.
  {
    auto bad        = lp;
    bad.start_times = {1e-3, 2e-3, 3e-3};
    bool refused    = false;
    try
      {
        LayerSchedule<dim> too_tall(bad, {}, first_top, Lz, h);
      }
    catch (const InputError &e)
      {
        refused = std::strstr(e.what(), "Build/Layer start times") &&
                  std::strstr(e.what(), "above the domain");
      }
    checks.at_most("a layer above the domain is refused (0 = yes)",
                   refused ? 0 : 1,
                   0);
  }
  const auto layer = schedule.layers()[0];

  // 1. Substrate and track only.
  {
    MaterialPoints<dim> points(pp, mat, grid);
    points.create_region(
      [&](const Point<dim> &x) { return x[2] < z_c || in_bead(x); },
      300.,
      MaterialPoints<dim>::solid);
    Recoater<dim> recoater(pp, mat.density, grid);
    const auto    r    = recoater.recoat(points, layer, 320.);
    const double  V    = Lx * Ly * (layer.top - z_c) - Lx * M_PI * R * R / 2;
    const double  mass = mat.density * r.point_volume;
    const double  mass_expected = mat.density * pp.packing_fraction * V;
    checks.print("bare track: grains", r.grains);
    checks.at_most("bare track: |volume between surface and top - box less "
                   "half cylinder| / volume",
                   std::abs(r.fill_volume - V) / V,
                   0.01);
    checks.at_most("bare track: |powder mass - rho phi V| / (rho phi V)",
                   std::abs(mass - mass_expected) / mass_expected,
                   0.08);
  }

  // 2. With the first layer's powder beside the track.
  MaterialPoints<dim> points(pp, mat, grid);
  points.create(300.);
  {
    // The track: the powder points in the bead's half cylinder leave, the
    // bead's lattice points come as solid points.
    auto &handler = points.particle_handler_for_update();
    std::vector<typename Particles::ParticleHandler<dim>::particle_iterator>
      gone;
    for (auto p = handler.begin(); p != handler.end(); ++p)
      if (in_bead(p->get_location()))
        gone.push_back(p);
    handler.remove_particles(gone);
    std::vector<std::pair<std::uint32_t, Point<dim>>> add;
    for (const auto idx : grid.owned_cells())
      {
        const auto ijk = grid.global_index(idx);
        for (int k = 0; k < 2; ++k)
          for (int j = 0; j < 2; ++j)
            for (int i = 0; i < 2; ++i)
              {
                const Point<dim> x((ijk[0] * 2 + i + 0.5) * s,
                                   (ijk[1] * 2 + j + 0.5) * s,
                                   (ijk[2] * 2 + k + 0.5) * s);
                if (in_bead(x))
                  add.emplace_back(idx, x);
              }
      }
    std::vector<double> props(points.n_properties(), 0.);
    props[P::mass]             = mat.density * s * s * s;
    props[P::volume]           = s * s * s;
    props[P::temperature]      = 300;
    props[P::peak_temperature] = 2000;
    props[P::state]            = MaterialPoints<dim>::solid;
    std::uint64_t n = add.size(), off = 0;
    MPI_Exscan(&n, &off, 1, MPI_UINT64_T, MPI_SUM, comm);
    if (root)
      off = 0;
    const auto first = handler.get_next_free_particle_index() + off;
    for (std::size_t k = 0; k < add.size(); ++k)
      {
        const auto &cell = grid.cell_iterator(add[k].first);
        Point<dim>  ref;
        for (int d = 0; d < dim; ++d)
          ref[d] = (add[k].second[d] - cell->vertex(0)[d]) / h;
        handler.insert_particle(
          add[k].second, ref, first + k, cell, ArrayView<const double>(props));
      }
    handler.update_cached_numbers();
    points.points_moved();
  }
  const auto before = gather_points(points, comm);

  Recoater<dim> recoater(pp, mat.density, grid);
  const auto    surf = recoater.surface(points);
  const auto    r    = recoater.recoat(points, layer, 320.);
  checks.print("beside powder: grains", r.grains);
  checks.print("beside powder: mass / (rho phi x nominal layer volume)",
               r.point_volume / (pp.packing_fraction * Lx * Ly * 40e-6),
               2);

  const auto after = gather_points(points, comm);
  if (root)
    {
      // New points: those of after that are not in before (both sorted).
      std::vector<std::array<double, 4>> added;
      std::set_difference(after.begin(),
                          after.end(),
                          before.begin(),
                          before.end(),
                          std::back_inserter(added));
      std::uint64_t hash = 1469598103934665603ull;
      for (const auto &a : added)
        for (int d = 0; d < 3; ++d)
          {
            std::uint64_t bits;
            std::memcpy(&bits, &a[d], 8);
            hash = (hash ^ bits) * 1099511628211ull;
          }
      // Shared lattice sites: equal positions among all points.
      unsigned int shared = 0, below = 0, not_powder = 0;
      for (std::size_t k = 1; k < after.size(); ++k)
        shared += after[k][0] == after[k - 1][0] &&
                  after[k][1] == after[k - 1][1] &&
                  after[k][2] == after[k - 1][2];
      const unsigned int nx = Lx / s + 0.5;
      for (const auto &a : added)
        {
          const unsigned int i = a[0] / s, j = a[1] / s;
          below += a[2] < surf[i + nx * j];
          not_powder += a[3] != MaterialPoints<dim>::powder;
        }
      std::cout << "beside powder: new points = " << added.size()
                << " (reported " << r.points << ")" << std::endl;
      std::cout << "beside powder: hash of their positions = "
                << hash % 1000000007ull << std::endl;
      std::cout << "beside powder: points sharing a lattice site = " << shared
                << std::endl;
      std::cout << "beside powder: new points below the surface = " << below
                << std::endl;
      std::cout << "beside powder: new points not powder = " << not_powder
                << std::endl;
      if (shared + below + not_powder > 0 || added.size() != r.points)
        checks.at_most("recoat faults", 1, 0);
    }
  return checks.exit_code();
}
