// femp: sub-cell wall condition for the melt film that the recoil pressure
// drives along a solid wall (Melt flow/Front wall film; doc/flow.md, "Front
// wall film").
//
// On the front wall of a vapour depression the recoil pressure pushes the
// melt out of the beam's spot (Semak and Matsunawa, J. Phys. D 30 (1997)
// 2541); the melt leaves through a film of a few micrometres, thinner than
// a cell. femp's fluid step fixes the velocity of every node of a solid
// cell to zero (no slip), so a film inside one cell carries at most the
// velocity of its gas-side nodes, interpolated linearly to zero one cell
// away. With this condition, on the nodes where the melt between a solid
// cell and a recoil-driven surface is less than one cell thick ("film
// nodes"), only the component normal to the wall is fixed (slip), and the
// Darcy damping is not applied: the film is liquid (its surface boils) and
// its velocity profile is a plug across the film, set by the pressure drop
// along it, not by a no-slip node a cell away. The film nodes are the
// active nodes that are a corner of a solid cell and of a recoil-driven
// surface cell (FreeSurface::mark_recoil_driven()); the wall normal of a
// film node is the sum of the vectors from the centres of its solid cells
// to the node, with the directions fixed by the domain boundary removed.
#ifndef femp_front_wall_film_h
#define femp_front_wall_film_h

#include <femp/grid/background_grid.h>

#include <array>
#include <cstdint>
#include <vector>

namespace femp
{
  using namespace dealii;

  template <int dim>
  class FrontWallFilm
  {
  public:
    explicit FrontWallFilm(const BackgroundGrid<dim> &grid);

    /// Forget the wall nodes and film nodes of the last step.
    void
    clear();
    /// A node of the local box that is a corner of a solid cell: @p node,
    /// the cell above it (node ijk = cell ijk), and the directions fixed by
    /// the domain boundary (bit d).
    void
    add_wall_node(const std::uint32_t node,
                  const std::uint32_t cell_above,
                  const std::uint8_t  domain_fix)
    {
      wall_node.push_back(node);
      wall_cell.push_back(cell_above);
      wall_fix.push_back(domain_fix);
    }
    /// From the wall nodes, select the film nodes: those that are a corner
    /// of a cell with @p driven != 0 (cell field, ghosts exchanged); for
    /// them, node_fix becomes the domain-boundary bits and the wall normal
    /// is stored. @p type: the flow's cell classes (ghosts exchanged).
    void
    select(const std::vector<double> &type,
           const std::vector<double> &driven,
           std::vector<std::uint8_t> &node_fix);
    /// Remove the wall-normal component of @p u on the film nodes.
    void
    project(std::array<std::vector<double>, dim> &u) const;
    /// Whether node @p n is a film node of this step.
    bool
    is_film(const std::size_t n) const
    {
      return film_flag[n] != 0;
    }
    /// Film nodes of this step on this rank.
    std::size_t
    size() const
    {
      return film_node.size();
    }

  private:
    static constexpr unsigned int         n_corners = 1u << dim;
    std::array<std::ptrdiff_t, n_corners> around_offset; // cells round a node

    std::vector<std::uint32_t> wall_node, wall_cell;
    std::vector<std::uint8_t>  wall_fix;
    std::vector<std::uint32_t> film_node;
    std::vector<double>        film_normal; // dim per film node, unit
    std::vector<std::uint8_t>  film_flag;   // per local node
  };
} // namespace femp

#endif
