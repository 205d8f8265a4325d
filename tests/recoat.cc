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
//   3. the blade, on the bare substrate with three detached drops (balls
//      of solid points, 16-20 um across, two cells or more from any other
//      metal): one across the layer's top, one at the box's lid, one
//      floating below the top. The two that reach above the top are swept:
//      the bodies, points and mass reported against those the test placed
//      (exact), none of their points left; the one below stays whole. The
//      surface is the substrate's top in every column (the attached metal
//      only), grains come down to it under the swept drops, the volume
//      between the resting height and the top is the box's less the
//      shadow of the drop that stayed (from the drop's lattice points); no
//      new point on a site a point holds. The packing: the ballistic bed
//      of this 70 um fill (two to three grains deep) reaches 0.32-0.34,
//      below the asked 0.35, with or without drops, and its value
//      scatters between seeds by about 1.4 % for the same scene; so the
//      same plate without drops and the scene with them are recoated with
//      the seeds 1-10, and the mean packing with drops must lie within
//      3 % of the mean without (the drop that stays below the top lowers
//      it by about 1.5 %: grains pack less densely against it), the mean
//      powder volume per fill volume within 8 % (the grains as lattice
//      points, as in 1.). The counts and a hash of the new points agree
//      between 1 and 2 ranks.
// Also the layer schedule: listed times, and the refusal of a layer above
// the domain.
#include <femp/base/input_checks.h>
#include <femp/builds/recoater.h>
#include <femp/grid/metal_bodies.h>

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

  /// FNV hash of the positions of @p pts, reduced for printing.
  std::uint64_t
  position_hash(const std::vector<std::array<double, 4>> &pts)
  {
    std::uint64_t hash = 1469598103934665603ull;
    for (const auto &a : pts)
      for (int d = 0; d < 3; ++d)
        {
          std::uint64_t bits;
          std::memcpy(&bits, &a[d], 8);
          hash = (hash ^ bits) * 1099511628211ull;
        }
    return hash % 1000000007ull;
  }

  /// The recoat with the workpiece of the points' own alpha.
  Recoater<dim>::Report
  recoat(const Recoater<dim>             &recoater,
         MaterialPoints<dim>             &points,
         const BackgroundGrid<dim>       &grid,
         const LayerSchedule<dim>::Layer &layer,
         const double                     T,
         std::vector<std::uint8_t>       *attached_out = nullptr)
  {
    const auto alpha    = points.metal_fraction();
    const auto attached = attached_metal_cells(grid, alpha);
    if (attached_out)
      *attached_out = attached;
    return recoater.recoat(points, layer, T, alpha, attached);
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
    const auto    r    = recoat(recoater, points, grid, layer, 320.);
    const double  V    = Lx * Ly * (layer.top - z_c) - Lx * M_PI * R * R / 2;
    const double  mass = mat.density * r.point_volume;
    const double  mass_expected = mat.density * pp.packing_fraction * V;
    checks.print("bare track: grains", r.grains);
    checks.print("bare track: packing reached", r.packing, 3);
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
  const auto    surf =
    recoater
      .surface(points, attached_metal_cells(grid, points.metal_fraction()))
      .rest;
  const auto r = recoat(recoater, points, grid, layer, 320.);
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
      const std::uint64_t hash = position_hash(added);
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
      std::cout << "beside powder: hash of their positions = " << hash
                << std::endl;
      std::cout << "beside powder: points sharing a lattice site = " << shared
                << std::endl;
      std::cout << "beside powder: new points below the surface = " << below
                << std::endl;
      std::cout << "beside powder: new points not powder = " << not_powder
                << std::endl;
      if (shared + below + not_powder > 0 || added.size() != r.points)
        checks.at_most("recoat faults", 1, 0);
    }

  // 3. The blade: drops above the top are swept, the one below stays.
  {
    struct Ball
    {
      Point<dim> c;
      double     r;
      bool
      inside(const Point<dim> &x) const
      {
        return x.distance(c) < r;
      }
    };
    // Across the top (134 um), at the lid (192 um), below the top.
    const Ball above{Point<dim>(60e-6, 40e-6, layer.top + 2e-6), 10e-6};
    const Ball lid{Point<dim>(180e-6, 120e-6, 182e-6), 8e-6};
    const Ball below{Point<dim>(160e-6, 80e-6, 100e-6), 10e-6};
    MaterialPoints<dim> points(pp, mat, grid);
    points.create_region(
      [&](const Point<dim> &x) {
        return x[2] < z_c || above.inside(x) || lid.inside(x) ||
               below.inside(x);
      },
      300.,
      MaterialPoints<dim>::solid);
    // The lattice points of each drop, and per lattice column the top of
    // the drop below the blade (its shadow).
    const unsigned int  nx = Lx / s + 0.5, ny = Ly / s + 0.5, nz = Lz / s + 0.5;
    unsigned int        n_above = 0, n_lid = 0, n_below = 0;
    std::vector<double> shadow(nx * ny, z_c);
    for (unsigned int k = 0; k < nz; ++k)
      for (unsigned int j = 0; j < ny; ++j)
        for (unsigned int i = 0; i < nx; ++i)
          {
            const Point<dim> x((i + 0.5) * s, (j + 0.5) * s, (k + 0.5) * s);
            if (x[2] < z_c)
              continue;
            n_above += above.inside(x);
            n_lid += lid.inside(x);
            if (below.inside(x))
              {
                ++n_below;
                shadow[i + nx * j] =
                  std::max(shadow[i + nx * j], x[2] + 0.5 * s);
              }
          }
    double       V        = 0;
    unsigned int on_drops = 0;
    for (const double z : shadow)
      {
        V += (layer.top - z) * s * s;
        on_drops += z > z_c;
      }
    const auto before = gather_points(points, comm);

    Recoater<dim> recoater(pp, mat.density, grid);
    const auto    r = recoat(recoater, points, grid, layer, 320.);
    checks.print("blade: points of the two drops reaching above the top",
                 n_above + n_lid);
    checks.print("blade: drop placed below the top (points)", n_below);
    checks.at_most("blade: |detached bodies swept - 2|",
                   std::abs(double(r.swept_bodies) - 2),
                   0);
    checks.at_most("blade: |points swept - points of the drops above|",
                   std::abs(double(r.swept_points) - (n_above + n_lid)),
                   0);
    const double m_drops = mat.density * std::pow(s, 3) * (n_above + n_lid);
    checks.at_most("blade: |mass swept - their mass| / their mass",
                   std::abs(r.swept_mass - m_drops) / m_drops,
                   1e-12);
    checks.at_most("blade: |highest column of the surface - substrate top| "
                   "(um)",
                   std::abs(r.surface_max - z_c) * 1e6,
                   1e-9);
    checks.at_most("blade: |lowest column of the surface - substrate top| "
                   "(um)",
                   std::abs(r.surface_min - z_c) * 1e6,
                   1e-9);
    checks.at_most("blade: |columns resting on the drop below - its "
                   "footprint|",
                   std::abs(double(r.columns_on_drops) - on_drops),
                   0);
    checks.at_most("blade: |volume between resting height and top - box "
                   "less the drop's shadow| / volume",
                   std::abs(r.fill_volume - V) / V,
                   1e-9);
    checks.print("blade: grains", r.grains);
    checks.print("blade: packing reached", r.packing, 3);
    // The same plate without drops, recoated alike, and both scenes with
    // the seeds 1-10 (3 is the one above): the packing that the ballistic
    // bed reaches in this fill (70 um, two to three grains deep) is below
    // the asked 0.35 with or without drops, and it scatters between seeds
    // by about 1.4 % (one standard deviation of the difference of the two
    // scenes at one seed), so the means over the ten seeds are compared.
    const auto plate_recoat = [&](const unsigned int seed, const bool drops) {
      auto pq = pp;
      pq.seed = seed;
      const Recoater<dim> rq(pq, mat.density, grid);
      MaterialPoints<dim> plate(pq, mat, grid);
      plate.create_region(
        [&](const Point<dim> &x) {
          return x[2] < z_c || (drops && (above.inside(x) || lid.inside(x) ||
                                          below.inside(x)));
        },
        300.,
        MaterialPoints<dim>::solid);
      return recoat(rq, plate, grid, layer, 320.);
    };
    const unsigned int n_seeds    = 10;
    double             mean[2][2] = {{0, 0}, {0, 0}}; // [plain, drops][phi, m]
    for (unsigned int seed = 1; seed <= n_seeds; ++seed)
      {
        const auto a = plate_recoat(seed, false);
        const auto b = seed == pp.seed ? r : plate_recoat(seed, true);
        if (seed == pp.seed)
          checks.print("blade: packing reached on the plate without drops",
                       a.packing,
                       3);
        mean[0][0] += a.packing / n_seeds;
        mean[0][1] += a.point_volume / a.fill_volume / n_seeds;
        mean[1][0] += b.packing / n_seeds;
        mean[1][1] += b.point_volume / b.fill_volume / n_seeds;
      }
    checks.print("blade: packing reached, mean over 10 seeds, without drops",
                 mean[0][0],
                 3);
    checks.print("blade: packing reached, mean over 10 seeds, with drops",
                 mean[1][0],
                 3);
    checks.at_most("blade: |mean packing with drops - without| / without",
                   std::abs(mean[1][0] - mean[0][0]) / mean[0][0],
                   0.03);
    // The new powder's mass per fill volume (the grains as lattice
    // points, as in 1.), likewise.
    checks.at_most("blade: |mean powder volume / fill volume with drops - "
                   "without| / without",
                   std::abs(mean[1][1] - mean[0][1]) / mean[0][1],
                   0.08);

    const auto after = gather_points(points, comm);
    if (root)
      {
        // Solid points now: the substrate and the drop below, exactly; the
        // new ones: powder, none on a site a point held, some under each
        // swept drop within a grain of the substrate's top.
        unsigned int n_substrate = 0, n_below_left = 0, n_other_solid = 0;
        unsigned int under_above = 0, under_lid = 0, shared = 0;
        for (std::size_t k = 0; k < after.size(); ++k)
          {
            const auto      &a = after[k];
            const Point<dim> x(a[0], a[1], a[2]);
            if (k > 0 && a[0] == after[k - 1][0] && a[1] == after[k - 1][1] &&
                a[2] == after[k - 1][2])
              ++shared;
            if (a[3] == MaterialPoints<dim>::solid)
              {
                if (x[2] < z_c)
                  ++n_substrate;
                else if (below.inside(x))
                  ++n_below_left;
                else
                  ++n_other_solid;
                continue;
              }
            const auto under = [&](const Ball &b) {
              return std::hypot(x[0] - b.c[0], x[1] - b.c[1]) < b.r &&
                     x[2] < z_c + pp.max_diameter;
            };
            under_above += under(above);
            under_lid += under(lid);
          }
        std::vector<std::array<double, 4>> added;
        std::set_difference(after.begin(),
                            after.end(),
                            before.begin(),
                            before.end(),
                            std::back_inserter(added));
        std::cout << "blade: new points = " << added.size() << " (reported "
                  << r.points
                  << "), hash of their positions = " << position_hash(added)
                  << std::endl;
        std::cout << "blade: solid points left: substrate " << n_substrate
                  << ", drop below the top " << n_below_left << ", elsewhere "
                  << n_other_solid << std::endl;
        std::cout << "blade: new points within a grain of the substrate "
                     "under the swept drops: "
                  << under_above << ", " << under_lid << std::endl;
        const unsigned int n_sub =
          nx * ny * static_cast<unsigned int>(z_c / s + 0.5);
        checks.at_most("blade: faults (drop below not whole, a swept "
                       "drop's point left, a shared site, no grain under a "
                       "swept drop, count)",
                       (n_below_left != n_below) + (n_other_solid != 0) +
                         (n_substrate != n_sub) + (shared != 0) +
                         (under_above == 0) + (under_lid == 0) +
                         (added.size() != r.points),
                       0);
      }
  }
  return checks.exit_code();
}
