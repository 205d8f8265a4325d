// femp: what the modules of the melt flow (IncompressibleFlow, FreeSurface,
// PressureSolver) share: the cell classes of the flow, the index offsets of
// a cell's corners and neighbours in the flat cell and node arrays of the
// local box, and the optional timer section.
#ifndef femp_flow_cells_h
#define femp_flow_cells_h

#include <deal.II/base/timer.h>

#include <femp/grid/background_grid.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <optional>
#include <vector>

namespace femp
{
  namespace flow_cells
  {
    /// Cell classes of the flow, stored as double in a cell field.
    enum Type : int
    {
      gas     = 0, ///< no metal point: free surface beyond, p = 0
      solid   = 1, ///< metal points but none fluid: rigid, no-slip
      fluid   = 2, ///< at least one fluid point: pressure unknown
      outside = 3  ///< beyond the domain: free-slip wall
    };

    /// Offsets of the 2^dim corner nodes of a cell from its first node
    /// (@p nodes true, node strides) or of the 2^dim cells round a node
    /// from the cell above it (@p nodes false, cell strides): bit d of the
    /// corner number is its position along direction d.
    template <int dim>
    inline std::array<std::ptrdiff_t, (1u << dim)>
    corner_offsets(const BackgroundGrid<dim> &grid, const bool nodes)
    {
      const auto &s = nodes ? grid.node_strides() : grid.strides();
      std::array<std::ptrdiff_t, (1u << dim)> offset;
      for (unsigned int c = 0; c < (1u << dim); ++c)
        {
          offset[c] = 0;
          for (int d = 0; d < dim; ++d)
            if ((c >> d) & 1)
              offset[c] += s[d];
        }
      return offset;
    }

    /// Offsets of the 3^dim cells around a cell (itself included).
    template <int dim>
    inline std::vector<std::ptrdiff_t>
    neighbourhood(const BackgroundGrid<dim> &grid)
    {
      const auto                 &cs = grid.strides();
      std::vector<std::ptrdiff_t> stencil;
      for (unsigned int k = 0; k < std::pow(3, dim); ++k)
        {
          std::ptrdiff_t o = 0;
          unsigned int   r = k;
          for (int d = 0; d < dim; ++d, r /= 3)
            o += (int(r % 3) - 1) * cs[d];
          stencil.push_back(o);
        }
      return stencil;
    }

    /// A section of the flow's timer, when a timer is given.
    struct Section
    {
      Section(dealii::TimerOutput *t, const char *name)
      {
        if (t)
          scope.emplace(*t, name);
      }
      std::optional<dealii::TimerOutput::Scope> scope;
    };
  } // namespace flow_cells
} // namespace femp

#endif
