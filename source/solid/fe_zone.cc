// femp: the finite-element zone as a set of grid cells, a mask over its
// bounding box (see fe_zone.h).
#include <femp/solid/fe_zone.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace femp
{
  template <int dim>
  FeZone<dim>::FeZone(const bool        enabled,
                      const Point<dim> &lower_corner,
                      const Point<dim> &upper_corner,
                      const Point<dim> &origin,
                      const double      h)
      : on(enabled)
      , x0(origin)
      , h(h)
      , ih(1. / h)
  {
    if (!on)
      return;
    std::size_t n_all = 1;
    for (int d = 0; d < dim; ++d)
      {
        lo[d] = static_cast<int>(std::round((lower_corner[d] - origin[d]) / h));
        n[d] =
          static_cast<int>(std::round((upper_corner[d] - lower_corner[d]) / h));
        n_all *= std::max(n[d], 0);
      }
    in.assign(n_all, 1);
  }

  template <int dim>
  FeZone<dim>::FeZone(const std::array<int, dim>      &first_cell,
                      const std::array<int, dim>      &n_cells,
                      const std::vector<std::uint8_t> &mask,
                      const Point<dim>                &origin,
                      const double                     h)
      : lo(first_cell)
      , n(n_cells)
      , in(mask)
      , x0(origin)
      , h(h)
      , ih(1. / h)
  {
    on = std::any_of(in.begin(), in.end(), [](const auto c) { return c; });
  }

  template <int dim>
  bool
  FeZone<dim>::contains(const Point<dim> &x) const
  {
    std::array<int, dim> ijk;
    for (int d = 0; d < dim; ++d)
      ijk[d] = static_cast<int>(std::floor((x[d] - x0[d]) * ih));
    return contains_cell(ijk);
  }

  template <int dim>
  bool
  FeZone<dim>::is_box() const
  {
    return std::all_of(in.begin(), in.end(), [](const auto c) { return c; });
  }

  template <int dim>
  std::size_t
  FeZone<dim>::n_zone_cells() const
  {
    return std::count_if(in.begin(), in.end(), [](const auto c) {
      return c != 0;
    });
  }

  template <int dim>
  Point<dim>
  FeZone<dim>::lower_corner() const
  {
    Point<dim> p;
    for (int d = 0; d < dim; ++d)
      p[d] = x0[d] + lo[d] * h;
    return p;
  }

  template <int dim>
  Point<dim>
  FeZone<dim>::upper_corner() const
  {
    Point<dim> p;
    for (int d = 0; d < dim; ++d)
      p[d] = x0[d] + (lo[d] + n[d]) * h;
    return p;
  }

  template <int dim>
  FeZone<dim>
  FeZone<dim>::with_cells(const std::vector<std::array<int, dim>> &cells) const
  {
    std::array<int, dim> a, b; // new box [a, b)
    for (int d = 0; d < dim; ++d)
      {
        a[d] = on ? lo[d] : std::numeric_limits<int>::max();
        b[d] = on ? lo[d] + n[d] : std::numeric_limits<int>::min();
      }
    for (const auto &c : cells)
      for (int d = 0; d < dim; ++d)
        a[d] = std::min(a[d], c[d]), b[d] = std::max(b[d], c[d] + 1);
    if (!on && cells.empty())
      return *this;
    std::array<int, dim> m;
    std::size_t          n_all = 1;
    for (int d = 0; d < dim; ++d)
      m[d] = b[d] - a[d], n_all *= m[d];
    std::vector<std::uint8_t> mask(n_all, 0);
    auto                      index = [&](const std::array<int, dim> &c) {
      std::size_t k = 0;
      for (int d = dim - 1; d >= 0; --d)
        k = k * m[d] + (c[d] - a[d]);
      return k;
    };
    if (on)
      for (std::size_t k = 0; k < in.size(); ++k)
        if (in[k])
          {
            std::array<int, dim> c;
            std::size_t          r = k;
            for (int d = 0; d < dim; ++d)
              c[d] = lo[d] + int(r % n[d]), r /= n[d];
            mask[index(c)] = 1;
          }
    for (const auto &c : cells)
      mask[index(c)] = 1;
    return FeZone<dim>(a, m, mask, x0, h);
  }

  template class FeZone<2>;
  template class FeZone<3>;
} // namespace femp
