// femp: the grid nodes and cells that the solid steps of a rank visit (see
// solid_active_region.h).
#include <deal.II/base/mpi.h>

#include <femp/solid/solid_active_region.h>

namespace femp
{
  template <int dim>
  SolidActiveRegion<dim>::SolidActiveRegion(const BackgroundGrid<dim> &grid)
      : grid(grid)
  {
  }

  template <int dim>
  void
  SolidActiveRegion<dim>::setup(
    const std::vector<std::uint8_t>                            &zone,
    const std::vector<std::pair<std::uint32_t, std::uint32_t>> &transition,
    const std::vector<Point<dim>>                              &probes,
    const MPI_Comm                                              comm)
  {
    const auto &ns = grid.node_strides();
    const auto &lo = grid.box_lower();
    // Grid nodes a step touches: nodes of owned cells outside the FE zone,
    // and the transition nodes among the nodes of owned cells.
    std::vector<std::uint8_t> active(grid.n_local_nodes(), 0);
    for (const auto c : grid.owned_cells())
      if (!zone[c])
        {
          const std::size_t n0 = grid.first_node_of_cell(c);
          for (unsigned int a = 0; a < (1u << dim); ++a)
            {
              std::size_t n = n0;
              for (int d = 0; d < dim; ++d)
                if (a & (1u << d))
                  n += ns[d];
              active[n] = 1;
            }
        }
    mpm.clear();
    fe.clear();
    for (const auto c : grid.owned_cells())
      (zone[c] ? fe : mpm).push_back(c);
    guard = Utilities::MPI::max(int(!fe.empty()), comm) > 0;
    for (const auto &[t, n] : transition)
      active[n] = 1;
    active_nodes.clear();
    for (std::size_t n = 0; n < active.size(); ++n)
      if (active[n])
        active_nodes.push_back(n);

    // Nodes whose point kinetic energy this rank counts (see the header).
    std::vector<std::int32_t> tr_of(grid.n_local_nodes(), -1);
    for (const auto &[t, n] : transition)
      tr_of[n] = t;
    // Global grid index of the local node n (the node box starts at lo).
    const auto node_ijk = [&](std::size_t r) {
      std::array<int, dim> ijk;
      for (int d = dim - 1; d >= 0; --d)
        {
          ijk[d] = lo[d] + static_cast<int>(r / ns[d]);
          r %= ns[d];
        }
      return ijk;
    };
    counted_nodes.clear();
    for (const auto n : active_nodes)
      {
        // The cell named for the node (the last cell for nodes on a top
        // face).
        std::array<int, dim> ijk = node_ijk(n);
        for (int d = 0; d < dim; ++d)
          ijk[d] = std::min(ijk[d], int(grid.n_cells()[d]) - 1);
        if (grid.in_box(ijk) && grid.cell_status()[grid.local_index(ijk)] ==
                                  BackgroundGrid<dim>::owned)
          counted_nodes.emplace_back(n, tr_of[n]);
      }
    counted_as_index.assign(grid.n_local_nodes(), -2);
    for (const auto &[n, t] : counted_nodes)
      counted_as_index[n] = t;

    // Always live: the transition nodes, the nodes that another rank's
    // cells share (sum_shared_nodes() writes them) and the probe cells.
    fixed_live_nodes.clear();
    for (const auto &[t, n] : transition)
      fixed_live_nodes.push_back(n);
    for (const auto n : active_nodes)
      {
        const std::array<int, dim> ijk    = node_ijk(n);
        bool                       shared = false;
        for (unsigned int a = 0; a < (1u << dim) && !shared; ++a)
          {
            std::array<int, dim> c  = ijk;
            bool                 in = true;
            for (int d = 0; d < dim; ++d)
              {
                c[d] -= (a >> d) & 1u;
                in = in && c[d] >= 0 && c[d] < int(grid.n_cells()[d]);
              }
            shared = in && (!grid.in_box(c) ||
                            grid.cell_status()[grid.local_index(c)] !=
                              BackgroundGrid<dim>::owned);
          }
        if (shared)
          fixed_live_nodes.push_back(n);
      }
    fixed_live_cells.clear();
    for (const auto &x : probes)
      {
        const auto ijk = grid.cell_of(x);
        if (!grid.in_box(ijk))
          continue;
        const auto c = grid.local_index(ijk);
        if (grid.cell_status()[c] == BackgroundGrid<dim>::owned && !zone[c])
          fixed_live_cells.push_back(c);
      }
    node_live.assign(grid.n_local_nodes(), 0);
    cell_live.assign(grid.n_local(), 0);
    live_node_list.clear();
    live_cell_list.clear();
    live_counted_list.clear();
  }

  template class SolidActiveRegion<2>;
  template class SolidActiveRegion<3>;
} // namespace femp
