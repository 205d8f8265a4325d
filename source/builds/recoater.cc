// femp: the layer schedule and the recoater of a layer-by-layer build (see
// the header and doc/builds.md, "Recoating"), on the ballistic packing of
// grid/powder_bed.h.
#include <deal.II/base/mpi.h>
#include <deal.II/base/utilities.h>

#include <femp/base/input_checks.h>
#include <femp/base/parameter_table.h>
#include <femp/builds/recoater.h>
#include <femp/grid/metal_bodies.h>
#include <femp/grid/powder_bed.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace femp
{
  const Choices<LayerSource> &
  layer_source_names()
  {
    static const Choices<LayerSource> names = {{LayerSource::none, "none"},
                                               {LayerSource::scan_path,
                                                "scan path"},
                                               {LayerSource::times, "times"}};
    return names;
  }

  template <int dim>
  void
  LayerSchedule<dim>::Parameters::add_parameters(ParameterTable &table)
  {
    ParameterHandler &prm = table.handler();
    table.enter_subsection("Build");
    table.add(
      "Layer schedule",
      source,
      layer_source_names(),
      "When a new powder layer is spread (doc/builds.md). none: one layer "
      "(the scene's powder). 'scan path': a layer starts where the height of "
      "the scan path's segments rises (Laser/Scan path file in a format "
      "with heights), its powder reaching the first layer's top plus the "
      "rise. times: at 'Layer start times', each 'Layer thickness' higher.");
    table.add("Layer thickness",
              thickness,
              Patterns::Double(0.),
              "With 'Layer schedule = times': how much higher each "
              "new layer's powder reaches than the last, m; range "
              "(0, inf).");
    if (table.declaring())
      prm.declare_entry("Layer start times",
                        "",
                        Patterns::Anything(),
                        "With 'Layer schedule = times': the times at which the "
                        "layers after the first are spread, s, increasing and "
                        "positive, separated by ','.");
    table.add("Powder temperature",
              powder_temperature,
              Patterns::Double(0.),
              "Temperature of the spread powder, K; 0: the ambient "
              "(Heat transfer/Reference temperature). Range [0, "
              "inf).");
    table.add(
      "Rebalance above imbalance",
      rebalance_above,
      Patterns::Double(0.),
      "At the end of the step in which a layer starts (after its recoat "
      "and hand-over), with 'Background grid/Partition = cost' on several "
      "ranks and the solid on: when the busiest rank holds more than this "
      "many times the mean over the ranks of the solid's MPM points, the "
      "run writes a checkpoint and goes on from it on a grid cut by its "
      "state, as 'femp --resume' with 'Checkpoint/Partition on resume = "
      "checkpoint' does (doc/builds.md); that checkpoint is kept only "
      "until the next one. Refused with 'Background grid/Partition = "
      "cells'; on one rank, without the solid or with one layer it is "
      "inert (the scene's printout says so). Ratio, unit none; 0: "
      "never; otherwise range [1, inf).");
    table.leave_subsection();
  }

  template <int dim>
  void
  LayerSchedule<dim>::Parameters::declare_parameters(ParameterHandler &prm)
  {
    Parameters     defaults;
    ParameterTable table(prm, ParameterTable::Mode::declare);
    defaults.add_parameters(table);
  }

  template <int dim>
  void
  LayerSchedule<dim>::Parameters::parse_parameters(ParameterHandler &prm)
  {
    ParameterTable table(prm, ParameterTable::Mode::parse);
    add_parameters(table);
    prm.enter_subsection("Build");
    const std::string times = prm.get("Layer start times");
    prm.leave_subsection();
    require(rebalance_above == 0 || rebalance_above >= 1,
            "Build/Rebalance above imbalance",
            rebalance_above,
            "it must be 0 (never) or a ratio in [1, inf) (the busiest "
            "rank's MPM points over their mean over the ranks)");
    start_times.clear();
    for (const auto &t : Utilities::split_string_list(times, ','))
      {
        char        *end = nullptr;
        const double v   = std::strtod(t.c_str(), &end);
        require(end != t.c_str() && *end == '\0' && v > 0 &&
                  (start_times.empty() || v > start_times.back()),
                "Build/Layer start times",
                times,
                "it must list increasing positive times (s) separated by ','");
        start_times.push_back(v);
      }
    if (source == LayerSource::times)
      {
        require(!start_times.empty(),
                "Build/Layer start times",
                times,
                "'Layer schedule = times' needs at least one start time");
        require(thickness > 0,
                "Build/Layer thickness",
                thickness,
                "it must be positive (m)");
      }
  }

  template <int dim>
  LayerSchedule<dim>::LayerSchedule(
    const Parameters                                &prm,
    const std::vector<typename Laser<dim>::Segment> &segments,
    const double                                     first_top,
    const double                                     domain_top,
    const double                                     cell_size)
  {
    if (prm.source == LayerSource::times)
      for (unsigned int k = 0; k < prm.start_times.size(); ++k)
        list.push_back({k + 2,
                        prm.start_times[k],
                        first_top + (k + 1) * prm.thickness,
                        prm.thickness});
    else if (prm.source == LayerSource::scan_path && !segments.empty())
      {
        // The first layer: the height of the first segment with the laser
        // on (moves before it place the beam). A later layer starts with
        // the first segment that ends higher than the layer before (the
        // jump up to it). A path at one height is one layer (no layer
        // after the first). The layer in progress when a segment starts is
        // the last layer begun before that segment: a jump up is scanned
        // from the layer it leaves. A segment with the laser on that starts
        // or ends below the layer in progress scans below it, where no
        // layer of a schedule that only rises is: refused. The first
        // segment with the laser on begins layer 1 and only its end is
        // read (no layer is in progress before it; an AdditiveFOAM path
        // starts at the origin).
        auto seg = segments.begin();
        while (seg != segments.end() && seg->power <= 0)
          ++seg;
        const auto   first_on = seg;
        const double z1       = seg != segments.end() ? seg->end[dim - 1] : 0.;
        double       z        = z1;
        const auto   refuse_below = [&](const typename Laser<dim>::Segment &s,
                                      const std::string                  &which,
                                      const double height) {
          require(false,
                  "Build/Layer schedule",
                  choice_name(prm.source, layer_source_names()),
                  "the scan path goes down: its segment from t = " +
                    num(s.t_begin) + " s to " + num(s.t_end) +
                    " s, with the laser on, " + which + " at the height " +
                    num(height) + " m, below the height " + num(z) +
                    " m of layer " + std::to_string(list.size() + 1) +
                    " (Laser/Scan path file: with the laser on, the path "
                      "must not go below the layer in progress)");
        };
        for (; seg != segments.end(); ++seg)
          {
            const auto &s = *seg;
            if (s.power > 0 && seg != first_on && s.start[dim - 1] < z - 1e-9)
              refuse_below(s, "starts", s.start[dim - 1]);
            if (s.end[dim - 1] > z + 1e-9)
              {
                list.push_back({static_cast<unsigned int>(list.size() + 2),
                                s.t_begin,
                                first_top + (s.end[dim - 1] - z1),
                                s.end[dim - 1] - z});
                z = s.end[dim - 1];
              }
            else if (s.power > 0 && s.end[dim - 1] < z - 1e-9)
              refuse_below(s, "ends", s.end[dim - 1]);
          }
      }
    // The last layer's powder must leave two cells of gas below the top.
    if (!list.empty())
      {
        const Layer &last = list.back();
        require(last.top <= domain_top - 2 * cell_size * (1 - 1e-9),
                prm.source == LayerSource::times ? "Build/Layer start times" :
                                                   "Build/Layer schedule",
                choice_name(prm.source, layer_source_names()),
                "layer " + std::to_string(last.number) + "'s powder reaches " +
                  num(last.top) + " m, above the domain's top " +
                  num(domain_top) + " m less two cells (" +
                  num(domain_top - 2 * cell_size) +
                  " m): raise Grid/Upper corner or use fewer or thinner "
                  "layers");
      }
  }

  template <int dim>
  std::vector<typename LayerSchedule<dim>::Layer>
  LayerSchedule<dim>::starting_in(const double t0, const double t1) const
  {
    std::vector<Layer> due;
    for (const auto &l : list)
      if (l.start_time > t0 && l.start_time <= t1 * (1 + 1e-12))
        due.push_back(l);
    return due;
  }

  template <int dim>
  Recoater<dim>::Recoater(
    const typename MaterialPoints<dim>::Parameters &powder,
    const double                                    density,
    const BackgroundGrid<dim>                      &grid)
      : powder(powder)
      , density(density)
      , grid(grid)
  {
    const double s = powder.point_spacing;
    for (int d = 0; d < dim - 1; ++d)
      n_columns[d] = static_cast<unsigned int>(
        std::ceil(grid.n_cells()[d] * grid.h() / s * (1 - 1e-12)));
  }

  template <int dim>
  std::size_t
  Recoater<dim>::column_of(const Point<dim> &x) const
  {
    const double s  = powder.point_spacing;
    const auto  &x0 = grid.origin();
    std::size_t  c  = 0;
    for (int d = dim - 2; d >= 0; --d)
      {
        const long i = static_cast<long>(std::floor((x[d] - x0[d]) / s));
        c = c * n_columns[d] + std::clamp<long>(i, 0, long(n_columns[d]) - 1);
      }
    return c;
  }

  template <int dim>
  std::array<std::vector<double>, 2>
  Recoater<dim>::column_tops(const MaterialPoints<dim>       &points,
                             const std::vector<std::uint8_t> &attached,
                             const std::vector<double>       *skip) const
  {
    const double      s  = powder.point_spacing;
    const double      z0 = grid.origin()[dim - 1];
    const std::size_t n  = std::size_t(n_columns[0]) * n_columns[1];
    std::array<std::vector<double>, 2> top{
      {std::vector<double>(n, z0), std::vector<double>(n, z0)}};
    for (const auto &[idx, cell] : points.occupied_cells())
      {
        if (skip && (*skip)[idx] > 0)
          continue;
        auto &t = top[attached[idx] ? 0 : 1];
        for (const auto &p : points.particle_handler().particles_in_cell(cell))
          {
            const Point<dim> &x = p.get_location();
            double           &z = t[column_of(x)];
            z                   = std::max(z, x[dim - 1] + 0.5 * s);
          }
      }
    return top;
  }

  template <int dim>
  typename Recoater<dim>::Surface
  Recoater<dim>::surface(const MaterialPoints<dim>       &points,
                         const std::vector<std::uint8_t> &attached) const
  {
    auto    top = column_tops(points, attached, nullptr);
    Surface surf;
    for (auto &t : top)
      Utilities::MPI::max(ArrayView<const double>(t),
                          grid.communicator(),
                          ArrayView<double>(t));
    surf.attached = top[0];
    surf.rest     = top[0];
    for (std::size_t c = 0; c < surf.rest.size(); ++c)
      surf.rest[c] = std::max(top[0][c], top[1][c]);
    return surf;
  }

  template <int dim>
  typename Recoater<dim>::Report
  Recoater<dim>::recoat(MaterialPoints<dim>                      &points,
                        const typename LayerSchedule<dim>::Layer &layer,
                        const double                              T,
                        const std::vector<double>                &alpha,
                        const std::vector<std::uint8_t>          &attached,
                        const std::function<double(double)>      &per_mass,
                        const RemovalHook &before_removal) const
  {
    using P              = typename MaterialPoints<dim>::PropertyIndex;
    const int    v       = dim - 1;
    const double s       = powder.point_spacing;
    const auto  &x0      = grid.origin();
    const double h       = grid.h();
    const double area    = dim == 3 ? s * s : s;
    auto        &handler = points.particle_handler_for_update();

    Report r;
    r.layer = layer.number;

    // 1. The blade. Seeds: the detached metal cells holding a point whose
    // top lies above the blade (round-off of the lattice's positions
    // allowed), labelled by their global index + 1; the fill over the
    // detached metal (attached cells masked) names each body swept by its
    // least seed.
    const double        blade  = layer.top + 1e-6 * s;
    std::vector<double> seeds  = grid.make_field(0.);
    std::vector<double> metal  = alpha;
    const auto         &n_cell = grid.n_cells();
    for (const auto &[idx, cell] : points.occupied_cells())
      {
        if (attached[idx])
          continue;
        for (const auto &p : handler.particles_in_cell(cell))
          if (p.get_location()[v] + 0.5 * s > blade)
            {
              const auto ijk = grid.global_index(idx);
              double     id  = 0;
              for (int d = dim - 1; d >= 0; --d)
                id = id * n_cell[d] + ijk[d];
              seeds[idx] = id + 1;
              break;
            }
      }
    for (const auto idx : grid.owned_cells())
      if (attached[idx])
        metal[idx] = 0;
    const std::vector<double> swept = label_metal_bodies(grid, metal, seeds);
    // The swept points (each cell's, in the handler's order), their mass
    // and heat; the bodies: the distinct labels over all ranks.
    std::vector<types::particle_index> gone_ids;
    std::vector<double>                labels;
    double                             local[2] = {0, 0}; // mass, heat
    for (const auto &[idx, cell] : points.occupied_cells())
      if (swept[idx] > 0)
        {
          labels.push_back(swept[idx]);
          for (const auto &p : handler.particles_in_cell(cell))
            {
              const double m = p.get_properties()[P::mass];
              local[0] += m;
              if (per_mass)
                local[1] += m * per_mass(p.get_properties()[P::temperature]);
              gone_ids.push_back(p.get_id());
            }
        }
    std::sort(labels.begin(), labels.end());
    labels.erase(std::unique(labels.begin(), labels.end()), labels.end());
    std::vector<double> all_labels;
    for (const auto &part :
         Utilities::MPI::all_gather(grid.communicator(), labels))
      all_labels.insert(all_labels.end(), part.begin(), part.end());
    std::sort(all_labels.begin(), all_labels.end());
    all_labels.erase(std::unique(all_labels.begin(), all_labels.end()),
                     all_labels.end());
    r.swept_bodies = all_labels.size();
    r.swept_points =
      Utilities::MPI::sum<std::uint64_t>(gone_ids.size(), grid.communicator());
    // Whoever counts points (the solid) learns of them before they go
    // (every rank, when any rank sweeps); then the iterators to delete
    // (the call may have rewritten the points' properties, not moved them).
    if (r.swept_points > 0 && before_removal)
      before_removal(gone_ids);
    std::vector<typename Particles::ParticleHandler<dim>::particle_iterator>
      gone;
    for (const auto &[idx, cell] : points.occupied_cells())
      if (swept[idx] > 0)
        {
          auto range = handler.particles_in_cell(cell);
          for (auto it = range.begin(); it != range.end(); ++it)
            gone.push_back(it);
        }
    {
      double global[2];
      Utilities::MPI::sum(ArrayView<const double>(local, 2),
                          grid.communicator(),
                          ArrayView<double>(global, 2));
      r.swept_mass     = global[0];
      r.swept_enthalpy = global[1];
    }

    // 2. The surface of what is left: the attached metal's tops, and the
    // resting height with the detached metal below the blade.
    auto top = column_tops(points, attached, &swept);
    for (auto &t : top)
      Utilities::MPI::max(ArrayView<const double>(t),
                          grid.communicator(),
                          ArrayView<double>(t));
    const std::vector<double> &surface_z = top[0];
    std::vector<double>        floor_z   = top[0];
    for (std::size_t c = 0; c < floor_z.size(); ++c)
      if (top[1][c] > top[0][c])
        {
          floor_z[c] = top[1][c];
          ++r.columns_on_drops;
        }
    // Delete the swept points; the handler is re-indexed with the new
    // powder below (insert_powder()). The new ids follow the largest one
    // before the sweep: deleting the points of the highest ids lowers the
    // handler's next free id, and an id of a swept point given to a new
    // one would make it the swept point for whoever tracks points by id
    // (the solid's members).
    const types::particle_index first_free =
      handler.get_next_free_particle_index();
    handler.remove_particles(gone);

    r.surface_min = *std::min_element(surface_z.begin(), surface_z.end());
    r.surface_max = *std::max_element(surface_z.begin(), surface_z.end());
    const double rest_min = *std::min_element(floor_z.begin(), floor_z.end());
    for (const double z : floor_z)
      r.fill_volume += std::max(0., layer.top - z) * area;
    if (r.fill_volume <= 0 || rest_min >= layer.top)
      {
        // Nothing to spread; the swept points leave all the same.
        if (r.swept_points > 0)
          {
            std::vector<std::pair<std::uint32_t, Point<dim>>> none;
            insert_powder(points, none, T, first_free);
          }
        return r;
      }

    // The bed is periodic across the lateral faces (the bed goes on beyond
    // them): grains that cross a face come back through the opposite one,
    // so the volume of grains placed is the volume inside the domain, and
    // no grain rests on a lateral face (a bed cut there is looser at the
    // faces and denser inside).
    PowderBedSpec spec;
    spec.dim      = dim;
    spec.periodic = true;
    for (int d = 0; d < dim; ++d)
      {
        spec.lower[d] = x0[d];
        spec.upper[d] = x0[d] + grid.n_cells()[d] * h;
      }
    spec.lower[v]         = rest_min;
    spec.upper[v]         = layer.top;
    spec.mean_diameter    = powder.mean_diameter;
    spec.std_diameter     = powder.std_diameter;
    spec.min_diameter     = powder.min_diameter;
    spec.max_diameter     = powder.max_diameter;
    spec.packing_fraction = powder.packing_fraction;
    spec.seed             = powder.seed + 7919ull * layer.number;
    spec.fill_volume      = r.fill_volume;
    // Column index of horizontal lattice index i (x) and j (y).
    const auto column = [&](const long i, const long j) {
      return std::size_t(i) + std::size_t(n_columns[0]) * std::size_t(j);
    };
    // A grain of radius rad at c rests where it first touches the surface
    // (the heights at the column centres within its radius).
    spec.rest_height = [&](const std::array<double, 3> &c, const double rad) {
      double z     = -std::numeric_limits<double>::infinity();
      long   lo[2] = {0, 0}, hi[2] = {0, 0};
      for (int d = 0; d < dim - 1; ++d)
        {
          lo[d] = long(std::floor((c[d] - rad - x0[d]) / s - 0.5));
          hi[d] = long(std::ceil((c[d] + rad - x0[d]) / s - 0.5));
        }
      for (long j = lo[1]; j <= hi[1]; ++j)
        for (long i = lo[0]; i <= hi[0]; ++i)
          {
            double     d2     = 0;
            const long idx[2] = {i, j};
            for (int d = 0; d < dim - 1; ++d)
              {
                const double dx = x0[d] + (idx[d] + 0.5) * s - c[d];
                d2 += dx * dx;
              }
            // Beyond a lateral face: the periodic image's column.
            const long n0 = n_columns[0], n1 = n_columns[1];
            const long ci = ((i % n0) + n0) % n0;
            const long cj = ((j % n1) + n1) % n1;
            if (d2 <= rad * rad)
              z = std::max(z,
                           floor_z[column(ci, cj)] + std::sqrt(rad * rad - d2));
          }
      return z;
    };
    const PowderBed bed = pack_powder_bed(spec);
    r.grains            = bed.grains.size();
    r.packing           = bed.achieved_packing_fraction;

    // The lattice points inside each grain, above the surface of their
    // column, in owned cells.
    std::vector<std::pair<std::uint32_t, Point<dim>>> added;
    // Each grain and its periodic images across the lateral faces.
    std::vector<Grain> images;
    for (const auto &g : bed.grains)
      for (int a = -1; a <= 1; ++a)
        for (int b = (dim == 3 ? -1 : 0); b <= (dim == 3 ? 1 : 0); ++b)
          {
            Grain     i     = g;
            const int k[2]  = {a, b};
            bool      reach = true;
            for (int d = 0; d < dim - 1; ++d)
              {
                const double L = spec.upper[d] - spec.lower[d];
                i.center[d] += k[d] * L;
                reach = reach && i.center[d] + i.radius > spec.lower[d] &&
                        i.center[d] - i.radius < spec.upper[d];
              }
            if (reach)
              images.push_back(i);
          }
    for (const auto &g : images)
      {
        std::array<long, dim> first, last;
        bool                  empty = false;
        for (int d = 0; d < dim; ++d)
          {
            const double lo = std::max(g.center[d] - g.radius, x0[d]);
            const double hi =
              std::min(g.center[d] + g.radius, x0[d] + grid.n_cells()[d] * h);
            first[d] = static_cast<long>(std::ceil((lo - x0[d]) / s - 0.5));
            last[d]  = static_cast<long>(std::ceil((hi - x0[d]) / s - 0.5)) - 1;
            empty    = empty || last[d] < first[d];
          }
        if (empty)
          continue;
        std::array<long, dim> i = first;
        for (bool more = true; more;)
          {
            Point<dim> p;
            double     r2 = 0;
            for (int d = 0; d < dim; ++d)
              {
                p[d] = x0[d] + (i[d] + 0.5) * s;
                r2 += (p[d] - g.center[d]) * (p[d] - g.center[d]);
              }
            const std::size_t col =
              column(std::clamp<long>(i[0], 0, n_columns[0] - 1),
                     dim == 3 ? std::clamp<long>(i[1], 0, n_columns[1] - 1) :
                                0);
            if (r2 <= g.radius * g.radius && p[v] >= floor_z[col] &&
                grid.in_domain(p))
              {
                const auto ijk = grid.cell_of(p);
                if (grid.in_box(ijk))
                  {
                    const auto idx = grid.local_index(ijk);
                    if (grid.cell_status()[idx] == BackgroundGrid<dim>::owned)
                      added.emplace_back(idx, p);
                  }
              }
            int d = 0;
            for (; d < dim; ++d)
              {
                if (++i[d] <= last[d])
                  break;
                i[d] = first[d];
              }
            more = d < dim;
          }
      }
    // Two grains may share a lattice site where they touch: keep one.
    std::sort(added.begin(), added.end(), [](const auto &a, const auto &b) {
      if (a.first != b.first)
        return a.first < b.first;
      for (int d = dim - 1; d >= 0; --d)
        if (a.second[d] != b.second[d])
          return a.second[d] < b.second[d];
      return false;
    });
    added.erase(std::unique(added.begin(),
                            added.end(),
                            [](const auto &a, const auto &b) {
                              return a.first == b.first && a.second == b.second;
                            }),
                added.end());
    r.points =
      Utilities::MPI::sum<std::uint64_t>(added.size(), grid.communicator());
    r.point_volume = r.points * std::pow(s, dim);
    insert_powder(points, added, T, first_free);
    return r;
  }

  template <int dim>
  void
  Recoater<dim>::insert_powder(
    MaterialPoints<dim>                               &points,
    std::vector<std::pair<std::uint32_t, Point<dim>>> &added,
    const double                                       T,
    const types::particle_index                        first_free) const
  {
    // Ids after the largest one in use, numbered across the ranks in rank
    // order; then the handler sorts them into its cells and the points'
    // cache is rebuilt (MaterialPoints::points_moved()).
    using P                 = typename MaterialPoints<dim>::PropertyIndex;
    auto         &handler   = points.particle_handler_for_update();
    std::uint64_t n_local64 = added.size(), offset64 = 0;
    MPI_Exscan(
      &n_local64, &offset64, 1, MPI_UINT64_T, MPI_SUM, grid.communicator());
    if (Utilities::MPI::this_mpi_process(grid.communicator()) == 0)
      offset64 = 0;
    const types::particle_index first =
      std::max(first_free, handler.get_next_free_particle_index()) + offset64;
    const double        s      = powder.point_spacing;
    const double        volume = std::pow(s, dim);
    std::vector<double> props(points.n_properties(), 0.);
    props[P::mass]             = density * volume;
    props[P::volume]           = volume;
    props[P::temperature]      = T;
    props[P::peak_temperature] = T;
    props[P::state]            = MaterialPoints<dim>::powder;
    const double h             = grid.h();
    for (std::size_t n = 0; n < added.size(); ++n)
      {
        const auto       &cell = grid.cell_iterator(added[n].first);
        const Point<dim> &p    = added[n].second;
        Point<dim>        ref;
        const Point<dim>  v0 = cell->vertex(0);
        for (int d = 0; d < dim; ++d)
          ref[d] = (p[d] - v0[d]) / h;
        handler.insert_particle(
          p, ref, first + n, cell, ArrayView<const double>(props));
      }
    handler.update_cached_numbers();
    points.points_moved();
  }

  template class LayerSchedule<2>;
  template class LayerSchedule<3>;
  template class Recoater<2>;
  template class Recoater<3>;
} // namespace femp
