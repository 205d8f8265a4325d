// femp: SolidActiveRegion<dim>, which grid nodes and cells a solid step of
// this rank visits (doc/performance.md, "Solid steps visit only the nodes
// that carry mass"). Fixed at setup: the active nodes (of owned cells
// outside the FE zone, and the transition nodes among the nodes of owned
// cells), the owned cells outside and inside the FE zone, and the nodes
// whose point kinetic energy this rank counts (each node on one rank: the
// owner of the cell with the node as lower corner, clamped at the upper
// domain faces). Changing with the points: the live nodes and cells, the
// part of the above that a step visits: the corners of the cells that held
// points since the last gather (SolidMPM::nodes_reached()), the transition
// nodes and the nodes shared with another rank (ascending, so that sums
// keep their order), and the cells that held points since the last gather
// and the probe cells (the cells whose temperature a step interpolates).
// All node fields are zero at the other active nodes. No equation of the
// paper: bookkeeping of where eqs. 11-17 have work to do.
#ifndef femp_solid_active_region_h
#define femp_solid_active_region_h

#include <deal.II/base/point.h>

#include <femp/grid/background_grid.h>

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

namespace femp
{
  using namespace dealii;

  template <int dim>
  class SolidActiveRegion
  {
  public:
    explicit SolidActiveRegion(const BackgroundGrid<dim> &grid);

    /// The fixed sets (collective), from the FE-zone mask @p zone (local
    /// cells), the transition nodes among the nodes of this rank's owned
    /// cells @p transition (transition index, local node), and the probe
    /// points @p probes; no live node or cell yet.
    void
    setup(
      const std::vector<std::uint8_t>                            &zone,
      const std::vector<std::pair<std::uint32_t, std::uint32_t>> &transition,
      const std::vector<Point<dim>>                              &probes,
      const MPI_Comm                                              comm);

    /// The live nodes and cells anew (after a gather) from the corners
    /// @p reached_nodes and cells @p reached_cells that held points since
    /// it: @p node_left(n) for each node that stops being live (the caller
    /// zeroes its fields), @p cell_added(c) for each fixed or reached cell.
    template <typename NodeLeft, typename CellAdded>
    void
    rebuild(const std::vector<std::uint32_t> &reached_nodes,
            const std::vector<std::uint32_t> &reached_cells,
            NodeLeft                        &&node_left,
            CellAdded                       &&cell_added);
    /// After a step: the entries of @p reached_nodes and @p reached_cells
    /// added since the last rebuild() or extend() become live;
    /// @p cell_added(c) for each cell that becomes live.
    template <typename CellAdded>
    void
    extend(const std::vector<std::uint32_t> &reached_nodes,
           const std::vector<std::uint32_t> &reached_cells,
           CellAdded                       &&cell_added);

    /// Owned cells outside the FE zone (the only cells whose temperature
    /// the points need; none: no gather of the points at all).
    const std::vector<std::uint32_t> &
    mpm_cells() const
    {
      return mpm;
    }
    /// Owned cells inside the FE zone (the solidus guard).
    const std::vector<std::uint32_t> &
    fe_cells() const
    {
      return fe;
    }
    /// Whether any rank has a cell of the FE zone.
    bool
    guard_fe_zone() const
    {
      return guard;
    }
    /// Live nodes, ascending.
    const std::vector<std::uint32_t> &
    live_nodes() const
    {
      return live_node_list;
    }
    /// Live cells.
    const std::vector<std::uint32_t> &
    live_cells() const
    {
      return live_cell_list;
    }
    /// Whether cell @p c is live.
    bool
    is_live_cell(const std::uint32_t c) const
    {
      return cell_live[c];
    }
    /// The live nodes that this rank counts, with their transition index
    /// or -1, in the order of live_nodes().
    const std::vector<std::pair<std::uint32_t, std::int32_t>> &
    live_counted() const
    {
      return live_counted_list;
    }
    /// Transition index of node @p n if this rank counts it, -1 for a
    /// counted node that is not one, -2 if not counted.
    std::int32_t
    counted_as(const std::uint32_t n) const
    {
      return counted_as_index[n];
    }

  private:
    const BackgroundGrid<dim> &grid;
    /// Nodes of this rank's owned cells outside the FE zone plus the
    /// transition nodes among its owned-cell nodes: the only grid nodes a
    /// solid step touches.
    std::vector<std::uint32_t> active_nodes;
    std::vector<std::uint32_t> mpm, fe;
    bool                       guard = false;
    /// The nodes this rank counts, with their transition index or -1.
    std::vector<std::pair<std::uint32_t, std::int32_t>> counted_nodes;
    std::vector<std::uint32_t> live_node_list, live_cell_list;
    std::vector<std::pair<std::uint32_t, std::int32_t>> live_counted_list;
    std::vector<std::uint8_t>                           node_live, cell_live;
    std::vector<std::uint32_t> fixed_live_nodes, fixed_live_cells;
    std::vector<std::int32_t>  counted_as_index;
    /// Entries of the reached nodes and cells already live.
    std::size_t nodes_seen = 0, cells_seen = 0;
  };

  template <int dim>
  template <typename NodeLeft, typename CellAdded>
  void
  SolidActiveRegion<dim>::rebuild(
    const std::vector<std::uint32_t> &reached_nodes,
    const std::vector<std::uint32_t> &reached_cells,
    NodeLeft                        &&node_left,
    CellAdded                       &&cell_added)
  {
    std::vector<std::uint32_t> old;
    old.swap(live_node_list);
    for (const auto n : old)
      node_live[n] = 0;
    auto add = [&](const std::uint32_t n) {
      if (!node_live[n])
        node_live[n] = 1, live_node_list.push_back(n);
    };
    for (const auto n : fixed_live_nodes)
      add(n);
    for (const auto n : reached_nodes)
      add(n);
    nodes_seen = reached_nodes.size();
    std::sort(live_node_list.begin(), live_node_list.end());
    // Nodes that leave: zero, as the next step's update would leave them.
    for (const auto n : old)
      if (!node_live[n])
        node_left(n);
    live_counted_list.clear();
    for (const auto n : live_node_list)
      if (counted_as_index[n] > -2)
        live_counted_list.emplace_back(n, counted_as_index[n]);

    for (const auto c : live_cell_list)
      cell_live[c] = 0;
    live_cell_list.clear();
    auto add_cell = [&](const std::uint32_t c) {
      if (!cell_live[c])
        cell_live[c] = 1, live_cell_list.push_back(c);
      cell_added(c);
    };
    for (const auto c : fixed_live_cells)
      add_cell(c);
    for (const auto c : reached_cells)
      add_cell(c);
    cells_seen = reached_cells.size();
  }

  template <int dim>
  template <typename CellAdded>
  void
  SolidActiveRegion<dim>::extend(
    const std::vector<std::uint32_t> &reached_nodes,
    const std::vector<std::uint32_t> &reached_cells,
    CellAdded                       &&cell_added)
  {
    if (reached_nodes.size() > nodes_seen)
      {
        const std::size_t n0 = live_node_list.size(),
                          c0 = live_counted_list.size();
        for (std::size_t i = nodes_seen; i < reached_nodes.size(); ++i)
          {
            const auto n = reached_nodes[i];
            if (node_live[n])
              continue;
            node_live[n] = 1;
            live_node_list.push_back(n);
            if (counted_as_index[n] > -2)
              live_counted_list.emplace_back(n, counted_as_index[n]);
          }
        nodes_seen = reached_nodes.size();
        std::sort(live_node_list.begin() + n0, live_node_list.end());
        std::inplace_merge(live_node_list.begin(),
                           live_node_list.begin() + n0,
                           live_node_list.end());
        std::sort(live_counted_list.begin() + c0, live_counted_list.end());
        std::inplace_merge(live_counted_list.begin(),
                           live_counted_list.begin() + c0,
                           live_counted_list.end());
      }
    for (std::size_t i = cells_seen; i < reached_cells.size(); ++i)
      {
        const auto c = reached_cells[i];
        if (!cell_live[c])
          {
            cell_live[c] = 1, live_cell_list.push_back(c);
            cell_added(c);
          }
      }
    cells_seen = reached_cells.size();
  }
} // namespace femp

#endif
