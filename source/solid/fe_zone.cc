// femp: the finite-element zone as a box of grid cells (see fe_zone.h).
#include <femp/solid/fe_zone.h>

#include <cmath>

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
      , ih(1. / h)
  {
    if (!on)
      return;
    for (int d = 0; d < dim; ++d)
      {
        lo[d] = static_cast<int>(std::round((lower_corner[d] - origin[d]) / h));
        n[d] =
          static_cast<int>(std::round((upper_corner[d] - lower_corner[d]) / h));
      }
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

  template class FeZone<2>;
  template class FeZone<3>;
} // namespace femp
