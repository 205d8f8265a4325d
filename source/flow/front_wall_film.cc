// femp: sub-cell wall condition for the recoil-driven melt film on a solid
// wall (Melt flow/Front wall film; doc/flow.md, "Front wall film"; the
// melt expulsion of Semak and Matsunawa, J. Phys. D 30 (1997) 2541). The
// film nodes, where the melt between a solid cell and a recoil-driven
// surface cell is less than one cell thick, keep only the wall-normal
// component of the no-slip condition.
#include <femp/flow/flow_cells.h>
#include <femp/flow/front_wall_film.h>

#include <cmath>

namespace femp
{
  template <int dim>
  FrontWallFilm<dim>::FrontWallFilm(const BackgroundGrid<dim> &grid)
      : around_offset(flow_cells::corner_offsets(grid, false))
      , film_flag(grid.n_local_nodes(), 0)
  {
  }

  template <int dim>
  void
  FrontWallFilm<dim>::clear()
  {
    for (const auto n : film_node)
      film_flag[n] = 0;
    film_node.clear();
    film_normal.clear();
    wall_node.clear();
    wall_cell.clear();
    wall_fix.clear();
  }

  template <int dim>
  void
  FrontWallFilm<dim>::select(const std::vector<double> &type,
                             const std::vector<double> &driven,
                             std::vector<std::uint8_t> &node_fix)
  {
    for (std::size_t w = 0; w < wall_node.size(); ++w)
      {
        const std::size_t c0      = wall_cell[w];
        bool              drive   = false;
        double            nw[dim] = {};
        for (unsigned int j = 0; j < n_corners; ++j)
          {
            const std::size_t c = c0 - around_offset[j];
            drive = drive || (type[c] == flow_cells::fluid && driven[c] != 0);
            // From the centre of a solid cell to the node: +1/2 h along d
            // where the cell lies below the node (bit d of j), else -1/2 h.
            if (type[c] == flow_cells::solid)
              for (int d = 0; d < dim; ++d)
                nw[d] += ((j >> d) & 1) ? 1. : -1.;
          }
        if (!drive)
          continue;
        double norm = 0;
        for (int d = 0; d < dim; ++d)
          {
            if ((wall_fix[w] >> d) & 1)
              nw[d] = 0;
            norm += nw[d] * nw[d];
          }
        // Solid cells on opposite sides (a slot narrower than a cell): no
        // wall direction, the node stays fixed.
        if (norm < 0.5)
          continue;
        const std::uint32_t n = wall_node[w];
        node_fix[n]           = wall_fix[w];
        film_flag[n]          = 1;
        film_node.push_back(n);
        norm = 1. / std::sqrt(norm);
        for (int d = 0; d < dim; ++d)
          film_normal.push_back(nw[d] * norm);
      }
  }

  template <int dim>
  void
  FrontWallFilm<dim>::project(std::array<std::vector<double>, dim> &u) const
  {
    for (std::size_t f = 0; f < film_node.size(); ++f)
      {
        const std::size_t n  = film_node[f];
        const double     *nw = &film_normal[dim * f];
        double            un = 0;
        for (int d = 0; d < dim; ++d)
          un += u[d][n] * nw[d];
        for (int d = 0; d < dim; ++d)
          u[d][n] -= un * nw[d];
      }
  }

  template class FrontWallFilm<2>;
  template class FrontWallFilm<3>;
} // namespace femp
