// femp: FeZone<dim>, the one answer to "is this background cell in the
// finite-element zone" (doc/method.md, "Solid": the zone where the solid
// is meshed with finite elements, eqs. 6-10, instead of material points).
// The zone is a set of whole grid cells: a bounding box (a first cell index
// and a number of cells per direction) and a mask over the box's cells
// (lexicographic, x fastest; 1: the cell is in the zone), the same on every
// rank. The user's zone ('Solid FEM/Zone lower corner', 'Zone upper
// corner', on cell faces: SolidFEM::Parameters::check()) is a full box; a
// build's hand-over adds cells (with_cells()), so that the zone may hold
// islands of material-point cells (a pore, porous metal) and columns
// of different heights. SolidFEM meshes it and FluidSolidForces gives its
// nodes full shares, both asking this object. The partition cost of the
// grid (Scene::partition_cost()) asks contains_cell() of the user's box,
// or of a resumed checkpoint's zone: the grid is partitioned once per run,
// so the cells a hand-over adds keep the cost of MPM cells until then
// (doc/performance.md, "Balancing the ranks"). No equation of the paper.
#ifndef femp_fe_zone_h
#define femp_fe_zone_h

#include <deal.II/base/point.h>

#include <array>
#include <cstdint>
#include <vector>

namespace femp
{
  using namespace dealii;

  template <int dim>
  class FeZone
  {
  public:
    /// No zone (every answer is no).
    FeZone() = default;
    /// The full box from @p lower_corner to @p upper_corner (m, on cell
    /// faces of the grid with origin @p origin and cell size @p h, m), or
    /// no zone when @p enabled is false.
    FeZone(const bool        enabled,
           const Point<dim> &lower_corner,
           const Point<dim> &upper_corner,
           const Point<dim> &origin,
           const double      h);
    /// The cells of @p mask (over the box of @p n_cells cells from
    /// @p first_cell, lexicographic, x fastest; 1: in the zone) on the grid
    /// with origin @p origin and cell size @p h; the bounding box is taken
    /// as given (no zone when it holds no cell).
    FeZone(const std::array<int, dim>      &first_cell,
           const std::array<int, dim>      &n_cells,
           const std::vector<std::uint8_t> &mask,
           const Point<dim>                &origin,
           const double                     h);

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
      std::size_t k = 0;
      for (int d = dim - 1; d >= 0; --d)
        {
          if (ijk[d] < lo[d] || ijk[d] >= lo[d] + n[d])
            return false;
          k = k * n[d] + (ijk[d] - lo[d]);
        }
      return in[k] != 0;
    }
    /// Whether the cell that holds @p x (e.g. a cell centre) lies in the
    /// zone.
    bool
    contains(const Point<dim> &x) const;
    /// Structured index of the first cell of the zone's bounding box.
    const std::array<int, dim> &
    first_cell() const
    {
      return lo;
    }
    /// Cells of the zone's bounding box per direction.
    const std::array<int, dim> &
    n_cells() const
    {
      return n;
    }
    /// The mask over the bounding box (lexicographic, x fastest; 1: in the
    /// zone).
    const std::vector<std::uint8_t> &
    mask() const
    {
      return in;
    }
    /// Whether every cell of the bounding box is in the zone.
    bool
    is_box() const;
    /// Cells in the zone.
    std::size_t
    n_zone_cells() const;
    /// Corners of the bounding box, m.
    Point<dim>
    lower_corner() const;
    Point<dim>
    upper_corner() const;
    /// The zone with the cells @p cells (structured indices inside the
    /// grid) added: the bounding box grows to hold them.
    FeZone<dim>
    with_cells(const std::vector<std::array<int, dim>> &cells) const;

  private:
    bool                      on = false;
    std::array<int, dim>      lo{}, n{};
    std::vector<std::uint8_t> in;
    Point<dim>                x0;
    double                    h  = 0;
    double                    ih = 0;
  };
} // namespace femp

#endif
