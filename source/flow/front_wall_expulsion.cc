// femp: sub-cell expulsion of the melt from a boiling surface at the
// Bernoulli speed of its recoil (Melt flow/Front wall expulsion;
// doc/flow.md, "Front wall expulsion"; the piston of Semak and Matsunawa,
// J. Phys. D 30 (1997) 2541: melt velocity u = sqrt(2 p_r / rho), film
// thickness from the mass and energy balances of PistonFilm::film()).
#include <femp/flow/flow_cells.h>
#include <femp/flow/front_wall_expulsion.h>

#include <algorithm>
#include <cmath>

namespace femp
{
  template <int dim>
  FrontWallExpulsion<dim>::FrontWallExpulsion(const BackgroundGrid<dim> &grid,
                                              const Material  &material,
                                              const RecoilLaw &recoil,
                                              const double     spot_radius,
                                              const double     T_far)
      : grid(grid)
      , rho(material.density)
      , piston(material, recoil, spot_radius, T_far)
      , around_offset(flow_cells::corner_offsets(grid, false))
      , speed(grid.make_field(0.))
  {
    for (int d = 0; d < dim; ++d)
      direction[d] = grid.make_field(0.);
  }

  template <int dim>
  double
  FrontWallExpulsion<dim>::bernoulli_speed(const double p_r) const
  {
    return p_r > 0 ? std::sqrt(2 * p_r / rho) : 0.;
  }

  template <int dim>
  double
  FrontWallExpulsion<dim>::film_thickness(const double T_s) const
  {
    double delta, v_d;
    piston.film(T_s, delta, v_d);
    return delta;
  }

  template <int dim>
  void
  FrontWallExpulsion<dim>::select(const std::vector<std::uint32_t> &fluid_cells,
                                  const std::vector<double>        &driven,
                                  const std::vector<double>        &type,
                                  const std::vector<double>        &p_surface,
                                  const std::vector<double>        &p_capillary,
                                  const std::vector<double>        &alpha,
                                  const std::vector<double>        &T)
  {
    const auto  &st = grid.strides();
    const auto  &n  = grid.n_cells();
    const double h  = grid.h();
    for (const auto c : expelling)
      {
        speed[c] = 0;
        for (int d = 0; d < dim; ++d)
          direction[d][c] = 0;
      }
    expelling.clear();
    fastest    = 0;
    auto metal = [&](const std::size_t c) {
      return type[c] == flow_cells::fluid || type[c] == flow_cells::solid;
    };
    for (const auto c : fluid_cells)
      {
        if (driven[c] == 0)
          continue;
        // Melt beyond the piston's film: the cell's own metal, alpha~ h, is
        // the least melt the grid holds under this surface.
        const double melt = std::clamp(alpha[c], 0., 1.) * h;
        if (!(film_thickness(T[c]) < melt))
          continue;
        const double u = bernoulli_speed(p_surface[c] - p_capillary[c]);
        if (!(u > 0))
          continue;
        // Normal from alpha~ (all neighbours of a fluid cell are near the
        // fluid), grad T from the metal neighbours (one-sided where only
        // one is metal; zero gradient at the box faces).
        const auto ijk = grid.global_index(c);
        double     na[dim], gT[dim], nn = 0;
        for (int d = 0; d < dim; ++d)
          {
            const bool has_m = ijk[d] > 0, has_p = ijk[d] < int(n[d]) - 1;
            const std::size_t cm = c - st[d], cp = c + st[d];
            const double      am = has_m ? alpha[cm] : alpha[c];
            const double      ap = has_p ? alpha[cp] : alpha[c];
            na[d]                = -(ap - am);
            nn += na[d] * na[d];
            const bool mm = has_m && metal(cm), mp = has_p && metal(cp);
            if (mm && mp)
              gT[d] = (T[cp] - T[cm]) / (2 * h);
            else if (mp)
              gT[d] = (T[cp] - T[c]) / h;
            else if (mm)
              gT[d] = (T[c] - T[cm]) / h;
            else
              gT[d] = 0;
          }
        if (!(nn > 0))
          continue;
        double ng = 0;
        for (int d = 0; d < dim; ++d)
          ng += na[d] * gT[d] / nn; // (n . grad T) / |na|, n = na/|na|
        double t[dim], tt = 0;
        for (int d = 0; d < dim; ++d)
          {
            t[d] = -(gT[d] - ng * na[d]);
            tt += t[d] * t[d];
          }
        // No surface gradient (the top of the hot spot): no direction.
        if (!(tt > 0))
          continue;
        tt       = 1. / std::sqrt(tt);
        speed[c] = u;
        for (int d = 0; d < dim; ++d)
          direction[d][c] = t[d] * tt;
        expelling.push_back(c);
        fastest = std::max(fastest, u);
      }
    grid.update_ghosts(speed);
    for (int d = 0; d < dim; ++d)
      grid.update_ghosts(direction[d]);
  }

  template <int dim>
  void
  FrontWallExpulsion<dim>::apply(const std::vector<std::uint32_t> &active,
                                 const std::vector<std::uint32_t> &active_cell,
                                 const std::vector<std::uint8_t>  &node_fix,
                                 std::array<std::vector<double>, dim> &u) const
  {
    const std::uint8_t all = (1u << dim) - 1;
    for (std::size_t a = 0; a < active.size(); ++a)
      {
        const std::size_t nd = active[a];
        if ((node_fix[nd] & all) == all)
          continue;
        // The fastest expelling cell among the node's cells.
        const std::size_t c0   = active_cell[a];
        std::size_t       best = 0;
        double            s    = 0;
        for (unsigned int j = 0; j < n_corners; ++j)
          {
            const std::size_t c = c0 - around_offset[j];
            if (speed[c] > s)
              s = speed[c], best = c;
          }
        if (!(s > 0))
          continue;
        double t[dim], tt = 0;
        for (int d = 0; d < dim; ++d)
          {
            t[d] = ((node_fix[nd] >> d) & 1) ? 0. : direction[d][best];
            tt += t[d] * t[d];
          }
        if (!(tt > 1e-12))
          continue;
        const double norm = std::sqrt(tt);
        double       ut   = 0;
        for (int d = 0; d < dim; ++d)
          ut += u[d][nd] * t[d] / norm;
        // The free part of the direction carries its share of the speed.
        const double target = s * norm;
        if (ut < target)
          for (int d = 0; d < dim; ++d)
            u[d][nd] += (target - ut) * t[d] / norm;
      }
  }

  template class FrontWallExpulsion<2>;
  template class FrontWallExpulsion<3>;
} // namespace femp
