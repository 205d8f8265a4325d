// femp: the free surface of the melt flow: smoothed metal fraction,
// interface position, capillary pressure sigma div(n), recoil pressure and
// Marangoni traction (paper sec. 2.3, eq. 3; doc/flow.md). See
// include/femp/flow/free_surface.h.
#include <femp/base/input_checks.h>
#include <femp/base/parameter_table.h>
#include <femp/base/recoil_law.h>
#include <femp/flow/free_surface.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace femp
{
  namespace
  {
    constexpr int gas   = flow_cells::gas;
    constexpr int solid = flow_cells::solid;
    constexpr int fluid = flow_cells::fluid;
  } // namespace

  template <int dim>
  void
  FreeSurface<dim>::Parameters::add_parameters(ParameterTable &table)
  {
    table.add("Curvature smoothing",
              curvature_smoothing,
              Patterns::Integer(0, 4),
              "Passes of the curvature smoothing: each pass replaces "
              "the capillary pressure of a free-surface cell by the "
              "mean over the free-surface cells among its 3^dim "
              "neighbours (see doc/flow.md); 0: none. Allowed: 0, "
              "2 or 4 (an odd number of passes flips the sign of the "
              "curvature's cell-to-cell noise, and the surface goes "
              "unstable; doc/stability.md).");
    table.add("Curvature",
              curvature,
              {{Curvature::alpha_gradient, "alpha gradient"},
               {Curvature::height_function, "height function"}},
              "How the curvature div(n) of a free-surface cell is "
              "computed (doc/flow.md): 'alpha gradient' (default), "
              "the divergence of the normalized gradient of the "
              "smoothed metal fraction at the cell's corners; "
              "'height function', the heights of the metal fraction "
              "summed over columns of 7 cells along the normal's "
              "largest component, 3 (2D) or 3 x 3 (3D) columns, "
              "falling back to the alpha gradient where a column "
              "does not cross the surface (melt thinner than about "
              "3 cells, walls).");
    table.add("Surface tension",
              surface_tension,
              Patterns::Double(0.),
              "Surface tension coefficient sigma, N/m (0: no surface "
              "tension); enters as the capillary pressure sigma div(n) "
              "at the free surface. Range [0, inf).");
    table.add("Surface tension temperature derivative",
              surface_tension_gradient,
              Patterns::Double(),
              "dsigma/dT of the Marangoni stress with the linear Surface "
              "tension model, N/(m K) (negative for most metals; 0: no "
              "Marangoni stress). Range any real number.");
    SurfaceTension::add_model_parameter(table, surface_tension_model);
    surfactant.add_parameters(table);
    table.add("Recoil coefficient",
              recoil_coefficient,
              Patterns::Double(0., 1.),
              "zeta_p of the recoil pressure zeta_p p0 exp[L_v M "
              "(T - T_v)/(R T T_v)] (about 0.54; 0: no recoil), with "
              "L_v, M, T_v, p0 from the Heat transfer subsection. "
              "Range [0, 1].");
    table.add("Recoil temperature",
              recoil_temperature,
              {{RecoilTemperature::limited, "limited"},
               {RecoilTemperature::cell, "cell"},
               {RecoilTemperature::median, "median"}},
              "The surface temperature T of a free-surface cell's recoil "
              "pressure (see doc/flow.md, \"Recoil pressure\"): 'limited' "
              "(default), the cell's own temperature limited to the range of "
              "those of the other free-surface cells among its 3^dim "
              "neighbours (a single-cell extremum is cut to its neighbours' "
              "nearest value); 'cell', the cell's own temperature; 'median', "
              "the median of the temperatures of the free-surface cells among "
              "its 3^dim neighbours, itself included.");
    table.add("Recoil above ambient",
              recoil_above_ambient,
              "Whether the recoil enters the free-surface pressure net of "
              "the ambient pressure p0 that the gas exerts everywhere else: "
              "true: max(0, zeta_p p_sat(T) - p0), p_sat(T) = p0 exp[L_v M "
              "(T - T_v)/(R T T_v)] (zero below the temperature at which "
              "zeta_p p_sat = p0, 3213 K for 316L's data); false: zeta_p "
              "p_sat(T), which is zeta_p p0 already at T_v. The front-wall "
              "film, expulsion and piston take the same law (see doc/flow.md, "
              "\"Recoil pressure\").");
  }

  template <int dim>
  void
  FreeSurface<dim>::Parameters::declare_parameters(ParameterHandler &prm)
  {
    Parameters     defaults;
    ParameterTable table(prm, ParameterTable::Mode::declare);
    defaults.add_parameters(table);
  }

  template <int dim>
  void
  FreeSurface<dim>::Parameters::parse_parameters(ParameterHandler &prm)
  {
    ParameterTable table(prm, ParameterTable::Mode::parse);
    add_parameters(table);
    require(surface_tension >= 0,
            "Melt flow/Surface tension",
            surface_tension,
            "it must be non-negative (N/m)");
    surfactant.check();
    // One pass maps the curvature's cell-to-cell alternation on a chain of
    // surface cells to -1/3 of itself (the mean of a cell and its two
    // neighbours): an odd number of passes turns the restoring capillary
    // pressure of a one-cell wrinkle into one that pushes it further, and
    // the drops of doc/stability.md ("Curvature smoothing") go unstable.
    require(curvature_smoothing % 2 == 0,
            "Melt flow/Curvature smoothing",
            curvature_smoothing,
            "it must be 0, 2 or 4: an odd number of passes reverses the sign "
            "of the curvature's cell-to-cell noise, which makes the free "
            "surface unstable (doc/stability.md, \"Curvature smoothing\")");
  }

  template <int dim>
  FreeSurface<dim>::FreeSurface(const Parameters          &prm,
                                const Material            &material,
                                const BackgroundGrid<dim> &grid,
                                const MaterialPoints<dim> &points)
      : prm(prm)
      , tension(prm.surface_tension_law())
      , mat(material)
      , grid(grid)
      , points(points)
      , corner_offset(flow_cells::corner_offsets(grid, true))
      , around_offset(flow_cells::corner_offsets(grid, false))
      , stencil(flow_cells::neighbourhood(grid))
  {
    p_surface    = grid.make_field(0.);
    p_capillary  = grid.make_field(0.);
    surface_mark = grid.make_field(0.);
    alpha_cell   = grid.make_field(0.);
    alpha_node   = grid.make_node_field();
    for (int d = 0; d < dim; ++d)
      surface_force[d] = grid.make_node_field();
    for (int f = 0; f < 2 * dim; ++f)
      theta[f] = grid.make_field(0.5);
    near1 = grid.make_field();
    near2 = grid.make_field();
  }

  template <int dim>
  void
  FreeSurface<dim>::update(const std::vector<double>        &type,
                           const std::vector<std::uint32_t> &fluid_cells,
                           const std::vector<double>        *temperature)
  {
    const bool thermal = tension.marangoni() || prm.recoil_coefficient > 0;
    AssertThrow(!thermal || temperature != nullptr,
                ExcMessage("Melt flow: Marangoni stress and recoil pressure "
                           "need the cell temperature (CellFields)."));
    mark_near_fluid(type);
    map_metal_fraction();
    locate_interface(type, fluid_cells);
    if (!prm.any())
      return;
    if (prm.curvature == Parameters::Curvature::height_function &&
        prm.surface_tension > 0)
      height_columns(type);
    capillary_and_marangoni(type, fluid_cells, temperature);
    if (prm.recoil_coefficient > 0 ||
        (prm.curvature_smoothing > 0 && prm.surface_tension > 0))
      grid.update_ghosts(surface_mark);
    add_recoil_pressure(fluid_cells, temperature);
    smooth_capillary_pressure(fluid_cells);
    grid.update_ghosts(p_surface);
  }

  template <int dim>
  void
  FreeSurface<dim>::mark_near_fluid(const std::vector<double> &type)
  {
    // Only cells near the fluid need alpha: near1 = within one cell of a
    // fluid cell (alpha_cell is used there), near2 = within two (their
    // points contribute to the nodes of near1 cells). Marked from the fluid
    // cells of the local box; near1 of ghosts comes from their owners.
    const auto &status = grid.cell_status();
    std::fill(near1.begin(), near1.end(), 0.);
    std::fill(near2.begin(), near2.end(), 0.);
    for (std::size_t c = 0; c < type.size(); ++c)
      if (type[c] == fluid)
        for (const auto o : stencil)
          {
            const std::ptrdiff_t e = std::ptrdiff_t(c) + o;
            if (e >= 0 && std::size_t(e) < near1.size())
              near1[e] = 1;
          }
    grid.update_ghosts(near1);
    for (std::size_t c = 0; c < near1.size(); ++c)
      if (near1[c] != 0 && status[c] != BackgroundGrid<dim>::outside)
        for (const auto o : stencil)
          {
            const std::ptrdiff_t e = std::ptrdiff_t(c) + o;
            if (e >= 0 && std::size_t(e) < near2.size())
              near2[e] = 1;
          }
  }

  template <int dim>
  void
  FreeSurface<dim>::map_metal_fraction()
  {
    using P          = typename MaterialPoints<dim>::PropertyIndex;
    const double h   = grid.h();
    const double ih  = 1. / h;
    const double ihd = std::pow(ih, dim);
    const auto  &x0  = grid.origin();
    // alpha at nodes: volume of the metal points near the fluid, tent
    // weights.
    std::fill(alpha_node.begin(), alpha_node.end(), 0.);
    const auto &handler = points.particle_handler();
    for (const auto &[idx, cell] : points.occupied_cells())
      {
        if (near2[idx] == 0)
          continue;
        const auto        ijk = grid.global_index(idx);
        const std::size_t n0  = grid.first_node_of_cell(idx);
        for (const auto &particle : handler.particles_in_cell(cell))
          {
            const Point<dim> x = particle.get_location();
            double           xi[dim];
            for (int d = 0; d < dim; ++d)
              xi[d] = (x[d] - x0[d]) * ih - ijk[d];
            const double V = particle.get_properties()[P::volume] * ihd;
            for (unsigned int k = 0; k < n_corners; ++k)
              {
                double w = V;
                for (int d = 0; d < dim; ++d)
                  w *= ((k >> d) & 1) ? xi[d] : 1. - xi[d];
                alpha_node[n0 + corner_offset[k]] += w;
              }
          }
      }
    grid.sum_shared_nodes(alpha_node);
    // Smoothed alpha at the owned near1 cell centres: mean of the cell's
    // nodes, node values mirrored at the domain boundary (walls are not
    // free surfaces).
    std::fill(alpha_cell.begin(), alpha_cell.end(), 0.);
    for (const auto c : grid.owned_cells())
      {
        if (near1[c] == 0)
          continue;
        double a = 0;
        for (const double ak : corner_alpha(c))
          a += ak;
        alpha_cell[c] = a / n_corners;
      }
    grid.update_ghosts(alpha_cell);
  }

  template <int dim>
  void
  FreeSurface<dim>::locate_interface(
    const std::vector<double>        &type,
    const std::vector<std::uint32_t> &fluid_cells)
  {
    // Free-surface position on each fluid-gas face: where the smoothed
    // alpha, linear between the two cell centres, is 1/2; theta is its
    // distance from the fluid cell centre in units of h, in
    // [theta_min, 1] (1/2 for a fluid cell filled to its face).
    const auto &cs = grid.strides();
    for (int f = 0; f < 2 * dim; ++f)
      std::fill(theta[f].begin(), theta[f].end(), 0.5);
    for (const auto c : fluid_cells)
      for (int d = 0; d < dim; ++d)
        for (const int side : {0, 1})
          {
            const std::size_t g = side ? c + cs[d] : c - cs[d];
            if (type[g] != gas)
              continue;
            const double ac = alpha_cell[c], ag = alpha_cell[g];
            const double th = ac > ag ? (ac - 0.5) / (ac - ag) : theta_min;
            theta[2 * d + side][c] = std::min(std::max(th, theta_min), 1.);
          }
    for (int f = 0; f < 2 * dim; ++f)
      grid.update_ghosts(theta[f]);
  }

  // Height-function curvature (Cummins, Francois and Kothe 2005; Popinet
  // 2009): across a surface that is a graph over the directions other than
  // d, the column sums H of alpha along d (in cells) are the surface's
  // height up to a constant, and div(n) = -H''/(h (1 + H'^2)^(3/2)) in 2D
  // with central differences over three columns (both orientations of the
  // metal give the same sign), in 3D with the mixed derivative over 3 x 3
  // columns. The columns are 7 cells long, centred on the surface cell's
  // row. Unlike the divergence of alpha's gradient, whose error relative
  // to 1/R grows with R/h, this is consistent: the smoothing of alpha by
  // the tent weights moves a column sum only by the curvature of the
  // surface times h^2.
  template <int dim>
  void
  FreeSurface<dim>::height_columns(const std::vector<double> &type)
  {
    const auto  &cs     = grid.strides();
    const auto  &status = grid.cell_status();
    const double nan    = std::numeric_limits<double>::quiet_NaN();
    // alpha where it is known: near1 cells (computed) and gas cells (no
    // metal); NaN elsewhere, so that a column through such a cell is NaN.
    const auto a = [&](const std::size_t c) {
      if (status[c] == BackgroundGrid<dim>::outside)
        return nan;
      return (near1[c] != 0 || type[c] == gas) ? alpha_cell[c] : nan;
    };
    for (int d = 0; d < dim; ++d)
      {
        if (col3[d].empty())
          {
            col3[d] = grid.make_field(nan);
            col5[d] = grid.make_field(nan);
          }
        auto &c3 = col3[d];
        auto &c5 = col5[d];
        for (const auto c : grid.owned_cells())
          c3[c] = near2[c] != 0 ? a(c - cs[d]) + a(c) + a(c + cs[d]) : nan;
        grid.update_ghosts(c3);
        for (const auto c : grid.owned_cells())
          c5[c] = near1[c] != 0 ? c3[c - cs[d]] + c3[c + cs[d]] - a(c) : nan;
        grid.update_ghosts(c5);
      }
  }

  template <int dim>
  double
  FreeSurface<dim>::height_function_curvature(const std::size_t c,
                                              const double     *n) const
  {
    const auto &cs = grid.strides();
    int         d  = 0;
    for (int e = 1; e < dim; ++e)
      if (std::abs(n[e]) > std::abs(n[d]))
        d = e;
    const auto &c3 = col3[d];
    const auto &c5 = col5[d];
    // 7-cell sum of the column through x: cells x - 3 ... x + 3 along d.
    const auto column = [&](const std::size_t x) {
      return c5[x - cs[d]] + c5[x + cs[d]] - c3[x];
    };
    // The other directions (one in 2D, two in 3D).
    int e[2] = {0, 0}, ne = 0;
    for (int k = 0; k < dim; ++k)
      if (k != d)
        e[ne++] = k;
    double H[3][3];
    for (int i = -1; i <= 1; ++i)
      for (int j = -1; j <= 1; ++j)
        {
          if (dim == 2 && j != 0)
            continue;
          std::ptrdiff_t o = i * cs[e[0]];
          if (dim == 3)
            o += j * cs[e[1]];
          const double Hij = column(std::size_t(std::ptrdiff_t(c) + o));
          // Each column must cross the surface well inside its 7 cells.
          if (!(Hij > 0.5 && Hij < 6.5))
            return std::numeric_limits<double>::quiet_NaN();
          H[i + 1][j + 1] = Hij;
        }
    const double h = grid.h();
    if (dim == 2)
      {
        const double Hx  = 0.5 * (H[2][1] - H[0][1]);
        const double Hxx = H[2][1] - 2 * H[1][1] + H[0][1];
        return -Hxx / (h * std::pow(1 + Hx * Hx, 1.5));
      }
    const double Hx  = 0.5 * (H[2][1] - H[0][1]);
    const double Hy  = 0.5 * (H[1][2] - H[1][0]);
    const double Hxx = H[2][1] - 2 * H[1][1] + H[0][1];
    const double Hyy = H[1][2] - 2 * H[1][1] + H[1][0];
    const double Hxy = 0.25 * (H[2][2] - H[2][0] - H[0][2] + H[0][0]);
    return -((1 + Hy * Hy) * Hxx + (1 + Hx * Hx) * Hyy - 2 * Hx * Hy * Hxy) /
           (h * std::pow(1 + Hx * Hx + Hy * Hy, 1.5));
  }

  template <int dim>
  void
  FreeSurface<dim>::capillary_and_marangoni(
    const std::vector<double>        &type,
    const std::vector<std::uint32_t> &fluid_cells,
    const std::vector<double>        *temperature)
  {
    const double h      = grid.h();
    const auto  &cs     = grid.strides();
    const auto  &status = grid.cell_status();
    // Surface cells (owned fluid cells with a gas face): p_s = sigma div(n)
    // + p_recoil(T), and the Marangoni traction on their gas faces.
    std::fill(p_surface.begin(), p_surface.end(), 0.);
    std::fill(p_capillary.begin(), p_capillary.end(), 0.);
    std::fill(surface_mark.begin(), surface_mark.end(), 0.);
    const bool marangoni = tension.marangoni();
    if (marangoni)
      for (int d = 0; d < dim; ++d)
        std::fill(surface_force[d].begin(), surface_force[d].end(), 0.);
    for (const auto c : fluid_cells)
      {
        bool surface = false;
        for (int d = 0; d < dim; ++d)
          surface = surface || type[c + cs[d]] == gas || type[c - cs[d]] == gas;
        if (!surface)
          continue;
        double div     = 0;
        double nc[dim] = {};
        for (unsigned int k = 0; k < n_corners; ++k)
          {
            // Node k of cell c; the cell above it is c0.
            const std::size_t c0 = c + around_offset[k];
            double            g[dim], norm = 0;
            for (int d = 0; d < dim; ++d)
              {
                g[d] = 0;
                for (unsigned int j = 0; j < n_corners; ++j)
                  if (!((j >> d) & 1))
                    {
                      const std::size_t up = c0 - around_offset[j];
                      const std::size_t lo = up - cs[d];
                      // Outside the domain alpha has zero gradient.
                      if (status[up] != BackgroundGrid<dim>::outside &&
                          status[lo] != BackgroundGrid<dim>::outside)
                        g[d] += alpha_cell[up] - alpha_cell[lo];
                    }
                norm += g[d] * g[d];
              }
            norm = std::sqrt(norm);
            if (norm > 1e-8)
              for (int d = 0; d < dim; ++d)
                {
                  div -= (((k >> d) & 1) ? 1. : -1.) * g[d] / norm;
                  nc[d] -= g[d] / norm;
                }
          }
        double ps = prm.surface_tension * div / (h * (1u << (dim - 1)));
        if (prm.curvature == Parameters::Curvature::height_function &&
            prm.surface_tension > 0)
          {
            const double k = height_function_curvature(c, nc);
            if (std::isfinite(k))
              ps = prm.surface_tension * k;
          }
        p_capillary[c]  = ps;
        surface_mark[c] = 1;
        p_surface[c]    = ps; // the recoil is added by add_recoil_pressure()
        if (!marangoni)
          continue;
        const double T = (*temperature)[c];
        // dsigma/dT at the cell's temperature (constant: linear model).
        const double dsdT = tension.gradient(T);
        // Unit normal of the cell; grad T from metal neighbours.
        double nn = 0;
        for (int d = 0; d < dim; ++d)
          nn += nc[d] * nc[d];
        nn = std::sqrt(nn);
        if (nn < 1e-12)
          continue;
        double gT[dim], ndotg = 0;
        for (int d = 0; d < dim; ++d)
          {
            nc[d] /= nn;
            const bool m = type[c - cs[d]] == fluid || type[c - cs[d]] == solid;
            const bool p = type[c + cs[d]] == fluid || type[c + cs[d]] == solid;
            const double Tm = m ? (*temperature)[c - cs[d]] : T;
            const double Tp = p ? (*temperature)[c + cs[d]] : T;
            gT[d]           = (m && p) ? (Tp - Tm) / (2 * h) : (Tp - Tm) / h;
            ndotg += nc[d] * gT[d];
          }
        const double face = std::pow(h, dim - 1) / (1u << (dim - 1));
        for (int d = 0; d < dim; ++d)
          for (const int side : {0, 1})
            {
              const std::ptrdiff_t o = side ? cs[d] : -cs[d];
              if (type[c + o] != gas)
                continue;
              const double      w  = dsdT * face * std::abs(nc[d]);
              const std::size_t n0 = grid.first_node_of_cell(c);
              for (unsigned int k = 0; k < n_corners; ++k)
                if ((int((k >> d) & 1)) == side)
                  for (int e = 0; e < dim; ++e)
                    surface_force[e][n0 + corner_offset[k]] +=
                      w * (gT[e] - ndotg * nc[e]);
            }
      }
    if (marangoni)
      for (int d = 0; d < dim; ++d)
        grid.sum_shared_nodes(surface_force[d]);
  }

  // Recoil pressure zeta_p p0 exp[L_v M (T_s - T_v)/(R T_s T_v)] of each
  // surface cell (doc/flow.md, "Recoil pressure"), or with Melt
  // flow/Recoil above ambient its part above the ambient pressure p0 that
  // the gas exerts on the whole surface (the flow's pressure is relative
  // to it): max(0, zeta_p p_sat - p0). T_s (Melt flow/Recoil
  // temperature): 'limited' (default), the cell's own temperature limited
  // to the range of the temperatures of the other surface cells among its
  // 3^dim neighbours; 'cell', its own temperature; 'median', the median
  // over the surface cells among its 3^dim neighbours (itself included; the
  // mean of the two middle values for an even count). Single surface cells
  // can be far hotter than all their neighbours: on the 3D track, before
  // the heat equation's fix of partly filled surface cells, cells at the
  // top of melting powder grains reached 8,000-17,000 K next to cells at
  // 4,500-6,000 K, and the exponential turned that into recoil jumps of
  // 1e9-3e10 Pa that blew the fragment apart at 300-5,000 m/s. Both the
  // limiter and the median cut such a single-cell extremum to its
  // neighbours' values and keep the cell's own temperature where T is
  // monotone along the surface. At a smooth peak the limiter takes the
  // hottest neighbour's value (a second-order cut), the median about the
  // value one cell away: near the beam the surface T falls by several
  // hundred K per cell, and the median's recoil above 4000 K is typically
  // 0.3 (0.03-0.65) of the cell-wise value, which starves the vapour
  // depression (doc/flow.md, "Recoil pressure").
  template <int dim>
  void
  FreeSurface<dim>::add_recoil_pressure(
    const std::vector<std::uint32_t> &fluid_cells,
    const std::vector<double>        *temperature)
  {
    if (prm.recoil_coefficient == 0)
      return;
    const RecoilLaw law(mat, prm.recoil_coefficient, prm.recoil_above_ambient);
    using RT = typename Parameters::RecoilTemperature;
    std::array<double, 27> Ts;
    for (const auto c : fluid_cells)
      {
        if (surface_mark[c] == 0)
          continue;
        double T = (*temperature)[c];
        if (prm.recoil_temperature == RT::median)
          {
            unsigned int n = 0;
            for (const auto o : stencil)
              if (surface_mark[c + o] != 0)
                Ts[n++] = (*temperature)[c + o];
            std::sort(Ts.begin(), Ts.begin() + n);
            T = (n % 2) ? Ts[n / 2] : 0.5 * (Ts[n / 2 - 1] + Ts[n / 2]);
          }
        else if (prm.recoil_temperature == RT::limited)
          {
            double lo = std::numeric_limits<double>::infinity(), hi = -lo;
            for (const auto o : stencil)
              if (o != 0 && surface_mark[c + o] != 0)
                {
                  lo = std::min(lo, (*temperature)[c + o]);
                  hi = std::max(hi, (*temperature)[c + o]);
                }
            if (lo <= hi)
              T = std::min(std::max(T, lo), hi);
          }
        p_surface[c] += law.pressure(T);
      }
  }

  // Curvature smoothing: the curvature div(n) of the smoothed alpha at a
  // staircase surface is noisy from cell to cell (at a round drop of
  // R = 20 h the capillary pressure of single surface cells ranged from 0.13
  // to 2.5 sigma/R). Each pass replaces the capillary part of p_s of every
  // surface cell by the mean over the surface cells among its 3^dim
  // neighbours (itself included), i.e. the curvature is averaged along the
  // interface over about three cells per pass, the usual remedy of
  // convolved-CSF schemes (smoothed curvature; cf. the height-function and
  // smoothing comparisons of Cummins, Francois and Kothe 2005). The recoil
  // part is not smoothed.
  template <int dim>
  void
  FreeSurface<dim>::smooth_capillary_pressure(
    const std::vector<std::uint32_t> &fluid_cells)
  {
    if (prm.curvature_smoothing == 0 || prm.surface_tension == 0)
      return;
    std::vector<double> smoothed(fluid_cells.size());
    for (unsigned int pass = 0; pass < prm.curvature_smoothing; ++pass)
      {
        grid.update_ghosts(p_capillary);
        for (std::size_t i = 0; i < fluid_cells.size(); ++i)
          {
            const std::size_t c = fluid_cells[i];
            if (surface_mark[c] == 0)
              continue;
            double sum = 0, n = 0;
            for (const auto o : stencil)
              if (surface_mark[c + o] != 0)
                sum += p_capillary[c + o], n += 1;
            smoothed[i] = sum / n;
          }
        for (std::size_t i = 0; i < fluid_cells.size(); ++i)
          {
            const std::size_t c = fluid_cells[i];
            if (surface_mark[c] == 0)
              continue;
            p_surface[c] += smoothed[i] - p_capillary[c];
            p_capillary[c] = smoothed[i];
          }
      }
  }

  // Where the recoil drives the melt (Melt flow/Front wall film): the
  // recoil part of p_s is p_s - p_capillary (the capillary part after its
  // smoothing).
  template <int dim>
  void
  FreeSurface<dim>::mark_recoil_driven(
    const std::vector<std::uint32_t> &fluid_cells,
    std::vector<double>              &driven) const
  {
    if (driven.size() != grid.n_local())
      driven = grid.make_field(0.);
    else
      std::fill(driven.begin(), driven.end(), 0.);
    // The recoil at T_v: zeta_p p0, or net of the ambient pressure zero
    // (the recoil starts where zeta_p p_sat reaches p0).
    const double boiling =
      RecoilLaw(mat, prm.recoil_coefficient, prm.recoil_above_ambient)
        .at_evaporation_temperature();
    if (prm.recoil_coefficient > 0)
      for (const auto c : fluid_cells)
        {
          if (surface_mark[c] == 0)
            continue;
          const double recoil = p_surface[c] - p_capillary[c];
          if (recoil > boiling && recoil > std::abs(p_capillary[c]))
            driven[c] = 1;
        }
    grid.update_ghosts(driven);
  }

  template <int dim>
  std::array<double, (1u << dim)>
  FreeSurface<dim>::corner_alpha(const std::size_t c) const
  {
    const auto                     &nc  = grid.n_cells();
    const auto                      ijk = grid.global_index(c);
    const std::size_t               n0  = grid.first_node_of_cell(c);
    std::array<double, (1u << dim)> a;
    for (unsigned int k = 0; k < n_corners; ++k)
      {
        double f = 1;
        for (int d = 0; d < dim; ++d)
          {
            const int i = ijk[d] + ((k >> d) & 1);
            if (i == 0 || i == int(nc[d]))
              f *= 2;
          }
        a[k] = f * alpha_node[n0 + corner_offset[k]];
      }
    return a;
  }

  template class FreeSurface<2>;
  template class FreeSurface<3>;
} // namespace femp
