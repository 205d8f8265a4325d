// femp: FeZone<dim>, the one answer to "is this background cell in the
// finite-element zone" (doc/method.md, "Solid": the zone where the solid
// is meshed with finite elements, eqs. 6-10, instead of material points).
// The zone is a box of whole grid cells: its corners ('Solid FEM/Zone lower
// corner', 'Zone upper corner') lie on cell faces (SolidFEM::Parameters::
// check()), so the box is a first cell index and a number of cells per
// direction. SolidFEM meshes it, FluidSolidForces gives its nodes full
// shares, and the partition cost of the grid counts no MPM work in it: all
// ask this object. No equation of the paper.
#ifndef femp_fe_zone_h
#define femp_fe_zone_h

#include <deal.II/base/point.h>

#include <array>

namespace femp
{
  using namespace dealii;

  template <int dim>
  class FeZone
  {
  public:
    /// No zone (every answer is no).
    FeZone() = default;
    /// The zone from @p lower_corner to @p upper_corner (m, on cell faces
    /// of the grid with origin @p origin and cell size @p h, m), or no zone
    /// when @p enabled is false.
    FeZone(const bool        enabled,
           const Point<dim> &lower_corner,
           const Point<dim> &upper_corner,
           const Point<dim> &origin,
           const double      h);

    /// Whether there is a zone.
    bool
    enabled() const
    {
      return on;
    }
    /// Whether the cell with structured index @p ijk lies in the zone.
    bool
    contains_cell(const std::array<int, dim> &ijk) const
    {
      if (!on)
        return false;
      for (int d = 0; d < dim; ++d)
        if (ijk[d] < lo[d] || ijk[d] >= lo[d] + n[d])
          return false;
      return true;
    }
    /// Whether the cell that holds @p x (e.g. a cell centre) lies in the
    /// zone.
    bool
    contains(const Point<dim> &x) const;
    /// Structured index of the zone's first cell.
    const std::array<int, dim> &
    first_cell() const
    {
      return lo;
    }
    /// Cells of the zone per direction.
    const std::array<int, dim> &
    n_cells() const
    {
      return n;
    }

  private:
    bool                 on = false;
    std::array<int, dim> lo{}, n{};
    Point<dim>           x0;
    double               ih = 0;
  };
} // namespace femp

#endif
