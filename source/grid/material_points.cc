// femp: material points on the background grid: creation of the substrate
// and the powder layer (inserted cell by cell), metal fraction by sub-cell
// occupation (by point volume in cells holding melt), and the cell-to-point
// temperature transfer (doc/method.md, "Zones and discretizations").
#include <deal.II/base/mpi.h>

#include <femp/base/input_checks.h>
#include <femp/base/parameter_table.h>
#include <femp/grid/cell_state.h>
#include <femp/grid/material_points.h>
#include <femp/grid/powder_bed.h>
#include <femp/grid/saved_points.h>

#include <algorithm>
#include <array>
#include <bitset>
#include <cmath>
#include <limits>
#include <map>

namespace femp
{
  template <int dim>
  void
  MaterialPoints<dim>::Parameters::add_parameters(ParameterTable &table)
  {
    ParameterHandler &prm = table.handler();
    table.enter_subsection("Material points");
    table.add("Point spacing",
              point_spacing,
              Patterns::Double(0.),
              "Spacing of the lattice on which material points are "
              "placed, m; range (0, cell size / sub-cell divisions].");
    table.add("Substrate top",
              substrate_top,
              Patterns::Double(),
              "Vertical coordinate (z in 3D, y in 2D) of the top of the "
              "substrate block, m; the block fills the domain below it. "
              "Range [lower corner, upper corner].");
    table.add("Sub-cell divisions",
              subcells,
              Patterns::Integer(1, 4),
              "Sub-cells per direction n used to compute the metal "
              "fraction alpha by occupation (cells holding melt, i.e. "
              "a point that is or has been fluid, take the volume of "
              "their points instead); range 1..4.");
    table.add(
      "Carry points",
      carry,
      {{AutoSwitch::automatic, "auto"}, {AutoSwitch::on, "always"}},
      "Whether the scene carries material points. 'auto': only where "
      "something needs them, i.e. a powder layer (Layer thickness > 0), "
      "initial bodies, Physics/Melt flow, Physics/Solid stress or the "
      "track shape output (the points' melt history); a bare plate under "
      "a laser carries none: its metal fraction alpha comes from the "
      "substrate's lattice (the same alpha the points would give), the "
      "per-step transfer of temperatures to points costs nothing, and "
      "no point files are written. 'always': points in every scene (to "
      "write them).");
    table.enter_subsection("Powder layer");
    table.add("Layer thickness",
              layer_thickness,
              Patterns::Double(0.),
              "Thickness of the powder layer on the substrate, m; 0 for "
              "no powder. Range [0, upper corner - substrate top].");
    table.add("Mean grain diameter",
              mean_diameter,
              Patterns::Double(0.),
              "Mean diameter of the normally distributed grain sizes, m.");
    table.add("Grain diameter deviation",
              std_diameter,
              Patterns::Double(0.),
              "Standard deviation of the grain diameters, m; range [0, inf).");
    table.add("Minimum grain diameter",
              min_diameter,
              Patterns::Double(0.),
              "Smallest grain diameter, m (the distribution is "
              "truncated); range (0, maximum].");
    table.add("Maximum grain diameter",
              max_diameter,
              Patterns::Double(0.),
              "Largest grain diameter, m; also capped by the layer "
              "thickness. Range [minimum, inf).");
    table.add("Packing fraction",
              packing_fraction,
              Patterns::Double(0., 0.64),
              "Target volume fraction of grains in the layer; random "
              "sequential addition reaches about 0.3-0.45 (3D). Range "
              "(0, 0.64].");
    table.add("Random seed",
              seed,
              Patterns::Integer(0),
              "Seed of the packing; the same seed gives the same bed.");
    table.leave_subsection();
    if (table.declaring())
      prm.declare_entry(
        "Initial bodies",
        "",
        Patterns::Anything(),
        "Bodies of material points placed at the start besides the substrate "
        "and the powder (flow scenes: a liquid column, a drop, a pool), "
        "separated by ';'. Each is 'STATE box: x0,y0[,z0] -> x1,y1[,z1] : T' "
        "(lower and upper corner, m) or 'STATE ellipsoid: cx,cy[,cz] -> "
        "ax,ay[,az] : T' (centre and semi-axes, m; equal semi-axes give a "
        "circle or sphere), with STATE one of fluid, solid, powder and T the "
        "temperature of its points, K (range (0, inf); the cells it fills take "
        "the mean temperature of their points). A body must lie inside the "
        "domain and must not overlap the powder layer; below the substrate "
        "top it re-states the substrate's points. Empty (default): none.");
    table.leave_subsection();
  }

  template <int dim>
  void
  MaterialPoints<dim>::Parameters::declare_parameters(ParameterHandler &prm)
  {
    Parameters     defaults;
    ParameterTable table(prm, ParameterTable::Mode::declare);
    defaults.add_parameters(table);
  }

  template <int dim>
  void
  MaterialPoints<dim>::Parameters::parse_parameters(ParameterHandler &prm)
  {
    ParameterTable table(prm, ParameterTable::Mode::parse);
    add_parameters(table);
    prm.enter_subsection("Material points");
    prm.enter_subsection("Powder layer");
    prm.leave_subsection();
    const std::string list = prm.get("Initial bodies");
    prm.leave_subsection();
    bodies.clear();
    const std::string name = "Material points/Initial bodies";
    const std::string form =
      "each body must read 'STATE box: x0,y0[,z0] -> x1,y1[,z1] : T' or "
      "'STATE ellipsoid: centre -> semi-axes : T' with STATE fluid, solid or "
      "powder, " +
      std::to_string(dim) + " coordinates per point (m) and T > 0 (K)";
    const auto to_point = [&](const std::string &text,
                              const std::string &body) {
      const auto parts = Utilities::split_string_list(text, ',');
      require(parts.size() == dim, name, body, form);
      Point<dim> x;
      for (int d = 0; d < dim; ++d)
        {
          try
            {
              x[d] = Utilities::string_to_double(parts[d]);
            }
          catch (...)
            {
              require(false, name, body, form);
            }
        }
      return x;
    };
    for (const auto &body_text : Utilities::split_string_list(list, ';'))
      {
        if (body_text.empty())
          continue;
        const auto parts = Utilities::split_string_list(body_text, ':');
        require(parts.size() == 3, name, body_text, form);
        Body body;
        body.text        = body_text;
        const auto words = Utilities::split_string_list(parts[0], ' ');
        std::vector<std::string> w;
        for (const auto &x : words)
          if (!x.empty())
            w.push_back(x);
        require(w.size() == 2 &&
                  (w[0] == "fluid" || w[0] == "solid" || w[0] == "powder") &&
                  (w[1] == "box" || w[1] == "ellipsoid"),
                name,
                body_text,
                form);
        body.state =
          w[0] == "fluid" ? fluid : (w[0] == "solid" ? solid : powder);
        body.box         = w[1] == "box";
        const auto arrow = parts[1].find("->");
        require(arrow != std::string::npos, name, body_text, form);
        body.a = to_point(parts[1].substr(0, arrow), body_text);
        body.b = to_point(parts[1].substr(arrow + 2), body_text);
        try
          {
            body.T = Utilities::string_to_double(parts[2]);
          }
        catch (...)
          {
            require(false, name, body_text, form);
          }
        require(body.T > 0, name, body_text, form);
        for (int d = 0; d < dim; ++d)
          require(body.box ? body.b[d] > body.a[d] : body.b[d] > 0,
                  name,
                  body_text,
                  body.box ? "the upper corner must exceed the lower corner in "
                             "every direction" :
                             "the semi-axes must be positive (m)");
        bodies.push_back(body);
      }
    require(point_spacing > 0,
            "Material points/Point spacing",
            point_spacing,
            "it must be positive (m)");
    require(min_diameter > 0 && min_diameter <= max_diameter,
            "Material points/Powder layer/Minimum grain diameter",
            min_diameter,
            "it must be positive and not exceed the maximum grain diameter");
  }

  template <int dim>
  void
  MaterialPoints<dim>::Parameters::check(
    const typename BackgroundGrid<dim>::Parameters &g) const
  {
    require(point_spacing <= g.cell_size / subcells * (1 + 1e-9),
            "Material points/Point spacing",
            point_spacing,
            "it must not exceed cell size / sub-cell divisions = " +
              num(g.cell_size / subcells) +
              " m, so that every sub-cell of a full cell holds a point");
    const double lo = g.lower_corner[dim - 1], hi = g.upper_corner[dim - 1];
    require(substrate_top >= lo && substrate_top <= hi,
            "Material points/Substrate top",
            substrate_top,
            "it must lie in the vertical extent of the domain [" + num(lo) +
              ", " + num(hi) + "] m");
    require(substrate_top + layer_thickness <= hi * (1 + 1e-12),
            "Material points/Powder layer/Layer thickness",
            layer_thickness,
            "the powder layer must fit below the top of the domain (at most " +
              num(hi - substrate_top) + " m)");
    for (const auto &body : bodies)
      {
        Point<dim> lower = body.a, upper = body.b;
        if (!body.box)
          lower = body.a - body.b, upper = body.a + body.b;
        std::string domain = "[";
        for (int d = 0; d < dim; ++d)
          domain += num(g.lower_corner[d]) + ", " + num(g.upper_corner[d]) +
                    (d + 1 < dim ? "] x [" : "]");
        for (int d = 0; d < dim; ++d)
          require(lower[d] >=
                      g.lower_corner[d] - 1e-12 * std::abs(g.lower_corner[d]) &&
                    upper[d] <=
                      g.upper_corner[d] + 1e-12 * std::abs(g.upper_corner[d]),
                  "Material points/Initial bodies",
                  body.text,
                  "each body must lie inside the domain " + domain + " m");
        require(layer_thickness <= 0 ||
                  lower[dim - 1] >= substrate_top + layer_thickness ||
                  upper[dim - 1] <= substrate_top,
                "Material points/Initial bodies",
                body.text,
                "a body must not overlap the powder layer [" +
                  num(substrate_top) + ", " +
                  num(substrate_top + layer_thickness) + "] m (vertical)");
      }
  }

  template <int dim>
  void
  MaterialPoints<dim>::Parameters::resolve_carry(const bool melt_flow,
                                                 const bool solid,
                                                 const bool track_shape)
  {
    carry_points = carry == AutoSwitch::on || layer_thickness > 0 ||
                   !bodies.empty() || melt_flow || solid || track_shape;
  }

  template <int dim>
  bool
  MaterialPoints<dim>::Parameters::Body::inside(const Point<dim> &p) const
  {
    if (box)
      {
        for (int d = 0; d < dim; ++d)
          if (p[d] < a[d] || p[d] > b[d])
            return false;
        return true;
      }
    double r = 0;
    for (int d = 0; d < dim; ++d)
      r += (p[d] - a[d]) * (p[d] - a[d]) / (b[d] * b[d]);
    return r < 1;
  }

  template <int dim>
  MaterialPoints<dim>::MaterialPoints(const Parameters          &prm,
                                      const Material            &material,
                                      const BackgroundGrid<dim> &grid,
                                      const unsigned int         n_properties)
      : prm(prm)
      , n_props(n_properties)
      , mat(material)
      , grid(grid)
  {
    Assert(n_props == PropertyIndex::n_used(false, false) ||
             n_props == PropertyIndex::n_used(true, false) ||
             n_props == PropertyIndex::n_used(true, true),
           ExcMessage(
             "MaterialPoints: the property count must end a layout block"));
  }

  template <int dim>
  std::vector<std::string>
  MaterialPoints<dim>::property_names(const unsigned int n)
  {
    std::vector<std::string> names = {
      "mass", "volume", "temperature", "state", "peak_temperature"};
    for (int d = 0; d < dim; ++d)
      names.push_back(std::string("velocity_") + char('x' + d));
    const char *s2[] = {"stress_xx", "stress_yy", "stress_xy"};
    const char *s3[] = {"stress_xx",
                        "stress_yy",
                        "stress_zz",
                        "stress_xy",
                        "stress_xz",
                        "stress_yz"};
    for (int i = 0; i < dim * (dim + 1) / 2; ++i)
      names.push_back(dim == 2 ? s2[i] : s3[i]);
    names.push_back("plastic_strain");
    if (dim == 2)
      names.push_back("stress_zz");
    names.push_back("viscous_pressure");
    for (int i = 0; i < dim; ++i)
      for (int j = 0; j < dim; ++j)
        names.push_back(std::string("affine_velocity_") + char('x' + i) +
                        char('x' + j));
    names.resize(std::min<std::size_t>(n, names.size()));
    return names;
  }

  template <int dim>
  void
  MaterialPoints<dim>::create(const double T0)
  {
    handler.initialize(grid.triangulation(), mapping, n_props);
    if (!prm.carry_points)
      {
        // A bare plate: no points (metal_fraction() from the lattice).
        occupied.clear();
        cache_point_handles();
        return;
      }

    const double s  = prm.point_spacing;
    const double h  = grid.h();
    const auto  &x0 = grid.origin();

    // Points per owned cell, as (flat index, position), gathered first.
    std::vector<std::pair<std::uint32_t, Point<dim>>> points;

    // Substrate block: the lattice below the substrate top.
    for (const auto idx : grid.owned_cells())
      add_lattice_points(idx, prm.substrate_top, nullptr, points);

    // Powder layer: the same bed on every rank; keep points of owned cells.
    if (prm.layer_thickness > 0)
      {
        PowderBedSpec spec;
        spec.dim = dim;
        for (int d = 0; d < dim; ++d)
          {
            spec.lower[d] = x0[d];
            spec.upper[d] = x0[d] + grid.n_cells()[d] * h;
          }
        spec.lower[dim - 1]   = prm.substrate_top;
        spec.upper[dim - 1]   = prm.substrate_top + prm.layer_thickness;
        spec.mean_diameter    = prm.mean_diameter;
        spec.std_diameter     = prm.std_diameter;
        spec.min_diameter     = prm.min_diameter;
        spec.max_diameter     = prm.max_diameter;
        spec.packing_fraction = prm.packing_fraction;
        spec.seed             = prm.seed;
        const PowderBed bed   = pack_powder_bed(spec);
        n_grains              = bed.grains.size();
        packing               = bed.achieved_packing_fraction;
        for (const auto &g : bed.grains)
          {
            std::array<long, dim> first, last;
            for (int d = 0; d < dim; ++d)
              {
                const double lo =
                  std::max(g.center[d] - g.radius, spec.lower[d]);
                const double hi = std::min(g.center[d] + g.radius,
                                           x0[d] + grid.n_cells()[d] * h);
                first[d] = static_cast<long>(std::ceil((lo - x0[d]) / s - 0.5));
                last[d] =
                  static_cast<long>(std::ceil((hi - x0[d]) / s - 0.5)) - 1;
              }
            std::array<long, dim> i    = first;
            bool                  done = false;
            for (int d = 0; d < dim; ++d)
              done = done || last[d] < first[d];
            while (!done)
              {
                Point<dim> p;
                double     r2 = 0;
                for (int d = 0; d < dim; ++d)
                  {
                    p[d] = x0[d] + (i[d] + 0.5) * s;
                    r2 += (p[d] - g.center[d]) * (p[d] - g.center[d]);
                  }
                if (r2 <= g.radius * g.radius &&
                    p[dim - 1] >= prm.substrate_top)
                  {
                    const auto ijk = grid.cell_of(p);
                    if (grid.in_box(ijk))
                      {
                        const auto idx = grid.local_index(ijk);
                        if (grid.cell_status()[idx] ==
                            BackgroundGrid<dim>::owned)
                          points.emplace_back(idx, p);
                      }
                  }
                int d = 0;
                for (; d < dim; ++d)
                  {
                    if (++i[d] <= last[d])
                      break;
                    i[d] = first[d];
                  }
                done = (d == dim);
              }
          }
      }

    // Initial bodies: their lattice points above the substrate top.
    if (!prm.bodies.empty())
      for (const auto idx : grid.owned_cells())
        add_lattice_points(
          idx,
          std::numeric_limits<double>::infinity(),
          [this](const Point<dim> &p) {
            if (p[dim - 1] < prm.substrate_top)
              return false;
            for (const auto &b : prm.bodies)
              if (b.inside(p))
                return true;
            return false;
          },
          points);

    insert_points(points, T0, [this](const Point<dim> &p) {
      return p[dim - 1] < prm.substrate_top ? solid : powder;
    });
    if (prm.bodies.empty())
      return;
    // State and temperature of the points inside bodies (last body wins).
    using P = PropertyIndex;
    for (auto &particle : handler)
      {
        const Point<dim> p = particle.get_location();
        for (auto b = prm.bodies.rbegin(); b != prm.bodies.rend(); ++b)
          if (b->inside(p))
            {
              auto v                 = particle.get_properties();
              v[P::state]            = b->state;
              v[P::temperature]      = b->T;
              v[P::peak_temperature] = b->T;
              break;
            }
      }
  }

  template <int dim>
  void
  MaterialPoints<dim>::add_lattice_points(
    const std::uint32_t                                idx,
    const double                                       vertical_limit,
    const std::function<bool(const Point<dim> &)>     &keep,
    std::vector<std::pair<std::uint32_t, Point<dim>>> &points) const
  {
    // Global lattice x = x0 + (i + 1/2) s; the points of cell idx below
    // vertical_limit (and accepted by keep, if given).
    const double          s   = prm.point_spacing;
    const double          h   = grid.h();
    const auto           &x0  = grid.origin();
    const auto            ijk = grid.global_index(idx);
    std::array<long, dim> first, last;
    for (int d = 0; d < dim; ++d)
      {
        double lo = ijk[d] * h, hi = (ijk[d] + 1) * h;
        if (d == dim - 1)
          hi = std::min(hi, vertical_limit - x0[d]);
        first[d] = static_cast<long>(std::ceil(lo / s - 0.5));
        last[d]  = static_cast<long>(std::ceil(hi / s - 0.5)) - 1;
        if (last[d] < first[d])
          return;
      }
    std::array<long, dim> i = first;
    while (true)
      {
        Point<dim> p;
        for (int d = 0; d < dim; ++d)
          p[d] = x0[d] + (i[d] + 0.5) * s;
        if (!keep || keep(p))
          points.emplace_back(idx, p);
        int d = 0;
        for (; d < dim; ++d)
          {
            if (++i[d] <= last[d])
              break;
            i[d] = first[d];
          }
        if (d == dim)
          return;
      }
  }

  template <int dim>
  void
  MaterialPoints<dim>::insert_points(
    std::vector<std::pair<std::uint32_t, Point<dim>>> &points,
    const double                                       T0,
    const std::function<State(const Point<dim> &)>    &state_of)
  {
    // Insert cell by cell (stable sort keeps the lattice order in a cell),
    // with globally unique ids from an exclusive scan of the counts.
    std::stable_sort(points.begin(),
                     points.end(),
                     [](const auto &a, const auto &b) {
                       return a.first < b.first;
                     });
    // (types::particle_index is 32 bits in this deal.II build: the scan
    // goes through 64-bit integers, then the offset is narrowed.)
    std::uint64_t n_local64 = points.size(), offset64 = 0;
    MPI_Exscan(
      &n_local64, &offset64, 1, MPI_UINT64_T, MPI_SUM, grid.communicator());
    if (Utilities::MPI::this_mpi_process(grid.communicator()) == 0)
      offset64 = 0;
    const types::particle_index offset = offset64;
    ++moves_global; // the cells' points are new (point_moves())

    const double        h = grid.h();
    std::vector<double> props(n_props, 0.);
    const double        volume             = std::pow(prm.point_spacing, dim);
    props[PropertyIndex::mass]             = mat.density * volume;
    props[PropertyIndex::volume]           = volume;
    props[PropertyIndex::temperature]      = T0;
    props[PropertyIndex::peak_temperature] = T0;
    handler.reserve(points.size());
    occupied.clear();
    for (std::size_t n = 0; n < points.size(); ++n)
      {
        const auto  idx  = points[n].first;
        const auto &cell = grid.cell_iterator(idx);
        if (occupied.empty() || occupied.back().first != idx)
          occupied.emplace_back(idx, cell);
        const Point<dim> &p = points[n].second;
        Point<dim>        ref;
        const Point<dim>  v0 = cell->vertex(0);
        for (int d = 0; d < dim; ++d)
          ref[d] = (p[d] - v0[d]) / h;
        props[PropertyIndex::state] = state_of(p);
        handler.insert_particle(
          p, ref, offset + n, cell, ArrayView<const double>(props));
      }
    handler.update_cached_numbers();
    cache_point_handles();
  }

  template <int dim>
  void
  MaterialPoints<dim>::cache_point_handles()
  {
    // Where the properties of the points of each occupied cell live in the
    // property pool, so that the per-step loops write them directly (a
    // particles_in_cell() range per cell costs ~20 ns per point). Valid
    // until points are inserted, removed or re-sorted: call again then.
    point_properties.clear();
    point_locations.clear();
    point_handles.clear();
    cell_begin.assign(1, 0);
    ++layout_generation; // handles kept elsewhere may be stale now
    pushed_temperature.assign(grid.n_local(),
                              std::numeric_limits<double>::quiet_NaN());
    for (const auto &[idx, cell] : occupied)
      {
        for (auto &particle : handler.particles_in_cell(cell))
          {
            point_properties.push_back(particle.get_properties().data());
            point_locations.push_back(&particle.get_location());
            point_handles.push_back(particle.get_local_index());
          }
        cell_begin.push_back(point_properties.size());
      }
  }

  template <int dim>
  std::vector<double>
  MaterialPoints<dim>::metal_fraction() const
  {
    // Sub-cell occupancy (doc/method.md, "Heat transfer") everywhere, and, when
    // some point is fluid, the volume of the points in the cells that hold a
    // fluid point (see the header; doc/flow.md, "One fluid step").
    if (!prm.carry_points)
      return lattice_fraction();
    using P                       = PropertyIndex;
    const unsigned int         n  = prm.subcells;
    const double               ih = n / grid.h();
    const auto                &x0 = grid.origin();
    const double               Ts = mat.solidus;
    std::vector<std::uint64_t> mask(grid.n_local(), 0);
    std::vector<double>        volume(grid.n_local(), 0.);
    std::vector<double>        fluid_cell(grid.n_local(), 0.);
    bool                       any_fluid = false;
    // Over the cached position and property pointers (the points of each
    // occupied cell, in the handler's order), not deal.II's iterator.
    AssertDimension(point_locations.size(),
                    handler.n_locally_owned_particles());
    // The cell and sub-cell bit point k falls in.
    auto bin = [&](const std::size_t k, std::size_t &idx, unsigned int &bit) {
      const Point<dim>    &p = *point_locations[k];
      std::array<int, dim> ijk;
      unsigned int         m = 1;
      bit                    = 0;
      for (int d = 0; d < dim; ++d)
        {
          const int sub = static_cast<int>(std::floor((p[d] - x0[d]) * ih));
          const int c =
            std::min(std::max(sub / int(n), 0), int(grid.n_cells()[d]) - 1);
          ijk[d] = c;
          bit += m * std::min(std::max(sub - c * int(n), 0), int(n) - 1);
          m *= n;
        }
      idx = grid.local_index(ijk);
    };
    constexpr std::uint32_t not_binned =
      std::numeric_limits<std::uint32_t>::max();
    if (binned_count.size() != grid.n_local())
      {
        binned_bits.assign(grid.n_local(), 0);
        binned_volume.assign(grid.n_local(), 0.);
        binned_count.assign(grid.n_local(), not_binned);
      }
    for (std::size_t c = 0; c < occupied.size(); ++c)
      {
        const std::uint32_t cell_idx = occupied[c].first;
        const std::uint32_t n_here   = cell_begin[c + 1] - cell_begin[c];
        const bool fixed = !fixed_cell.empty() && fixed_cell[cell_idx] != 0;
        // The same points at the same places as when they were binned: a
        // fixed cell with as many points, or a powder cell that did not
        // change since (powder points move only once they melted).
        if (binned_count[cell_idx] == n_here &&
            (fixed || !cell_changed_since(binned_mark, cell_idx)))
          {
            mask[cell_idx] |= binned_bits[cell_idx];
            volume[cell_idx] += binned_volume[cell_idx];
#ifdef DEBUG
            std::uint64_t bits = 0;
            for (std::uint32_t k = cell_begin[c]; k < cell_begin[c + 1]; ++k)
              {
                std::size_t  idx;
                unsigned int bit;
                bin(k, idx, bit);
                Assert(idx == cell_idx, ExcInternalError());
                bits |= std::uint64_t(1) << bit;
              }
            Assert(bits == binned_bits[cell_idx], ExcInternalError());
#endif
            continue;
          }
        std::uint64_t bits     = 0;
        double        vol      = 0;
        bool          reusable = true;
        for (std::uint32_t k = cell_begin[c]; k < cell_begin[c + 1]; ++k)
          {
            std::size_t  idx;
            unsigned int bit;
            bin(k, idx, bit);
            mask[idx] |= (std::uint64_t(1) << bit);
            const double *const v = point_properties[k];
            volume[idx] += v[P::volume];
            const bool is_fluid =
              v[P::state] == fluid || v[P::peak_temperature] > Ts;
            if (is_fluid)
              fluid_cell[idx] = 1, any_fluid = true;
            if (reusable)
              {
                reusable = idx == cell_idx && !is_fluid &&
                           (fixed || v[P::state] == powder);
                bits |= std::uint64_t(1) << bit;
                vol += v[P::volume];
              }
          }
        binned_count[cell_idx] = reusable ? n_here : not_binned;
        if (reusable)
          {
            binned_bits[cell_idx]   = bits;
            binned_volume[cell_idx] = vol;
          }
      }
    binned_mark                  = layout_mark();
    const double        inv_nsub = 1. / std::pow(n, dim);
    std::vector<double> alpha(grid.n_local(), 0.);
    for (std::size_t i = 0; i < alpha.size(); ++i)
      alpha[i] = std::bitset<64>(mask[i]).count() * inv_nsub;
    if (Utilities::MPI::logical_or(any_fluid, grid.communicator()))
      volume_fraction_of_fluid_cells(volume, fluid_cell, alpha);
    grid.update_ghosts(alpha);
    return alpha;
  }

  template <int dim>
  void
  MaterialPoints<dim>::set_fixed_cells(const std::vector<std::uint8_t> &fixed)
  {
    flush_point_temperatures();
    Assert(fixed.empty() || fixed.size() == grid.n_local(),
           ExcDimensionMismatch(fixed.size(), grid.n_local()));
    fixed_cell.clear();
    if (std::any_of(fixed.begin(), fixed.end(), [](auto f) { return f != 0; }))
      fixed_cell = fixed;
    binned_bits.clear();
    binned_volume.clear();
    binned_count.clear();
  }

  template <int dim>
  std::vector<double>
  MaterialPoints<dim>::lattice_fraction() const
  {
    // The substrate's lattice is a tensor product of one row of points per
    // direction (vertically the points below the substrate top), and
    // metal_fraction() bins a point into its sub-cell direction by
    // direction: the sub-cells of a cell that hold a point are the product
    // of the sub-cells hit along each direction. Each row is generated as
    // add_lattice_points() places it (cell by cell, the same arithmetic)
    // and binned as metal_fraction() bins, so alpha is the same number,
    // bit for bit, as the points give on one rank.
    const unsigned int                         n  = prm.subcells;
    const double                               s  = prm.point_spacing;
    const double                               h  = grid.h();
    const double                               ih = n / h;
    const auto                                &x0 = grid.origin();
    std::array<std::vector<unsigned int>, dim> hits;
    for (int d = 0; d < dim; ++d)
      {
        const int                  N = grid.n_cells()[d];
        std::vector<std::uint64_t> mask(N, 0);
        for (int c = 0; c < N; ++c)
          {
            const double lo = c * h;
            double       hi = (c + 1) * h;
            if (d == dim - 1)
              hi = std::min(hi, prm.substrate_top - x0[d]);
            const long first = static_cast<long>(std::ceil(lo / s - 0.5));
            const long last  = static_cast<long>(std::ceil(hi / s - 0.5)) - 1;
            for (long i = first; i <= last; ++i)
              {
                const double p = x0[d] + (i + 0.5) * s;
                const int sub  = static_cast<int>(std::floor((p - x0[d]) * ih));
                const int b    = std::min(std::max(sub / int(n), 0), N - 1);
                mask[b] |=
                  std::uint64_t(1)
                  << std::min(std::max(sub - b * int(n), 0), int(n) - 1);
              }
          }
        hits[d].resize(N);
        for (int c = 0; c < N; ++c)
          hits[d][c] = std::bitset<64>(mask[c]).count();
      }
    const double        inv_nsub = 1. / std::pow(n, dim);
    std::vector<double> alpha(grid.n_local(), 0.);
    for (const auto idx : grid.owned_cells())
      {
        const auto  ijk   = grid.global_index(idx);
        std::size_t count = 1;
        for (int d = 0; d < dim; ++d)
          count *= hits[d][ijk[d]];
        alpha[idx] = count * inv_nsub;
      }
    grid.update_ghosts(alpha);
    return alpha;
  }

  template <int dim>
  void
  MaterialPoints<dim>::volume_fraction_of_fluid_cells(
    std::vector<double> &v,
    std::vector<double> &is_fluid,
    std::vector<double> &alpha) const
  {
    // v: point volume per cell (owned cells), made a fraction of the cell
    // volume; is_fluid: 1 in cells holding a fluid point or one whose peak
    // passed the solidus. Excess volume (v > 1) of a fluid cell goes to its
    // fluid face neighbours, first to fill their deficits (1 - v, in
    // proportion), the rest in equal shares (they pass it on at the next
    // sweep), until no fluid cell is over-full by more than 1e-12 or
    // max_sweeps is reached; each sweep conserves sum v exactly. The
    // amounts depend only on the cell and its neighbours' values, so 1 and
    // n ranks give the same alpha. The sweeps diffuse the excess: where a
    // re-solidified track holds much of it they end at max_sweeps with
    // alpha still changing, and no exact test ends them earlier
    // (doc/flow.md, "One fluid step").
    constexpr unsigned int     max_sweeps = 32;
    const double               inv_V      = 1. / std::pow(grid.h(), dim);
    const auto                &cells      = grid.owned_cells();
    const auto                &st         = grid.strides();
    std::vector<std::uint32_t> fluid;
    for (const auto idx : cells)
      {
        v[idx] *= inv_V;
        if (is_fluid[idx] > 0)
          fluid.push_back(idx);
      }
    grid.update_ghosts(is_fluid);
    // Number of fluid face neighbours (padding cells are never fluid).
    std::vector<double> n_fluid(grid.n_local(), 0.);
    for (const auto idx : fluid)
      for (int d = 0; d < dim; ++d)
        n_fluid[idx] += is_fluid[idx - st[d]] + is_fluid[idx + st[d]];
    grid.update_ghosts(n_fluid);
    // Only the over-full cells and their fluid neighbours change in a
    // sweep (a cell at or below 1 with no over-full neighbour keeps v), and
    // only the over-full cells need their neighbours' deficit: each sweep
    // visits these (and the owned fluid cells next to a ghost, which an
    // over-full cell of the other rank may feed), with the same arithmetic
    // in the same order as a sweep over all fluid cells, so the result is
    // the same to the bit at a fraction of the cost (a re-solidified track
    // counts as fluid and can keep the sweeps going to max_sweeps).
    const auto                &status = grid.cell_status();
    std::vector<std::uint32_t> at_rank_boundary;
    for (const auto idx : fluid)
      {
        bool near_ghost = false;
        for (int d = 0; d < dim; ++d)
          for (const std::ptrdiff_t s : {-st[d], st[d]})
            near_ghost =
              near_ghost || (is_fluid[idx + s] > 0 &&
                             status[idx + s] != BackgroundGrid<dim>::owned);
        if (near_ghost)
          at_rank_boundary.push_back(idx);
      }
    std::vector<std::uint32_t> over;
    for (const auto idx : fluid)
      if (n_fluid[idx] > 0 && v[idx] > 1)
        over.push_back(idx);
    std::vector<double>        deficit(grid.n_local(), 0.), v_new;
    std::vector<std::uint8_t>  in_sweep(grid.n_local(), 0);
    std::vector<std::uint32_t> sweep_cells;
    for (unsigned int sweep = 0; sweep < max_sweeps; ++sweep)
      {
        grid.update_ghosts(v);
        double excess = 0;
        for (const auto idx : over)
          {
            excess   = std::max(excess, v[idx] - 1);
            double D = 0;
            for (int d = 0; d < dim; ++d)
              for (const std::ptrdiff_t s : {-st[d], st[d]})
                if (is_fluid[idx + s] > 0)
                  D += std::max(0., 1 - v[idx + s]);
            deficit[idx] = D;
          }
        if (Utilities::MPI::max(excess, grid.communicator()) <= 1e-12)
          break;
        grid.update_ghosts(deficit);
        // The cells of this sweep: the over-full ones, their owned fluid
        // neighbours and the fluid cells at the rank boundary.
        sweep_cells.clear();
        auto add = [&](const std::uint32_t idx) {
          if (!in_sweep[idx])
            in_sweep[idx] = 1, sweep_cells.push_back(idx);
        };
        for (const auto idx : over)
          {
            add(idx);
            for (int d = 0; d < dim; ++d)
              for (const std::ptrdiff_t s : {-st[d], st[d]})
                if (is_fluid[idx + s] > 0 &&
                    status[idx + s] == BackgroundGrid<dim>::owned)
                  add(idx + s);
          }
        for (const auto idx : at_rank_boundary)
          add(idx);
        v_new.resize(sweep_cells.size());
        for (std::size_t k = 0; k < sweep_cells.size(); ++k)
          {
            const auto   idx = sweep_cells[k];
            const double own = std::max(0., 1 - v[idx]);
            double       vc  = v[idx];
            if (vc > 1 && n_fluid[idx] > 0)
              vc = 1;
            for (int d = 0; d < dim; ++d)
              for (const std::ptrdiff_t s : {-st[d], st[d]})
                {
                  const auto   nb = idx + s;
                  const double E  = v[nb] - 1;
                  if (is_fluid[nb] <= 0 || E <= 0)
                    continue;
                  const double D = deficit[nb];
                  if (D > 0)
                    vc += own * std::min(1., E / D);
                  if (E > D)
                    vc += (E - D) / n_fluid[nb];
                }
            v_new[k] = vc;
          }
        over.clear();
        for (std::size_t k = 0; k < sweep_cells.size(); ++k)
          {
            const auto idx = sweep_cells[k];
            v[idx]         = v_new[k];
            in_sweep[idx]  = 0;
            if (n_fluid[idx] > 0 && v[idx] > 1)
              over.push_back(idx);
          }
      }
    for (const auto idx : fluid)
      alpha[idx] = std::min(1., v[idx]);
  }

  template <int dim>
  void
  MaterialPoints<dim>::cells_to_points(const std::vector<double> &T,
                                       const std::vector<double> *metal)
  {
    // A cell whose temperature is bit-for-bit the one last pushed to the
    // same set of points has nothing to change (temperature, peak and state
    // follow from it alone): far from the laser most cells are such. The
    // record is forgotten for every cell whose points change.
    temperatures_passed = true;
    if (!prm.carry_points)
      return;
    using P         = PropertyIndex;
    const double Ts = mat.solidus;
    if (pushed_temperature.size() != grid.n_local())
      pushed_temperature.assign(grid.n_local(),
                                std::numeric_limits<double>::quiet_NaN());
    bool counted = false; // this call in state_events
    for (std::size_t c = 0; c < occupied.size(); ++c)
      {
        const auto   idx = occupied[c].first;
        const double Tc  = T[idx];
        if (Tc == pushed_temperature[idx])
          continue;
        // A stale temperature (gas at the last alpha pass): the points keep
        // theirs, the record stays unset for volume_mean_over_points().
        if (metal != nullptr && !((*metal)[idx] > 0))
          continue;
        pushed_temperature[idx] = Tc;
        // A fixed cell (FE zone: solid points that stay put, never fluid)
        // below the solidus: its points would all take Tc, a peak of at
        // least Tc and no state change; keep that for the flush.
        // (A fixed cell that once went above the solidus holds fluid
        // points: it is written at every call from then on.)
        const bool fixed = !fixed_cell.empty() && fixed_cell[idx] != 0;
        if (fixed && pending_temperature.size() != grid.n_local())
          {
            pending_temperature.assign(
              grid.n_local(), std::numeric_limits<double>::quiet_NaN());
            pending_peak.assign(grid.n_local(), 0.);
            melted_fixed_cell.assign(grid.n_local(), 0);
          }
        if (fixed && Tc > Ts)
          melted_fixed_cell[idx] = 1;
        if (fixed && !melted_fixed_cell[idx])
          {
            pending_peak[idx]        = std::isnan(pending_temperature[idx]) ?
                                         Tc :
                                         std::max(pending_peak[idx], Tc);
            pending_temperature[idx] = Tc;
            any_pending              = true;
            continue;
          }
        if (fixed)
          flush_cell(c);
        bool changed = false;
        for (std::uint32_t k = cell_begin[c]; k < cell_begin[c + 1]; ++k)
          {
            double *const v   = point_properties[k];
            v[P::temperature] = Tc;
            if (Tc > v[P::peak_temperature])
              v[P::peak_temperature] = Tc;
            if (Tc > Ts)
              {
                if (drop_affine && v[P::state] != fluid)
                  for (unsigned int e = 0; e < dim * dim; ++e)
                    v[P::affine_velocity + e] = 0;
                changed     = changed || v[P::state] != fluid;
                v[P::state] = fluid;
              }
            else if (v[P::state] == fluid)
              {
                v[P::state] = solid;
                changed     = true;
                if (drop_affine)
                  for (unsigned int e = 0; e < dim * dim; ++e)
                    v[P::affine_velocity + e] = 0;
              }
          }
        if (!changed)
          continue;
        // For cell_changed_since().
        if (!counted)
          {
            ++state_events;
            cell_state_at.resize(grid.n_local(), 0);
            counted = true;
          }
        cell_state_at[idx] = state_events;
      }
  }

  template <int dim>
  void
  MaterialPoints<dim>::flush_cell(const std::size_t c) const
  {
    using P        = PropertyIndex;
    const auto idx = occupied[c].first;
    if (idx >= pending_temperature.size() ||
        std::isnan(pending_temperature[idx]))
      return;
    const double Tc = pending_temperature[idx], peak = pending_peak[idx];
    for (std::uint32_t k = cell_begin[c]; k < cell_begin[c + 1]; ++k)
      {
        double *const v = point_properties[k];
        Assert(v[P::state] != fluid, ExcInternalError());
        v[P::temperature] = Tc;
        if (peak > v[P::peak_temperature])
          v[P::peak_temperature] = peak;
      }
    pending_temperature[idx] = std::numeric_limits<double>::quiet_NaN();
  }

  template <int dim>
  void
  MaterialPoints<dim>::flush_point_temperatures() const
  {
    if (!any_pending)
      return;
    for (std::size_t c = 0; c < occupied.size(); ++c)
      flush_cell(c);
    any_pending = false;
  }

  template <int dim>
  std::vector<std::pair<std::uint32_t, double>>
  MaterialPoints<dim>::volume_mean_over_points(
    const std::vector<double>           &T,
    const std::function<double(double)> &e) const
  {
    // Only cells where some point brought another temperature need the
    // sums: not the cells whose points all took the cell's present
    // temperature in cells_to_points() and stayed (one comparison per
    // cell); in the others a comparison per point finds them (~1 ns), e is
    // evaluated only there.
    using P = PropertyIndex;
    std::vector<std::pair<std::uint32_t, double>> mean;
    const bool pushed = pushed_temperature.size() == grid.n_local();
    for (std::size_t c = 0; c < occupied.size(); ++c)
      {
        const double Tc = T[occupied[c].first];
        // All points of a cell hold the temperature cells_to_points() gave
        // them until one enters or leaves it (which forgets the record).
        if (pushed && Tc == pushed_temperature[occupied[c].first])
          continue;
        flush_cell(c);
        bool any = false;
        for (std::uint32_t k = cell_begin[c]; k < cell_begin[c + 1]; ++k)
          any = any || point_properties[k][P::temperature] != Tc;
        if (!any)
          continue;
        const double ec = e(Tc);
        double       sv = 0, se = 0;
        for (std::uint32_t k = cell_begin[c]; k < cell_begin[c + 1]; ++k)
          {
            const double *const v  = point_properties[k];
            const double        Tp = v[P::temperature];
            sv += v[P::volume];
            se += v[P::volume] * (Tp != Tc ? e(Tp) - ec : 0.);
          }
        if (sv > 0)
          mean.emplace_back(occupied[c].first, ec + se / sv);
      }
    return mean;
  }

  template <int dim>
  std::vector<double>
  MaterialPoints<dim>::zone_tags(const std::vector<double> &alpha,
                                 const std::vector<double> &T) const
  {
    std::vector<double> zone(grid.n_local(), 0.);
    if (!prm.carry_points)
      {
        // The substrate's points would all be solid at the start, and
        // fluid exactly above the solidus once they took the cells'
        // temperatures (cells_to_points()).
        for (const auto idx : grid.owned_cells())
          if (alpha[idx] > 0)
            zone[idx] = temperatures_passed && T[idx] > mat.solidus ? 3 : 2;
        return zone;
      }
    for (const auto &[idx, cell] : occupied)
      {
        bool any_fluid = false, any_powder = false;
        for (const auto &particle : handler.particles_in_cell(cell))
          {
            const auto state = particle.get_properties()[PropertyIndex::state];
            any_fluid        = any_fluid || state == fluid;
            any_powder       = any_powder || state == powder;
          }
        zone[idx] = any_fluid ? 3 : (any_powder ? 1 : 2);
      }
    return zone;
  }

  template <int dim>
  void
  MaterialPoints<dim>::create_region(
    const std::function<bool(const Point<dim> &)> &inside,
    const double                                   T0,
    const State                                    state)
  {
    handler.clear();
    handler.initialize(grid.triangulation(), mapping, n_props);
    std::vector<std::pair<std::uint32_t, Point<dim>>> points;
    for (const auto idx : grid.owned_cells())
      add_lattice_points(idx,
                         std::numeric_limits<double>::max(),
                         inside,
                         points);
    insert_points(points, T0, [state](const Point<dim> &) { return state; });
  }

  template <int dim>
  typename MaterialPoints<dim>::RemovedMass
  MaterialPoints<dim>::remove_mass(
    const std::vector<MassToRemove>     &cells,
    const std::function<double(double)> &per_mass)
  {
    using P = PropertyIndex;
    RemovedMass r;
    // A point with less than this is deleted (its rest counts as removed).
    const double m_min = 0.01 * mat.density * std::pow(prm.point_spacing, dim);
    std::vector<std::uint32_t> changed; // cells that lost a point
    std::vector<unsigned int>  deleted; // their pool handles
    std::vector<std::uint32_t> order;
    bool                       touched = false;
    std::size_t                c       = 0;
    for (const auto &cm : cells)
      {
        double need = cm.mass;
        if (!(need > 0))
          continue;
        while (c < occupied.size() && occupied[c].first < cm.index)
          ++c;
        if (c == occupied.size() || occupied[c].first != cm.index)
          {
            r.not_removed += need;
            continue;
          }
        // The cell's fluid points, outermost along the outward direction
        // first; ties by position (the order does not depend on the
        // handler's, nor on the rank count).
        Tensor<1, dim> n = cm.outward;
        if (!(n.norm() > 0))
          n[dim - 1] = 1;
        order.clear();
        for (std::uint32_t k = cell_begin[c]; k < cell_begin[c + 1]; ++k)
          if (point_properties[k][P::state] == fluid)
            order.push_back(k);
        std::sort(order.begin(),
                  order.end(),
                  [&](const std::uint32_t a, const std::uint32_t b) {
                    const Point<dim> &pa = *point_locations[a];
                    const Point<dim> &pb = *point_locations[b];
                    const double      da = pa * n, db = pb * n;
                    if (da != db)
                      return da > db;
                    for (int d = dim - 1; d >= 0; --d)
                      if (pa[d] != pb[d])
                        return pa[d] > pb[d];
                    return a < b;
                  });
        bool lost = false;
        for (const auto k : order)
          {
            if (!(need > 0))
              break;
            double *const v = point_properties[k];
            const double  m = v[P::mass];
            touched         = true;
            if (m - need < m_min)
              {
                // The whole point goes.
                need -= m;
                r.mass += m;
                r.weighted += m * per_mass(v[P::temperature]);
                deleted.push_back(point_handles[k]);
                ++r.deleted;
                lost = true;
              }
            else
              {
                // Mass and volume shrink together: density, temperature
                // and specific enthalpy stay.
                v[P::volume] *= (m - need) / m;
                v[P::mass] = m - need;
                r.mass += need;
                r.weighted += need * per_mass(v[P::temperature]);
                need = 0;
              }
          }
        if (need > 0)
          r.not_removed += need;
        if (lost)
          changed.push_back(cm.index);
      }
    // Delete the points (cells in increasing order, each cell's points in
    // the handler's order, removed last first as in relocate_points()).
    if (!changed.empty())
      {
        std::sort(deleted.begin(), deleted.end());
        std::vector<typename Particles::ParticleHandler<dim>::particle_iterator>
          to_remove;
        for (const auto idx : changed)
          {
            auto range = handler.particles_in_cell(grid.cell_iterator(idx));
            for (auto it = range.begin(); it != range.end(); ++it)
              if (std::binary_search(deleted.begin(),
                                     deleted.end(),
                                     it->get_local_index()))
                to_remove.push_back(it);
          }
        AssertThrow(to_remove.size() == deleted.size(),
                    ExcMessage("remove_mass(): a point to delete was not "
                               "found in its cell"));
        for (auto it = to_remove.rbegin(); it != to_remove.rend(); ++it)
          handler.remove_particle(*it);
        ++relocations;
        cell_moved_at.resize(grid.n_local(), 0);
        for (const auto idx : changed)
          cell_moved_at[idx] = relocations;
        refresh_occupied_cells(changed);
      }
    // One reduction: the sums over the ranks, and whether any rank changed
    // or deleted a point.
    const double local[6] = {r.mass,
                             r.not_removed,
                             double(r.deleted),
                             touched ? 1. : 0.,
                             changed.empty() ? 0. : 1.,
                             r.weighted};
    double       global[6];
    Utilities::MPI::sum(ArrayView<const double>(local, 6),
                        grid.communicator(),
                        ArrayView<double>(global, 6));
    r.mass        = global[0];
    r.not_removed = global[1];
    r.deleted     = static_cast<unsigned long>(global[2]);
    r.weighted    = global[5];
    if (global[3] > 0)
      ++moves_global; // alpha is stale (point_moves())
    if (global[4] > 0)
      handler.update_cached_numbers(); // the global count (collective)
    return r;
  }

  template <int dim>
  void
  MaterialPoints<dim>::index_occupied_cells()
  {
    // Owned cells that hold points, and where their properties live; after
    // points were inserted, removed or re-sorted.
    occupied.clear();
    for (const auto idx : grid.owned_cells())
      {
        const auto &cell = grid.cell_iterator(idx);
        if (handler.n_particles_in_cell(cell) > 0)
          occupied.emplace_back(idx, cell);
      }
    cache_point_handles();
  }

  template <int dim>
  void
  MaterialPoints<dim>::points_moved()
  {
    handler.sort_particles_into_subdomains_and_cells();
    index_occupied_cells();
    ++moves_global;
  }

  template <int dim>
  bool
  MaterialPoints<dim>::relocate_points(const std::vector<std::uint32_t> *from)
  {
    struct Move
    {
      Point<dim>            location, reference;
      types::particle_index id;
      std::uint32_t         cell;
      std::vector<double>   properties;
    };
    std::vector<typename Particles::ParticleHandler<dim>::particle_iterator>
                               to_remove;
    std::vector<Move>          moves;
    bool                       local = true;
    const double               h     = grid.h();
    std::vector<std::uint32_t> changed;
    // Points whose new cell is a ghost cell go to its owner: per rank,
    // (x, id, properties) of each point, n_send doubles each.
    const unsigned int                          n_send = dim + 1 + n_props;
    std::map<unsigned int, std::vector<double>> outgoing;
    auto                                        scan_cell =
      [&](const std::uint32_t                                      idx,
          const typename Triangulation<dim>::active_cell_iterator &cell) {
        const auto own   = grid.global_index(idx);
        auto       range = handler.particles_in_cell(cell);
        for (auto it = range.begin(); it != range.end(); ++it)
          {
            const Point<dim> x   = it->get_location();
            const auto       ijk = grid.cell_of(x);
            if (ijk == own)
              continue;
            if (!grid.in_box(ijk) ||
                grid.cell_status()[grid.local_index(ijk)] ==
                  BackgroundGrid<dim>::outside)
              {
                local = false;
                break;
              }
            if (grid.cell_status()[grid.local_index(ijk)] ==
                BackgroundGrid<dim>::ghost)
              {
                // To the owner of the ghost cell.
                auto &buffer =
                  outgoing[grid.cell_iterator(grid.local_index(ijk))
                             ->subdomain_id()];
                for (int d = 0; d < dim; ++d)
                  buffer.push_back(x[d]);
                buffer.push_back(static_cast<double>(it->get_id()));
                const auto p = it->get_properties();
                buffer.insert(buffer.end(), p.begin(), p.end());
                if (changed.empty() || changed.back() != idx)
                  changed.push_back(idx);
                to_remove.push_back(it);
                continue;
              }
            Move m;
            m.location = x;
            m.cell     = grid.local_index(ijk);
            m.id       = it->get_id();
            for (int d = 0; d < dim; ++d)
              m.reference[d] = (x[d] - grid.origin()[d]) / h - ijk[d];
            const auto p = it->get_properties();
            m.properties.assign(p.begin(), p.end());
            if (changed.empty() || changed.back() != idx)
              changed.push_back(idx);
            changed.push_back(m.cell);
            moves.push_back(std::move(m));
            to_remove.push_back(it);
          }
      };
    if (from)
      {
        for (const auto idx : *from)
          if (local)
            scan_cell(idx, grid.cell_iterator(idx));
      }
    else
      for (const auto &[idx, cell] : occupied)
        if (local)
          scan_cell(idx, cell);
    // One reduction for both: did a point go beyond the ghost layer
    // anywhere, does any rank send points?
    // (And, for point_moves(), does any point change cells?)
    const std::array<unsigned int, 3> flags{
      {!local ? 1u : 0u,
       outgoing.empty() ? 0u : 1u,
       outgoing.empty() && moves.empty() ? 0u : 1u}};
    std::array<unsigned int, 3> any;
    Utilities::MPI::max(ArrayView<const unsigned int>(flags.data(), 3),
                        grid.communicator(),
                        ArrayView<unsigned int>(any.data(), 3));
    if (any[0] != 0)
      return false;
    if (any[2] != 0)
      ++moves_global;
    // One by one, last first (so that the iterators of the earlier points of
    // a cell stay valid), and the cached numbers updated once at the end:
    // remove_particles() would update them as well, and each update loops
    // over every point (12 % of the 3D track's run time when done twice).
    for (auto it = to_remove.rbegin(); it != to_remove.rend(); ++it)
      handler.remove_particle(*it);
    for (const auto &m : moves)
      handler.insert_particle(m.location,
                              m.reference,
                              m.id,
                              grid.cell_iterator(m.cell),
                              ArrayView<const double>(m.properties));
    // Points from neighbour ranks (in the order of the sending ranks), into
    // their owned cells here.
    std::map<unsigned int, std::vector<double>> incoming;
    if (any[1] != 0)
      incoming = Utilities::MPI::some_to_some(grid.communicator(), outgoing);
    for (const auto &[rank, buffer] : incoming)
      for (std::size_t k = 0; k + n_send <= buffer.size(); k += n_send)
        {
          Point<dim> x, ref;
          for (int d = 0; d < dim; ++d)
            x[d] = buffer[k + d];
          const auto ijk = grid.cell_of(x);
          const auto idx = grid.local_index(ijk);
          AssertThrow(grid.in_box(ijk) &&
                        grid.cell_status()[idx] == BackgroundGrid<dim>::owned,
                      ExcMessage("a point sent to this rank is not in one of "
                                 "its cells"));
          for (int d = 0; d < dim; ++d)
            ref[d] = (x[d] - grid.origin()[d]) / h - ijk[d];
          handler.insert_particle(
            x,
            ref,
            static_cast<types::particle_index>(buffer[k + dim]),
            grid.cell_iterator(idx),
            ArrayView<const double>(buffer.data() + k + dim + 1, n_props));
          changed.push_back(idx);
        }
    // The handler's cached numbers need no update: insert_particle() and
    // remove_particle() keep the points of this rank counted, a move keeps
    // the global count and the ids, and the most points per cell is only
    // used for serialization, which femp does not do. (deal.II's update
    // loops over every point: a few per cent of the scan at the paper's
    // scale when it ran at every flow step in which a point changed rank.)
    std::sort(changed.begin(), changed.end());
    changed.erase(std::unique(changed.begin(), changed.end()), changed.end());
    if (!changed.empty())
      {
        ++relocations;
        cell_moved_at.resize(grid.n_local(), 0);
        for (const auto idx : changed)
          cell_moved_at[idx] = relocations;
      }
    refresh_occupied_cells(changed);
    // The count that the output and the checkpoint read, kept by deal.II's
    // single-point insert and remove (checked: two numbers).
    AssertThrow(handler.n_locally_owned_particles() == point_properties.size(),
                ExcMessage("the particle handler counts " +
                           std::to_string(handler.n_locally_owned_particles()) +
                           " points on this rank after a relocation, its "
                           "cells hold " +
                           std::to_string(point_properties.size())));
    return true;
  }

  template <int dim>
  void
  MaterialPoints<dim>::refresh_occupied_cells(
    const std::vector<std::uint32_t> &changed)
  {
    // The cached pointers of cells outside 'changed' stay valid when the
    // property pool did not move: removed points free slots that the
    // inserted ones take, so the pool does not grow. Check on one
    // unchanged cell (a moved pool moves every slot); otherwise rebuild.
    std::size_t c_check = 0;
    {
      std::size_t k = 0;
      while (c_check < occupied.size())
        {
          const auto idx = occupied[c_check].first;
          while (k < changed.size() && changed[k] < idx)
            ++k;
          if (k == changed.size() || changed[k] != idx)
            break;
          ++c_check;
        }
    }
    if (c_check < occupied.size())
      {
        const auto range = handler.particles_in_cell(occupied[c_check].second);
        if (range.begin() == range.end() ||
            range.begin()->get_properties().data() !=
              point_properties[cell_begin[c_check]] ||
            &range.begin()->get_location() !=
              point_locations[cell_begin[c_check]])
          {
            index_occupied_cells();
            return;
          }
      }
    // Merge the old occupied list with the changed cells (both increasing).
    decltype(occupied)              new_occupied;
    std::vector<double *>           new_pointers;
    std::vector<const Point<dim> *> new_locations;
    std::vector<unsigned int>       new_handles;
    std::vector<std::uint32_t>      new_begin(1, 0);
    new_occupied.reserve(occupied.size() + changed.size());
    new_pointers.reserve(point_properties.size());
    new_locations.reserve(point_locations.size());
    new_handles.reserve(point_handles.size());
    std::size_t c = 0, k = 0;
    while (c < occupied.size() || k < changed.size())
      {
        const std::uint32_t io = c < occupied.size() ?
                                   occupied[c].first :
                                   std::numeric_limits<std::uint32_t>::max();
        const std::uint32_t ik = k < changed.size() ?
                                   changed[k] :
                                   std::numeric_limits<std::uint32_t>::max();
        if (ik <= io)
          {
            // A changed cell: ask the handler (also when it was occupied).
            const auto &cell = grid.cell_iterator(ik);
            if (ik < pushed_temperature.size())
              pushed_temperature[ik] = std::numeric_limits<double>::quiet_NaN();
            if (handler.n_particles_in_cell(cell) > 0)
              {
                new_occupied.emplace_back(ik, cell);
                for (auto &particle : handler.particles_in_cell(cell))
                  {
                    new_pointers.push_back(particle.get_properties().data());
                    new_locations.push_back(&particle.get_location());
                    new_handles.push_back(particle.get_local_index());
                  }
                new_begin.push_back(new_pointers.size());
              }
            ++k;
            if (ik == io)
              ++c;
          }
        else
          {
            new_occupied.push_back(occupied[c]);
            new_pointers.insert(new_pointers.end(),
                                point_properties.begin() + cell_begin[c],
                                point_properties.begin() + cell_begin[c + 1]);
            new_locations.insert(new_locations.end(),
                                 point_locations.begin() + cell_begin[c],
                                 point_locations.begin() + cell_begin[c + 1]);
            new_handles.insert(new_handles.end(),
                               point_handles.begin() + cell_begin[c],
                               point_handles.begin() + cell_begin[c + 1]);
            new_begin.push_back(new_pointers.size());
            ++c;
          }
      }
    occupied.swap(new_occupied);
    point_properties.swap(new_pointers);
    point_locations.swap(new_locations);
    point_handles.swap(new_handles);
    cell_begin.swap(new_begin);
#ifdef DEBUG
    // Debug builds: the refreshed lists must equal a full rebuild, and the
    // handler's point count must be current.
    {
      std::size_t n = 0;
      for (auto it = handler.begin(); it != handler.end(); ++it)
        ++n;
      Assert(n == handler.n_locally_owned_particles(),
             ExcMessage("stale point count of the particle handler"));
      const auto o  = occupied;
      const auto p  = point_properties;
      const auto l  = point_locations;
      const auto hd = point_handles;
      const auto b  = cell_begin;
      const auto g  = layout_generation;
      index_occupied_cells();
      layout_generation = g; // (a check, not a change of the handler)
      Assert(o.size() == occupied.size() && p == point_properties &&
               l == point_locations && hd == point_handles && b == cell_begin,
             ExcMessage("refreshed point cache differs from a rebuild"));
      for (std::size_t i = 0; i < o.size(); ++i)
        Assert(o[i].first == occupied[i].first,
               ExcMessage("refreshed occupied list differs from a rebuild"));
    }
#endif
  }

  template <int dim>
  void
  MaterialPoints<dim>::save_state(StateWriter &out) const
  {
    flush_point_temperatures();
    // Fixed-size records: id, cell (global number), position, reference
    // position, properties.
    // Cell by cell in the order of the owned cells (the handler's own
    // order of cells depends on the history of insertions; the order of
    // the points in a cell is kept, it sets the order of sums).
    out.put<std::uint32_t>(n_props);
    out.put<std::uint64_t>(handler.n_locally_owned_particles());
    for (const auto &[idx, cell] : occupied)
      for (const auto &p : handler.particles_in_cell(cell))
        {
          out.put<std::uint64_t>(p.get_id());
          out.put(global_cell_number(grid, grid.global_index(idx)));
          const Point<dim> x = p.get_location(), r = p.get_reference_location();
          for (int d = 0; d < dim; ++d)
            out.put(x[d]);
          for (int d = 0; d < dim; ++d)
            out.put(r[d]);
          const auto props = p.get_properties();
          for (unsigned int i = 0; i < n_props; ++i)
            out.put(props[i]);
        }
  }

  template <int dim>
  void
  MaterialPoints<dim>::load_state(std::vector<StateReader> &parts)
  {
    handler.clear_particles();
    binned_count.clear(); // other points: bin them again
    pending_temperature.clear();
    melted_fixed_cell.clear();
    any_pending = false;
    std::vector<double> props(n_props);
    for (auto &in : parts)
      {
        require(in.get<std::uint32_t>() == n_props,
                "Checkpoint/Resume from",
                "",
                "its points carry other properties than this scene's");
        const auto n = in.get<std::uint64_t>();
        for (std::uint64_t k = 0; k < n; ++k)
          {
            const auto id   = in.get<std::uint64_t>();
            const auto cell = in.get<std::uint64_t>();
            Point<dim> x, r;
            for (int d = 0; d < dim; ++d)
              x[d] = in.get<double>();
            for (int d = 0; d < dim; ++d)
              r[d] = in.get<double>();
            for (unsigned int i = 0; i < n_props; ++i)
              props[i] = in.get<double>();
            const auto idx = owned_local_index(grid, cell);
            if (idx >= 0)
              handler.insert_particle(x,
                                      r,
                                      id,
                                      grid.cell_iterator(idx),
                                      ArrayView<const double>(props));
          }
      }
    handler.update_cached_numbers();
    index_occupied_cells();
  }

  template <int dim>
  void
  count_saved_points(std::vector<StateReader>   &parts,
                     const std::uint64_t         n_cells,
                     std::vector<std::uint32_t> &all,
                     std::vector<std::uint32_t> &solid)
  {
    using P = typename MaterialPoints<dim>::PropertyIndex;
    all.assign(n_cells, 0);
    solid.assign(n_cells, 0);
    for (auto &in : parts)
      {
        // The records of MaterialPoints::save_state(): id, cell, position,
        // reference position, properties.
        const auto          n_props = in.get<std::uint32_t>();
        const auto          n       = in.get<std::uint64_t>();
        std::vector<double> props(n_props);
        for (std::uint64_t k = 0; k < n; ++k)
          {
            in.get<std::uint64_t>();
            const auto cell = in.get<std::uint64_t>();
            for (int d = 0; d < 2 * dim; ++d)
              in.get<double>();
            for (auto &v : props)
              v = in.get<double>();
            require(cell < n_cells,
                    "Checkpoint/Resume from",
                    "",
                    "a point lies in a cell outside the grid");
            ++all[cell];
            if (n_props > P::state &&
                props[P::state] == MaterialPoints<dim>::solid)
              ++solid[cell];
          }
      }
  }

  template void
  count_saved_points<2>(std::vector<StateReader> &,
                        std::uint64_t,
                        std::vector<std::uint32_t> &,
                        std::vector<std::uint32_t> &);
  template void
  count_saved_points<3>(std::vector<StateReader> &,
                        std::uint64_t,
                        std::vector<std::uint32_t> &,
                        std::vector<std::uint32_t> &);

  template class MaterialPoints<2>;
  template class MaterialPoints<3>;
} // namespace femp
