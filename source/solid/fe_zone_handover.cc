// femp: the choice of the cells a build hands from material points to
// finite elements at each layer start (see the header and doc/builds.md,
// "Handing cooled metal to finite elements").
#include <deal.II/base/mpi.h>
#include <deal.II/base/utilities.h>

#include <femp/base/input_checks.h>
#include <femp/grid/cell_state.h>
#include <femp/solid/fe_zone_handover.h>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace femp
{
  namespace
  {
    /// A box of grid cells, first[d] <= ijk[d] < first[d] + n[d], and the
    /// lexicographic index of a cell in it (x fastest; -1 outside).
    template <int dim>
    struct CellBox
    {
      std::array<int, dim> first, n;

      long
      index(const std::array<int, dim> &ijk) const
      {
        long k = 0;
        for (int d = dim - 1; d >= 0; --d)
          {
            const int i = ijk[d] - first[d];
            if (i < 0 || i >= n[d])
              return -1;
            k = k * n[d] + i;
          }
        return k;
      }
    };
  } // namespace

  template <int dim>
  const Choices<typename FeZoneHandover<dim>::Parameters::Rule> &
  FeZoneHandover<dim>::Parameters::rule_names()
  {
    static const Choices<Rule> names = {{Rule::temperature, "temperature"},
                                        {Rule::reheating, "re-heating"}};
    return names;
  }

  template <int dim>
  void
  FeZoneHandover<dim>::Parameters::add_parameters(ParameterTable &table)
  {
    table.enter_subsection("Build");
    table.add(
      "Hand over cooled metal",
      enabled,
      "At each layer start, after its recoat, hand the cells of dense metal "
      "that have cooled below 'Hand-over temperature', lie 'Hand-over "
      "margin' below the deepest melt expected of the new layer and are "
      "connected to the FE zone from material points to finite elements: "
      "the FE zone of the solid rises behind the build (the cells of a "
      "pore and the porous metal around them stay points inside it), each "
      "new element taking its "
      "cell's mean stress and plastic strain (doc/builds.md, \"Handing "
      "cooled metal to finite elements\"). Needs the heat, the solid with "
      "its FE zone and a layer schedule. A checkpoint records the zone's "
      "cells and the fusion depths (doc/checkpoint.md).");
    table.add("Hand-over temperature",
              temperature,
              Patterns::Double(),
              "With 'Hand over cooled metal': every material point of a "
              "handed cell is below this temperature, K; range (0, "
              "Material/Solidus).");
    table.add(
      "Hand-over rule",
      rule,
      rule_names(),
      "With 'Hand over cooled metal': what keeps a dense, solid cell below "
      "the limit line as material points. 'temperature': a point at or "
      "above 'Hand-over temperature'. 're-heating': a predicted peak of the "
      "new layer at or above Material/Solidus less 'Re-heating margin', "
      "the prediction being the cell's hottest point plus the largest "
      "temperature rise over a layer that a metal cell at the same depth "
      "below its layer's powder top saw in the finished layers "
      "(doc/builds.md, \"Handing cooled metal to finite elements\").");
    table.add("Re-heating margin",
              reheat_margin,
              Patterns::Double(),
              "With 'Hand-over rule = re-heating': a handed cell's predicted "
              "peak stays this far below Material/Solidus, K; range [0, "
              "Material/Solidus).");
    table.add("Re-heating layers",
              reheat_layers,
              Patterns::Integer(),
              "With 'Hand-over rule = re-heating': the rise at a depth is "
              "the largest of the latest this many finished layers (the "
              "part's state changes from layer to layer: the first layer "
              "heats a cold plate). Count, range [1, 1000]; the "
              "default takes every finished layer (doc/builds.md: fewer "
              "let a deeper melt reach handed cells).");
    table.add("Hand-over checks per layer",
              checks,
              Patterns::Integer(),
              "With 'Hand over cooled metal': how many times per layer the "
              "cells are chosen and handed over: at the layer's start (after "
              "its recoat) and, for n > 1, at n - 1 more times equally spaced "
              "over the layer's window (from its start to the next layer's, "
              "the last layer's to the end time), the limit kept clear of "
              "the layer's own melt so far where it reaches deeper than the "
              "deepest fusion of the finished layers; the first layer is "
              "checked at the second's start only. Count, range [1, 100].");
    table.add("Hand-over margin",
              margin,
              Patterns::Double(),
              "With 'Hand over cooled metal': the handed cells stay this "
              "far below the new layer's powder top less the deepest "
              "fusion depth of the layers so far and, with 'Hand-over "
              "surface limit', below the lowest metal surface near their "
              "column less the penetration depth, m; range [0, inf).");
    table.add(
      "Hand-over surface limit",
      surface_limit,
      "With 'Hand over cooled metal': the handed cells also stay the "
      "penetration depth plus 'Hand-over margin' below the lowest metal "
      "surface within 'Hand-over surface window' of their column, the "
      "penetration depth being the deepest that a finished layer's melt "
      "reached below the metal surface it met (doc/builds.md, \"Handing "
      "cooled metal to finite elements\"). False: the powder top's line "
      "alone.");
    table.add("Hand-over surface window",
              surface_window,
              Patterns::Double(),
              "With 'Hand-over surface limit': a column's metal surface is "
              "the lowest of the columns whose centres lie within this "
              "horizontal distance of its centre, m; range [0, inf).");
    table.leave_subsection();
  }

  template <int dim>
  void
  FeZoneHandover<dim>::Parameters::declare_parameters(ParameterHandler &prm)
  {
    Parameters     defaults;
    ParameterTable table(prm, ParameterTable::Mode::declare);
    defaults.add_parameters(table);
  }

  template <int dim>
  void
  FeZoneHandover<dim>::Parameters::parse_parameters(ParameterHandler &prm)
  {
    ParameterTable table(prm, ParameterTable::Mode::parse);
    add_parameters(table);
  }

  template <int dim>
  void
  FeZoneHandover<dim>::Parameters::check(const double solidus,
                                         const bool   heat,
                                         const bool   solid,
                                         const bool   fe_zone,
                                         const bool   layers) const
  {
    // The values only matter with the hand-over on (a material whose
    // solidus lies below the default temperature runs without it).
    if (!enabled)
      return;
    require(std::isfinite(temperature) && temperature > 0 &&
              temperature < solidus,
            "Build/Hand-over temperature",
            temperature,
            "it must lie in (0, " + num(solidus) +
              ") K: below Material/Solidus");
    require(std::isfinite(reheat_margin) && reheat_margin >= 0 &&
              reheat_margin < solidus,
            "Build/Re-heating margin",
            reheat_margin,
            "it must lie in [0, " + num(solidus) +
              ") K: below Material/Solidus");
    require(reheat_layers >= 1 && reheat_layers <= 1000,
            "Build/Re-heating layers",
            reheat_layers,
            "it must be a count in [1, 1000]");
    require(checks >= 1 && checks <= 100,
            "Build/Hand-over checks per layer",
            checks,
            "it must be a count in [1, 100]");
    require(std::isfinite(margin) && margin >= 0,
            "Build/Hand-over margin",
            margin,
            "it must be a length in [0, inf) m");
    require(std::isfinite(surface_window) && surface_window >= 0,
            "Build/Hand-over surface window",
            surface_window,
            "it must be a length in [0, inf) m");
    const std::string name = "Build/Hand over cooled metal";
    require(heat,
            name,
            "true",
            "the hand-over needs 'Physics/Heat transfer = true' (it hands "
            "over metal that has cooled)");
    require(solid,
            name,
            "true",
            "the hand-over needs 'Physics/Solid stress = true' (it hands "
            "material points of the solid to its finite elements)");
    require(fe_zone,
            name,
            "true",
            "the hand-over needs 'Solid FEM/Use finite elements = true' (the "
            "zone it raises)");
    require(layers,
            name,
            "true",
            "the hand-over happens at layer starts: it needs 'Build/Layer "
            "schedule' other than none, with more than one layer");
  }

  template <int dim>
  FeZoneHandover<dim>::FeZoneHandover(const Parameters          &prm,
                                      const BackgroundGrid<dim> &grid,
                                      const double               solidus,
                                      const double               first_top,
                                      const double               first_surface)
      : prm(prm)
      , grid(grid)
      , solidus(solidus)
      , layer_top(first_top)
      , T_start(prm.rule == Parameters::Rule::reheating ? grid.make_field(0.) :
                                                          std::vector<double>())
      , rise(grid.n_cells()[dim - 1], 0.)
      , envelope(grid.n_cells()[dim - 1], 0.)
      , col_lowest(n_columns(), std::numeric_limits<double>::infinity())
  {
    if (std::isfinite(first_surface))
      start_surface.assign(n_columns(), first_surface);
  }

  template <int dim>
  std::size_t
  FeZoneHandover<dim>::n_columns() const
  {
    std::size_t n = 1;
    for (int d = 0; d < dim - 1; ++d)
      n *= grid.n_cells()[d];
    return n;
  }

  template <int dim>
  std::vector<double>
  FeZoneHandover<dim>::find_surface(const MaterialPoints<dim>       &points,
                                    const std::vector<std::uint8_t> &zone,
                                    const std::vector<double>       &alpha,
                                    const std::vector<double>       &pore) const
  {
    // The cells holding a powder point (local box).
    using P = typename MaterialPoints<dim>::PropertyIndex;
    std::vector<std::uint8_t> powder(grid.n_local(), 0);
    const auto               &cells = points.occupied_cells();
    for (std::size_t c = 0; c < cells.size(); ++c)
      for (const double *v : points.cell_point_properties(c))
        if (v[P::state] == MaterialPoints<dim>::powder)
          {
            powder[cells[c].first] = 1;
            break;
          }
    // Per column the row above its highest metal cell (0: none).
    std::vector<int> above(n_columns(), 0);
    grid.for_each_owned_cell([&](const std::size_t idx, const auto &ijk) {
      const bool metal = zone[idx] || (!pore.empty() && pore[idx] > 0) ||
                         (alpha[idx] >= 0.5 && !powder[idx]);
      if (metal)
        {
          int &a = above[column(ijk)];
          a      = std::max(a, int(ijk[dim - 1]) + 1);
        }
    });
    MPI_Allreduce(MPI_IN_PLACE,
                  above.data(),
                  int(above.size()),
                  MPI_INT,
                  MPI_MAX,
                  grid.communicator());
    const double        z0 = grid.origin()[dim - 1], h = grid.h();
    std::vector<double> s(above.size());
    for (std::size_t c = 0; c < above.size(); ++c)
      s[c] = z0 + above[c] * h;
    // The lowest within the window: a box of w cells each side, one
    // horizontal direction after the other.
    const int w = int(std::floor(prm.surface_window / h + 1e-9));
    if (w == 0)
      return s;
    std::size_t stride = 1;
    for (int d = 0; d < dim - 1; ++d)
      {
        const int           n = int(grid.n_cells()[d]);
        std::vector<double> t(s);
        for (std::size_t c = 0; c < s.size(); ++c)
          {
            const int i = int((c / stride) % n);
            for (int j = std::max(0, i - w); j <= std::min(n - 1, i + w); ++j)
              t[c] = std::min(t[c],
                              s[std::size_t(long(c) + (j - i) * long(stride))]);
          }
        s = t;
        stride *= n;
      }
    return s;
  }

  template <int dim>
  std::vector<double>
  FeZoneHandover<dim>::all_col_lowest() const
  {
    std::vector<double> low(col_lowest);
    MPI_Allreduce(MPI_IN_PLACE,
                  low.data(),
                  int(low.size()),
                  MPI_DOUBLE,
                  MPI_MIN,
                  grid.communicator());
    return low;
  }

  template <int dim>
  double
  FeZoneHandover<dim>::layer_penetration() const
  {
    const std::vector<double> low = all_col_lowest();
    double                    p   = -std::numeric_limits<double>::infinity();
    for (std::size_t c = 0; c < low.size(); ++c)
      if (std::isfinite(low[c]))
        p = std::max(p,
                     (start_surface.empty() ? layer_top : start_surface[c]) -
                       low[c]);
    return p;
  }

  template <int dim>
  void
  FeZoneHandover<dim>::observe(const std::vector<double> &T,
                               const std::vector<double> &alpha)
  {
    // The re-heating rule alone reads the rises: the temperature rule's
    // pass finds the lowest molten cell only.
    const bool track_rise = prm.rule == Parameters::Rule::reheating;
    // The layer's first step: the temperatures its rises start from.
    if (track_rise && start_pending)
      {
        for (const auto idx : grid.owned_cells())
          T_start[idx] = T[idx];
        start_pending = false;
      }
    // One pass over the owned cells: the bottom of the lowest molten one
    // and the largest rise of metal per depth row below the top.
    const double z0 = grid.origin()[dim - 1], h = grid.h();
    const int    n_depth = int(rise.size());
    grid.for_each_owned_cell([&](const std::size_t idx, const auto &ijk) {
      const double z = z0 + ijk[dim - 1] * h;
      if (alpha[idx] < 0.5)
        return;
      if (T[idx] >= solidus)
        {
          lowest      = std::min(lowest, z);
          double &low = col_lowest[column(ijk)];
          low         = std::min(low, z);
        }
      if (!track_rise)
        return;
      const double below = (layer_top - z) / h - 0.5;
      if (below < 0)
        return;
      const int k = std::min(int(below), n_depth - 1);
      rise[k]     = std::max(rise[k], T[idx] - T_start[idx]);
    });
  }

  template <int dim>
  double
  FeZoneHandover<dim>::choose_top(const double                     new_top,
                                  const MaterialPoints<dim>       &points,
                                  const std::vector<std::uint8_t> &zone,
                                  const std::vector<double>       &top_lift,
                                  const std::vector<double>       &alpha,
                                  const std::vector<double>       &pore)
  {
    // The layer before: its fusion depth below its powder top.
    const double low = Utilities::MPI::min(lowest, grid.communicator());
    closed_lowest    = low;
    if (std::isfinite(low))
      depth = std::max(depth, layer_top - low);
    lowest = std::numeric_limits<double>::infinity();
    // Its penetration below the metal surface it met.
    penetration = std::max(penetration, layer_penetration());
    std::fill(col_lowest.begin(),
              col_lowest.end(),
              std::numeric_limits<double>::infinity());
    // Its rises per depth join the envelope; the new layer's start anew.
    MPI_Allreduce(MPI_IN_PLACE,
                  rise.data(),
                  int(rise.size()),
                  MPI_DOUBLE,
                  MPI_MAX,
                  grid.communicator());
    history.push_back(rise);
    std::fill(envelope.begin(), envelope.end(), 0.);
    for (std::size_t l =
           history.size() -
           std::min<std::size_t>(history.size(), prm.reheat_layers);
         l < history.size();
         ++l)
      for (std::size_t k = 0; k < rise.size(); ++k)
        envelope[k] = std::max(envelope[k], history[l][k]);
    std::fill(rise.begin(), rise.end(), 0.);
    start_pending = true;
    layer_top     = new_top;
    used_depth    = depth;
    // The metal surface the new layer meets.
    start_surface    = find_surface(points, zone, alpha, pore);
    surface          = start_surface;
    used_penetration = penetration;
    return choose(
      new_top - depth - prm.margin, points, zone, top_lift, alpha, pore);
  }

  template <int dim>
  double
  FeZoneHandover<dim>::choose_in_layer(const MaterialPoints<dim>       &points,
                                       const std::vector<std::uint8_t> &zone,
                                       const std::vector<double> &top_lift,
                                       const std::vector<double> &alpha,
                                       const std::vector<double> &pore)
  {
    // The layer in progress stays open: its melt so far deepens the
    // depth the limit keeps clear, if it reaches deeper than D.
    const double low = Utilities::MPI::min(lowest, grid.communicator());
    closed_lowest    = low;
    used_depth = std::isfinite(low) ? std::max(depth, layer_top - low) : depth;
    used_penetration = std::max(penetration, layer_penetration());
    surface          = find_surface(points, zone, alpha, pore);
    return choose(
      layer_top - used_depth - prm.margin, points, zone, top_lift, alpha, pore);
  }

  template <int dim>
  double
  FeZoneHandover<dim>::choose(const double                     limit,
                              const MaterialPoints<dim>       &points,
                              const std::vector<std::uint8_t> &zone,
                              const std::vector<double>       &top_lift,
                              const std::vector<double>       &alpha,
                              const std::vector<double>       &pore)
  {
    const MPI_Comm comm = grid.communicator();
    // The zone's bounding box from its cells.
    std::array<int, dim> lo, hi;
    lo.fill(std::numeric_limits<int>::max());
    hi.fill(-1);
    grid.for_each_owned_cell([&](const std::size_t idx, const auto &ijk) {
      if (zone[idx])
        for (int d = 0; d < dim; ++d)
          lo[d] = std::min(lo[d], ijk[d]), hi[d] = std::max(hi[d], ijk[d]);
    });
    for (int d = 0; d < dim; ++d)
      lo[d] = Utilities::MPI::min(lo[d], comm),
      hi[d] = Utilities::MPI::max(hi[d], comm);
    const double z0 = grid.origin()[dim - 1], h = grid.h();
    const int    first_row = hi[dim - 1] + 1;
    current_top            = z0 + first_row * h;
    last_limit             = limit;
    reason.clear();
    row_fill.clear();
    row_mass.clear();
    row_points.clear();
    chosen.clear();
    chosen_mass         = 0;
    least_surface_limit = std::numeric_limits<double>::infinity();
    const int last_row =
      std::min<int>(int(std::floor((last_limit - z0) / h + 1e-9)),
                    int(grid.n_cells()[dim - 1]));
    kept_n_cells.fill(0);
    kept_n_points.fill(0);
    using P = typename MaterialPoints<dim>::PropertyIndex;
    if (hi[dim - 1] < 0)
      return current_top;
    // The surface's line per column (S_w - P - margin) and the row it
    // allows: a cell of row j lies below it when j < surface_row.
    const bool use_surface = prm.surface_limit && !surface.empty();
    auto       surface_row = [&](const std::array<int, dim> &c) {
      return int(std::floor(
        (surface[column(c)] - used_penetration - prm.margin - z0) / h + 1e-9));
    };
    if (use_surface)
      for (std::size_t col = 0; col < surface.size(); ++col)
        {
          bool        inside = true;
          std::size_t rest   = col;
          for (int d = 0; d < dim - 1; ++d)
            {
              const int i = int(rest % grid.n_cells()[d]);
              rest /= grid.n_cells()[d];
              inside = inside && i >= lo[d] && i <= hi[d];
            }
          if (inside)
            least_surface_limit =
              std::min(least_surface_limit,
                       surface[col] - used_penetration - prm.margin);
        }
    // The cells outside the zone at or above the limit line inside the
    // zone's horizontal extent that hold points: their cells and points
    // (over the ranks). @p in_zone tells the zone's cells.
    auto count_above = [&](const auto &in_zone) {
      const auto &occupied = points.occupied_cells();
      for (std::size_t c = 0; c < occupied.size(); ++c)
        {
          const auto           gijk = grid.global_index(occupied[c].first);
          std::array<int, dim> ijk;
          bool                 inside = gijk[dim - 1] >= last_row;
          for (int d = 0; d < dim; ++d)
            {
              ijk[d] = gijk[d];
              if (d < dim - 1)
                inside = inside && ijk[d] >= lo[d] && ijk[d] <= hi[d];
            }
          if (!inside || in_zone(ijk))
            continue;
          double n = 0;
          for (const double *v : points.cell_point_properties(c))
            n += v[P::state] == MaterialPoints<dim>::solid;
          if (n > 0)
            {
              kept_n_cells[above_limit] += 1;
              kept_n_points[above_limit] += n;
            }
        }
      Utilities::MPI::sum(ArrayView<const double>(kept_n_cells.data(), n_kept),
                          comm,
                          ArrayView<double>(kept_n_cells.data(), n_kept));
      Utilities::MPI::sum(ArrayView<const double>(kept_n_points.data(), n_kept),
                          comm,
                          ArrayView<double>(kept_n_points.data(), n_kept));
    };
    // Below the zone's bounding box nothing is the zone's.
    if (last_row <= lo[dim - 1])
      {
        count_above([](const auto &) { return false; });
        return current_top;
      }

    // The zone's cells over its bounding box (every rank: the owners' sum)
    // and the top of each column (one above its highest zone cell; -1:
    // none). Columns: the cells across the last direction, lexicographic
    // (x fastest).
    std::array<int, dim> n_zone;
    std::size_t          n_col = 1, n_zone_all = 1;
    for (int d = 0; d < dim; ++d)
      {
        n_zone[d] = hi[d] - lo[d] + 1;
        n_zone_all *= n_zone[d];
        if (d < dim - 1)
          n_col *= n_zone[d];
      }
    const CellBox<dim> zone_box{lo, n_zone};
    std::vector<int>   in_zone(n_zone_all, 0);
    grid.for_each_owned_cell([&](const std::size_t idx, const auto &ijk) {
      std::array<int, dim> c;
      for (int d = 0; d < dim; ++d)
        c[d] = ijk[d];
      const long k = zone_box.index(c);
      if (k >= 0 && zone[idx])
        in_zone[k] = 1;
    });
    MPI_Allreduce(
      MPI_IN_PLACE, in_zone.data(), int(n_zone_all), MPI_INT, MPI_MAX, comm);
    std::vector<int> col_top(n_col, -1);
    // The lowest row with a cell of the extent outside the zone: the
    // candidates start there (the zone's top for a box).
    int cand_row = first_row;
    for (std::size_t k = 0; k < n_zone_all; ++k)
      {
        const int row = lo[dim - 1] + int(k / n_col);
        if (in_zone[k])
          col_top[k % n_col] = std::max(col_top[k % n_col], row + 1);
        else
          cand_row = std::min(cand_row, row);
      }
    auto zone_cell = [&](const std::array<int, dim> &ijk) {
      const long k = zone_box.index(ijk);
      return k >= 0 && in_zone[k] != 0;
    };
    if (last_row <= cand_row)
      {
        count_above(zone_cell);
        return current_top;
      }

    // Per candidate row from the zone's top (the log): 1 a cell not full
    // of metal or without points, 2 a powder or fluid point, 4 a point at
    // or above the hand-over temperature; and the hottest point. Per cell
    // of the candidate box (rows cand_row to last_row): the same bits, and
    // the mass of its points.
    const int           n_rows = std::max(0, last_row - first_row);
    std::vector<int>    flags(n_rows, 0);
    std::vector<double> hottest(n_rows, 0.);
    std::vector<int>    has_points(grid.n_local(), 0);
    row_mass.assign(n_rows, 0.);
    row_points.assign(n_rows, 0.);
    const auto &cells  = points.occupied_cells();
    auto        in_box = [&](const std::array<int, dim> &ijk) {
      for (int d = 0; d < dim - 1; ++d)
        if (ijk[d] < lo[d] || ijk[d] > hi[d])
          return false;
      return ijk[dim - 1] >= cand_row && ijk[dim - 1] < last_row;
    };
    std::array<int, dim> n_box;
    for (int d = 0; d < dim - 1; ++d)
      n_box[d] = hi[d] - lo[d] + 1;
    n_box[dim - 1]     = last_row - cand_row;
    std::size_t n_fill = 1;
    for (int d = 0; d < dim; ++d)
      n_fill *= n_box[d];
    std::array<int, dim> first;
    for (int d = 0; d < dim - 1; ++d)
      first[d] = lo[d];
    first[dim - 1] = cand_row;
    const CellBox<dim>  cand_box{first, n_box};
    std::vector<int>    cell_flags(n_fill, 0);
    std::vector<double> cell_mass(n_fill, 0.), cell_points(n_fill, 0.);
    // The hottest point of each cell (the re-heating rule's prediction
    // starts there).
    const bool          reheat = prm.rule == Parameters::Rule::reheating;
    std::vector<double> cell_hot(n_fill,
                                 -std::numeric_limits<double>::infinity());
    for (std::size_t c = 0; c < cells.size(); ++c)
      {
        const auto gijk = grid.global_index(cells[c].first);
        if (!in_box(gijk))
          continue;
        std::array<int, dim> ijk;
        for (int d = 0; d < dim; ++d)
          ijk[d] = gijk[d];
        const long k = cand_box.index(ijk);
        const int  r = ijk[dim - 1] - first_row;
        for (const double *v : points.cell_point_properties(c))
          {
            has_points[cells[c].first] = 1;
            cell_mass[k] += v[P::mass];
            cell_points[k] += v[P::state] == MaterialPoints<dim>::solid;
            int bits = 0;
            if (v[P::state] != MaterialPoints<dim>::solid)
              bits |= 2;
            if (!reheat && !(v[P::temperature] < prm.temperature))
              bits |= 4;
            cell_flags[k] |= bits;
            cell_hot[k] = std::max(cell_hot[k], v[P::temperature]);
            if (r >= 0)
              {
                row_mass[r] += v[P::mass];
                row_points[r] += 1;
                flags[r] |= bits;
                hottest[r] = std::max(hottest[r], v[P::temperature]);
              }
          }
      }
    // The fill of each candidate cell: the points' volume under the hat of
    // half-width h centred at the cell's centre, over the hat's volume
    // inside the domain (see the header). Every rank adds its points; the
    // sums of the candidate box are reduced over the ranks.
    std::vector<double> fill(n_fill, 0.);
    // The zone's top face has moved by the lift since the zone was set
    // (multilinear between the nodes of a column's top face; 0 without
    // one): a point of a column's top zone cell is taken that far up, as
    // the metal above it has moved (see the header). A negative lift is
    // taken as 0.
    constexpr unsigned int nf = 1u << (dim - 1);
    AssertThrow(top_lift.empty() || top_lift.size() == nf * n_col,
                ExcMessage("FE zone hand-over: the zone's top lift does not "
                           "match the zone's columns"));
    auto lift_at = [&](const Point<dim> &x, const std::array<int, dim> &c) {
      if (top_lift.empty())
        return 0.;
      std::size_t col = 0;
      for (int d = dim - 2; d >= 0; --d)
        col = col * n_zone[d] + (c[d] - lo[d]);
      double lift = 0;
      for (unsigned int a = 0; a < nf; ++a)
        {
          double w = 1;
          for (int d = 0; d < dim - 1; ++d)
            {
              const bool   up = a & (1u << d);
              const double xi = (x[d] - grid.origin()[d]) / h - c[d];
              w *= up ? xi : 1. - xi;
            }
          lift += w * top_lift[nf * col + a];
        }
      return std::max(lift, 0.);
    };
    for (const auto &particle : points.particle_handler())
      {
        Point<dim>   x = particle.get_location();
        const double V = particle.get_properties()[P::volume];
        {
          std::array<int, dim> c;
          for (int d = 0; d < dim; ++d)
            c[d] = int(std::floor((x[d] - grid.origin()[d]) / h));
          const long k = zone_box.index(c);
          if (k >= 0 && in_zone[k] &&
              c[dim - 1] + 1 == col_top[std::size_t(k) % n_col])
            x[dim - 1] += lift_at(x, c);
        }
        // The two cell centres around x in each direction and the hats'
        // values there.
        std::array<int, dim>    i0;
        std::array<double, dim> w1;
        for (int d = 0; d < dim; ++d)
          {
            const double t = (x[d] - grid.origin()[d]) / h - 0.5;
            i0[d]          = int(std::floor(t));
            w1[d]          = t - i0[d];
          }
        for (unsigned int a = 0; a < (1u << dim); ++a)
          {
            std::array<int, dim> ijk;
            double               w = V;
            for (int d = 0; d < dim; ++d)
              {
                const bool up = a & (1u << d);
                ijk[d]        = i0[d] + (up ? 1 : 0);
                w *= up ? w1[d] : 1. - w1[d];
              }
            const long k = cand_box.index(ijk);
            if (k >= 0 && w > 0)
              fill[k] += w;
          }
      }
    Utilities::MPI::sum(fill, comm, fill);
    // The hat's volume inside the domain: h per direction, 7/8 h at a face
    // of the domain (an eighth of it lies beyond).
    auto hat_volume = [&](const std::array<int, dim> &ijk) {
      double vol = 1;
      for (int d = 0; d < dim; ++d)
        {
          double share = 1;
          if (ijk[d] == 0)
            share -= 0.125;
          if (ijk[d] == int(grid.n_cells()[d]) - 1)
            share -= 0.125;
          vol *= share * h;
        }
      return vol;
    };
    // The metal fraction and the pore cells of the candidate box widened
    // by one cell in each direction (a candidate's 3^dim neighbours), as
    // global arrays: every cell is owned by one rank, the sums gather them.
    std::array<int, dim> first_x, n_x;
    std::size_t          n_ext = 1;
    for (int d = 0; d < dim; ++d)
      {
        first_x[d] = first[d] - 1;
        n_x[d]     = n_box[d] + 2;
        n_ext *= n_x[d];
      }
    const CellBox<dim> ext_box{first_x, n_x};
    // Per widened cell: alpha, 1 where it lies in the grid, 1 on a pore.
    std::vector<double> ext(3 * n_ext, 0.);
    grid.for_each_owned_cell([&](const std::size_t idx, const auto &ijk) {
      std::array<int, dim> c;
      for (int d = 0; d < dim; ++d)
        c[d] = ijk[d];
      const long k = ext_box.index(c);
      if (k < 0)
        return;
      ext[3 * k]     = alpha[idx];
      ext[3 * k + 1] = 1;
      ext[3 * k + 2] = !pore.empty() && pore[idx] > 0 ? 1 : 0;
    });
    Utilities::MPI::sum(ext, comm, ext);
    // Over the 3^dim neighbours of a candidate cell (itself included, those
    // inside the grid): the least alpha of those that are no pore cells
    // (a pore cell stays points and its gas is the pore's: it does not
    // make the metal beside it porous) and whether one is a pore cell.
    auto neighbourhood = [&](const std::array<int, dim> &c) {
      double least_alpha = std::numeric_limits<double>::infinity();
      bool   near_pore   = false;
      for (unsigned int a = 0; a < Utilities::pow(3u, dim); ++a)
        {
          std::array<int, dim> n;
          unsigned int         b = a;
          for (int d = 0; d < dim; ++d, b /= 3)
            n[d] = c[d] + int(b % 3) - 1;
          const long k = ext_box.index(n);
          if (k < 0 || ext[3 * k + 1] == 0)
            continue;
          if (ext[3 * k + 2] > 0)
            near_pore = true;
          else
            least_alpha = std::min(least_alpha, ext[3 * k]);
        }
      return std::make_pair(least_alpha, near_pore);
    };
    // Per candidate cell (outside the zone): bit 1 not dense, 8 kept for a
    // pore (a pore cell, or a cell next to one that is not dense), 16 at
    // or above its column's surface line. Per row
    // from the zone's top, for the log: the cells not dense, their count,
    // the least fill and their horizontal extent (cell indices).
    std::vector<double> n_bad(n_rows, 0.),
      least(n_rows, std::numeric_limits<double>::infinity()),
      least_alpha(n_rows, std::numeric_limits<double>::infinity());
    row_fill.assign(n_rows, std::numeric_limits<double>::infinity());
    std::vector<int> bad_lo(n_rows * (dim - 1),
                            std::numeric_limits<int>::max()),
      bad_hi(n_rows * (dim - 1), -1);
    grid.for_each_owned_cell([&](const std::size_t idx, const auto &ijk) {
      if (!in_box(ijk))
        return;
      std::array<int, dim> c;
      for (int d = 0; d < dim; ++d)
        c[d] = ijk[d];
      if (zone_cell(c))
        return;
      const long   k            = cand_box.index(c);
      const bool   over         = use_surface && c[dim - 1] >= surface_row(c);
      const double f            = fill[k] / hat_volume(c);
      const auto [a, near_pore] = neighbourhood(c);
      const bool pore_cell      = !pore.empty() && pore[idx] > 0;
      const bool dense =
        has_points[idx] && !pore_cell && (a >= dense_alpha || f >= full_fill);
      const bool for_pore = pore_cell || (near_pore && !dense);
      if (!dense)
        cell_flags[k] |= 1;
      if (for_pore)
        cell_flags[k] |= 8;
      if (over)
        cell_flags[k] |= 16;
      const int r = ijk[dim - 1] - first_row;
      if (r < 0)
        return;
      if (over)
        flags[r] |= 16;
      row_fill[r] = std::min(row_fill[r], f);
      if (for_pore)
        flags[r] |= 8;
      if (!dense)
        {
          flags[r] |= 1;
          n_bad[r] += 1;
          least[r] = std::min(least[r], f);
          // Inside a pore (every neighbour a pore cell): its own alpha.
          least_alpha[r] =
            std::min(least_alpha[r], std::isfinite(a) ? a : alpha[idx]);
          for (int d = 0; d < dim - 1; ++d)
            {
              int &l = bad_lo[r * (dim - 1) + d],
                  &u = bad_hi[r * (dim - 1) + d];
              l      = std::min(l, ijk[d]);
              u      = std::max(u, ijk[d]);
            }
        }
    });
    // The cells' flags and masses of all ranks.
    MPI_Allreduce(
      MPI_IN_PLACE, cell_flags.data(), int(n_fill), MPI_INT, MPI_BOR, comm);
    Utilities::MPI::sum(cell_mass, comm, cell_mass);
    Utilities::MPI::sum(cell_points, comm, cell_points);
    MPI_Allreduce(
      MPI_IN_PLACE, cell_hot.data(), int(n_fill), MPI_DOUBLE, MPI_MAX, comm);
    // The rows' flags of all ranks: one maximum per bit.
    constexpr int    n_bits = 5;
    std::vector<int> bits(n_bits * n_rows);
    for (int r = 0; r < n_rows; ++r)
      for (int b = 0; b < n_bits; ++b)
        bits[n_bits * r + b] = (flags[r] >> b) & 1;
    MPI_Allreduce(
      MPI_IN_PLACE, bits.data(), n_bits * n_rows, MPI_INT, MPI_MAX, comm);
    for (int r = 0; r < n_rows; ++r)
      {
        flags[r] = 0;
        for (int b = 0; b < n_bits; ++b)
          flags[r] |= bits[n_bits * r + b] << b;
      }
    MPI_Allreduce(
      MPI_IN_PLACE, hottest.data(), n_rows, MPI_DOUBLE, MPI_MAX, comm);
    // The re-heating rule: a cell's predicted peak in the new layer is its
    // hottest point plus the envelope's rise at its depth below the top
    // (the same arrays on every rank: the same flags).
    std::vector<double> predicted(n_rows,
                                  -std::numeric_limits<double>::infinity());
    kept_prediction   = -std::numeric_limits<double>::infinity();
    handed_prediction = -std::numeric_limits<double>::infinity();
    std::vector<double> cell_peak(n_fill,
                                  -std::numeric_limits<double>::infinity());
    if (reheat)
      for (std::size_t k = 0; k < n_fill; ++k)
        {
          if (!std::isfinite(cell_hot[k]))
            continue;
          const int    j = first[dim - 1] + int(k / (n_fill / n_box[dim - 1]));
          const double below = (layer_top - z0) / h - j - 0.5;
          const int    kd =
            std::clamp(int(std::floor(below)), 0, int(envelope.size()) - 1);
          cell_peak[k] = cell_hot[k] + envelope[kd];
          if (cell_peak[k] >= solidus - prm.reheat_margin)
            cell_flags[k] |= 4;
          const int r = j - first_row;
          if (r >= 0 && (cell_flags[k] & 4))
            {
              flags[r] |= 4;
              predicted[r] = std::max(predicted[r], cell_peak[k]);
            }
        }
    MPI_Allreduce(
      MPI_IN_PLACE, n_bad.data(), n_rows, MPI_DOUBLE, MPI_SUM, comm);
    MPI_Allreduce(
      MPI_IN_PLACE, least.data(), n_rows, MPI_DOUBLE, MPI_MIN, comm);
    MPI_Allreduce(
      MPI_IN_PLACE, least_alpha.data(), n_rows, MPI_DOUBLE, MPI_MIN, comm);
    MPI_Allreduce(
      MPI_IN_PLACE, row_mass.data(), n_rows, MPI_DOUBLE, MPI_SUM, comm);
    MPI_Allreduce(
      MPI_IN_PLACE, row_points.data(), n_rows, MPI_DOUBLE, MPI_SUM, comm);
    MPI_Allreduce(
      MPI_IN_PLACE, row_fill.data(), n_rows, MPI_DOUBLE, MPI_MIN, comm);
    MPI_Allreduce(
      MPI_IN_PLACE, bad_lo.data(), n_rows * (dim - 1), MPI_INT, MPI_MIN, comm);
    MPI_Allreduce(
      MPI_IN_PLACE, bad_hi.data(), n_rows * (dim - 1), MPI_INT, MPI_MAX, comm);

    // The cells taken: the candidates (no flag) reached from the zone over
    // faces of candidates (the same on every rank: all hold the flags).
    auto cell_of = [&](std::size_t k) {
      std::array<int, dim> c;
      for (int d = 0; d < dim; ++d)
        c[d] = first[d] + int(k % n_box[d]), k /= n_box[d];
      return c;
    };
    auto candidate = [&](const long k, const std::array<int, dim> &c) {
      return k >= 0 && cell_flags[k] == 0 && !zone_cell(c);
    };
    std::vector<std::uint8_t> taken(n_fill, 0);
    std::vector<std::size_t>  front;
    for (std::size_t k = 0; k < n_fill; ++k)
      {
        const auto c = cell_of(k);
        if (!candidate(k, c))
          continue;
        for (unsigned int f = 0; f < 2 * dim && !taken[k]; ++f)
          {
            auto nb = c;
            nb[f / 2] += f % 2 ? 1 : -1;
            if (zone_cell(nb))
              taken[k] = 1, front.push_back(k);
          }
      }
    for (std::size_t i = 0; i < front.size(); ++i)
      {
        const auto c = cell_of(front[i]);
        for (unsigned int f = 0; f < 2 * dim; ++f)
          {
            auto nb = c;
            nb[f / 2] += f % 2 ? 1 : -1;
            const long k = cand_box.index(nb);
            if (candidate(k, nb) && !taken[k])
              taken[k] = 1, front.push_back(k);
          }
      }
    int top_row = first_row;
    for (std::size_t k = 0; k < n_fill; ++k)
      if (taken[k])
        {
          const auto c = cell_of(k);
          chosen.push_back(c);
          chosen_mass += cell_mass[k];
          handed_prediction = std::max(handed_prediction, cell_peak[k]);
          top_row           = std::max(top_row, c[dim - 1] + 1);
        }

    // Why the other cells with solid points stay points: above the limit
    // (the points of every rank, then summed), else by their flags (the
    // same on every rank: added after the sum).
    count_above(zone_cell);
    for (std::size_t k = 0; k < n_fill; ++k)
      {
        if (taken[k] || cell_points[k] == 0 || zone_cell(cell_of(k)))
          continue;
        const int  f   = cell_flags[k];
        const Kept why = f & 16 ? above_limit :
                         f & 2  ? powder :
                         f & 8  ? Kept::pore :
                         f & 1  ? not_dense :
                         f & 4  ? too_hot :
                                  not_connected;
        kept_n_cells[why] += 1;
        kept_n_points[why] += cell_points[k];
        if (why == too_hot)
          kept_prediction = std::max(kept_prediction, cell_peak[k]);
      }

    // The lowest row above the zone's top that keeps cells as points, and
    // why (the log).
    int r = 0;
    while (r < n_rows && flags[r] == 0)
      ++r;
    if (r < n_rows)
      {
        std::ostringstream s;
        s << "the row at z = " << z0 + (first_row + r) * h << " m holds ";
        if (flags[r] & 1)
          {
            s << n_bad[r] << " cells not dense (fill down to " << least[r]
              << ", alpha around them down to " << least_alpha[r];
            for (int d = 0; d < dim - 1; ++d)
              s << (d ? ", " : "; ") << (d ? "y" : "x") << " within "
                << grid.origin()[d] + bad_lo[r * (dim - 1) + d] * h << " to "
                << grid.origin()[d] + (bad_hi[r * (dim - 1) + d] + 1) * h
                << " m";
            s << ")";
          }
        // Every reason of the row, so that the log shows all that blocks.
        if (flags[r] & 8)
          s << ", a pore cell in or next to the row";
        if (flags[r] & 2)
          s << (flags[r] & 1 ? ", " : "") << "powder or fluid points";
        if (flags[r] & 4)
          {
            s << (flags[r] & 3 ? ", " : "") << "points up to " << hottest[r]
              << " K";
            if (reheat)
              s << " (a predicted peak up to " << predicted[r] << " K)";
          }
        if (flags[r] & 16)
          s << (flags[r] & 15 ? ", " : "")
            << "cells above the metal surface's line (down to "
            << least_surface_limit << " m: the lowest metal surface near "
            << "them less the penetration depth " << used_penetration
            << " m and the margin)";
        reason = s.str();
      }
    return z0 + top_row * h;
  }

  template <int dim>
  void
  FeZoneHandover<dim>::save_state(StateWriter &out) const
  {
    out.put(layer_top);
    // The lowest of all ranks (what the next choice reduces to), so that
    // the file does not depend on where each rank's lowest lies.
    out.put(Utilities::MPI::min(lowest, grid.communicator()));
    out.put(depth);
    out.put(current_top);
    out.put(last_limit);
    out.put(kept_n_cells);
    out.put(kept_n_points);
    // The layer's rises of all ranks (what the next choice reduces to),
    // the envelope and the temperatures the rises start from.
    std::vector<double> all(rise);
    MPI_Allreduce(MPI_IN_PLACE,
                  all.data(),
                  int(all.size()),
                  MPI_DOUBLE,
                  MPI_MAX,
                  grid.communicator());
    out.put_vector(all);
    out.put_vector(envelope);
    out.put<std::uint64_t>(history.size());
    for (const auto &h : history)
      out.put_vector(h);
    out.put<std::uint8_t>(start_pending);
    // The penetration depth, the layer's lowest molten cell per column of
    // all ranks and the surface it met.
    out.put(penetration);
    out.put_vector(all_col_lowest());
    out.put_vector(start_surface);
  }

  template <int dim>
  void
  FeZoneHandover<dim>::save_layer_start(StateWriter &out) const
  {
    save_cell_fields(out, grid, {&T_start});
  }

  template <int dim>
  void
  FeZoneHandover<dim>::load_layer_start(std::vector<StateReader> &parts)
  {
    load_cell_fields(parts, grid, {&T_start});
  }

  template <int dim>
  const char *
  FeZoneHandover<dim>::kept_name(const unsigned int k)
  {
    static const char *names[n_kept] = {
      "above_limit", "powder", "pore", "not_dense", "too_hot", "not_connected"};
    AssertIndexRange(k, n_kept);
    return names[k];
  }

  template <int dim>
  void
  FeZoneHandover<dim>::load_state(std::vector<StateReader> &parts)
  {
    // The lowest molten cell of all ranks (every part holds it).
    lowest = std::numeric_limits<double>::infinity();
    for (std::size_t f = 0; f < parts.size(); ++f)
      {
        StateReader &in = parts[f];
        const double t = in.get<double>(), low = in.get<double>(),
                     d = in.get<double>(), top = in.get<double>(),
                     limit = in.get<double>();
        const auto cells   = in.get<std::array<double, n_kept>>();
        const auto pts     = in.get<std::array<double, n_kept>>();
        lowest             = std::min(lowest, low);
        const auto                       r = in.get_vector<double>();
        const auto                       e = in.get_vector<double>();
        std::vector<std::vector<double>> hist(in.get<std::uint64_t>());
        for (auto &h : hist)
          h = in.get_vector<double>();
        const bool   pending = in.get<std::uint8_t>();
        const double pen     = in.get<double>();
        const auto   low_col = in.get_vector<double>();
        const auto   start   = in.get_vector<double>();
        AssertThrow(low_col.size() == col_lowest.size() &&
                      (start.empty() || start.size() == col_lowest.size()),
                    ExcMessage("checkpoint: the hand-over's metal surface "
                               "does not match the grid's columns"));
        if (f == 0)
          penetration = pen, col_lowest = low_col, start_surface = start;
        AssertThrow(r.size() == rise.size() && e.size() == envelope.size(),
                    ExcMessage("checkpoint: the hand-over's rises per depth "
                               "do not match the grid's rows"));
        if (f == 0)
          layer_top = t, depth = d, current_top = top, last_limit = limit,
          kept_n_cells = cells, kept_n_points = pts, rise = r, envelope = e,
          history = hist, start_pending = pending;
      }
  }

  template class FeZoneHandover<2>;
  template class FeZoneHandover<3>;
} // namespace femp
