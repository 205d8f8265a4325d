// femp: the background grid (paper sec. 2.1, eq. 2).
//
// One structured Cartesian grid of cubic cells of size h covers the whole
// domain. deal.II owns it as a parallel::distributed::Triangulation (one
// coarse cell per grid cell, or coarse blocks refined globally when the cell
// counts allow it) that p4est partitions over MPI ranks. For the hot loops,
// each rank also keeps its cells in flat arrays over a local index box
// (owned cells, the ghost layer, and one padding layer), addressed by
// structured index arithmetic: cell (i,j,k) sits at
//   (i - lo_0) + s_1 (j - lo_1) + s_2 (k - lo_2),
// and the cell that contains x is i_d = floor((x_d - x0_d) / h) (eq. 2).
// update_ghosts() copies owned values into the ghost layers of neighbours.
#ifndef femp_background_grid_h
#define femp_background_grid_h

#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/point.h>
#include <deal.II/distributed/tria.h>

#include <femp/base/parameter_table.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

namespace femp
{
  using namespace dealii;

  template <int dim>
  class BackgroundGrid
  {
  public:
    struct Parameters
    {
      Point<dim> lower_corner;
      Point<dim> upper_corner;
      double     cell_size = 8e-6; ///< as declared ("Cell size")
      /// "Partition": balance the cells' costs (true, 'cost') or their
      /// number (false, 'cells') over the ranks.
      bool partition_by_cost = true;

      /// Declare (the members' values are the defaults) or read the

      /// entries, each listed once.

      void

      add_parameters(ParameterTable &table);

      static void
      declare_parameters(ParameterHandler &prm);
      void
      parse_parameters(ParameterHandler &prm);
    };

    /// Status of an entry of the local box.
    enum CellStatus : std::uint8_t
    {
      outside = 0, ///< padding: outside the domain or not known to this rank
      owned   = 1,
      ghost   = 2
    };

    BackgroundGrid(const Parameters &parameters, MPI_Comm comm);

    /// Build the triangulation, the local index box and the ghost pattern.
    /// @p cell_cost, if given, returns the relative cost (>= 1) of the cell
    /// centred at a point; with several ranks p4est then balances the sum of
    /// the costs instead of the number of cells (doc/performance.md,
    /// "Balancing the ranks").
    void
    create(
      const std::function<unsigned int(const Point<dim> &)> &cell_cost = {});

    const parallel::distributed::Triangulation<dim> &
    triangulation() const
    {
      return tria;
    }
    parallel::distributed::Triangulation<dim> &
    triangulation()
    {
      return tria;
    }
    MPI_Comm
    communicator() const
    {
      return comm;
    }

    // ---- structured layout -------------------------------------------
    double
    h() const
    {
      return prm.cell_size;
    }
    const Point<dim> &
    origin() const
    {
      return prm.lower_corner;
    }
    /// Global number of cells per direction.
    const std::array<unsigned int, dim> &
    n_cells() const
    {
      return n_global;
    }
    std::uint64_t
    n_global_cells() const;

    /// Number of entries of the local box (including padding).
    std::size_t
    n_local() const
    {
      return status.size();
    }
    /// Flat-index stride per direction (stride[0] == 1).
    const std::array<std::ptrdiff_t, dim> &
    strides() const
    {
      return stride;
    }
    /// First global index of the local box per direction (may be -1).
    const std::array<int, dim> &
    box_lower() const
    {
      return lo;
    }
    const std::array<int, dim> &
    box_size() const
    {
      return size;
    }

    /// Flat local index of global cell index @p ijk (must be in the box).
    std::size_t
    local_index(const std::array<int, dim> &ijk) const
    {
      std::size_t idx = 0;
      for (int d = 0; d < dim; ++d)
        idx += (ijk[d] - lo[d]) * stride[d];
      return idx;
    }
    /// Global structured index of local flat index @p idx.
    std::array<int, dim>
    global_index(std::size_t idx) const
    {
      std::array<int, dim> ijk;
      for (int d = dim - 1; d >= 0; --d)
        {
          ijk[d] = lo[d] + static_cast<int>(idx / stride[d]);
          idx %= stride[d];
        }
      return ijk;
    }
    /// Global structured index of the cell containing @p x (eq. 2), clamped
    /// to the domain.
    std::array<int, dim>
    cell_of(const Point<dim> &x) const
    {
      std::array<int, dim> ijk;
      for (int d = 0; d < dim; ++d)
        {
          const int i =
            static_cast<int>(std::floor((x[d] - prm.lower_corner[d]) * inv_h));
          ijk[d] = std::min(std::max(i, 0), int(n_global[d]) - 1);
        }
      return ijk;
    }
    /// True if @p x lies inside the domain box (not in the padding of the
    /// triangulation).
    bool
    in_domain(const Point<dim> &x) const
    {
      for (int d = 0; d < dim; ++d)
        if ((x[d] - prm.lower_corner[d]) * inv_h >= n_global[d] ||
            x[d] < prm.lower_corner[d])
          return false;
      return true;
    }
    /// True if global index @p ijk lies inside the local box.
    bool
    in_box(const std::array<int, dim> &ijk) const
    {
      for (int d = 0; d < dim; ++d)
        if (ijk[d] < lo[d] || ijk[d] >= lo[d] + size[d])
          return false;
      return true;
    }
    /// Centre of the cell at local flat index @p idx.
    Point<dim>
    cell_center(const std::size_t idx) const
    {
      const auto ijk = global_index(idx);
      Point<dim> c;
      for (int d = 0; d < dim; ++d)
        c[d] = prm.lower_corner[d] + (ijk[d] + 0.5) * prm.cell_size;
      return c;
    }

    const std::vector<std::uint8_t> &
    cell_status() const
    {
      return status;
    }
    /// Local flat indices of the locally owned cells, in increasing order.
    const std::vector<std::uint32_t> &
    owned_cells() const
    {
      return owned_list;
    }
    /// Call @p f(idx, ijk) for each locally owned cell, in increasing flat
    /// index idx, with its global structured index ijk: the same cells as
    /// owned_cells(), without the divisions of global_index() (for passes
    /// over the whole grid).
    template <typename Function>
    void
    for_each_owned_cell(Function &&f) const
    {
      std::array<int, dim> ijk = lo;
      for (std::size_t idx = 0; idx < status.size(); ++idx)
        {
          if (status[idx] == owned)
            f(idx, static_cast<const std::array<int, dim> &>(ijk));
          for (int d = 0; d < dim; ++d)
            {
              if (++ijk[d] < lo[d] + size[d])
                break;
              ijk[d] = lo[d];
            }
        }
    }
    /// Local flat index of every active cell of the triangulation, by
    /// active_cell_index(); numbers::invalid_unsigned_int for artificial ones.
    const std::vector<std::uint32_t> &
    flat_index_of_active_cell() const
    {
      return flat_of_active;
    }
    /// Iterator of the triangulation cell at local flat index @p idx (owned
    /// or ghost).
    const typename Triangulation<dim>::active_cell_iterator &
    cell_iterator(const std::size_t idx) const
    {
      return cells_of_flat[idx];
    }

    /// Copy owned values into the ghost layers of all ranks.
    void
    update_ghosts(std::vector<double> &field) const;

    // ---- grid nodes ----------------------------------------------------
    // Node (i,j,k) is the corner x0 + (i,j,k) h; nodes of the local box are
    // those of its cells, (size_d + 1) per direction, stored with the same
    // lower index lo_d as the cells.

    /// Number of node entries of the local box.
    std::size_t
    n_local_nodes() const
    {
      return n_nodes_box;
    }
    /// Flat-index stride per direction for node arrays.
    const std::array<std::ptrdiff_t, dim> &
    node_strides() const
    {
      return node_stride;
    }
    /// Flat local index of global node index @p ijk.
    std::size_t
    local_node_index(const std::array<int, dim> &ijk) const
    {
      std::size_t idx = 0;
      for (int d = 0; d < dim; ++d)
        idx += (ijk[d] - lo[d]) * node_stride[d];
      return idx;
    }
    /// Flat node index of the lower (0,0,0) corner of cell at flat @p cell.
    std::size_t
    first_node_of_cell(const std::size_t cell) const
    {
      return local_node_index(global_index(cell));
    }
    /// Flat local node indices of the nodes of locally owned cells.
    const std::vector<std::uint32_t> &
    owned_cell_nodes() const
    {
      return active_nodes;
    }
    /// Sum node values over all ranks that share a node (nodes of owned
    /// cells): after the call, every rank holds the global sum on each node
    /// of its owned cells. Use after scattering particle data to nodes.
    void
    sum_shared_nodes(std::vector<double> &field) const;
    /// A new node field over the local box.
    std::vector<double>
    make_node_field(const double value = 0.) const
    {
      return std::vector<double>(n_nodes_box, value);
    }

    /// A new field over the local box, initialized to @p value.
    std::vector<double>
    make_field(const double value = 0.) const
    {
      return std::vector<double>(n_local(), value);
    }

  private:
    Parameters                                prm;
    MPI_Comm                                  comm;
    parallel::distributed::Triangulation<dim> tria;
    double                                    inv_h;
    std::array<unsigned int, dim>             n_global;
    std::array<int, dim>                      lo, size;
    std::array<std::ptrdiff_t, dim>           stride;
    std::vector<std::uint8_t>                 status;
    std::vector<std::uint32_t>                owned_list;
    std::vector<std::uint32_t>                flat_of_active;
    std::vector<typename Triangulation<dim>::active_cell_iterator>
      cells_of_flat;

    // Ghost exchange pattern: per neighbour rank, the local flat indices we
    // send (owned cells that are ghosts there) and receive (our ghosts that
    // it owns), both in increasing global lexicographic order.
    std::vector<int>                         neighbours;
    std::vector<std::vector<std::uint32_t>>  send_indices, recv_indices;
    mutable std::vector<std::vector<double>> send_buffers, recv_buffers;

    // Nodes: layout and the shared-node pattern (same node list on both
    // sides, in increasing global node order).
    std::size_t                              n_nodes_box = 0;
    std::array<std::ptrdiff_t, dim>          node_stride;
    std::vector<std::uint32_t>               active_nodes;
    std::vector<int>                         node_neighbours;
    std::vector<std::vector<std::uint32_t>>  shared_nodes;
    mutable std::vector<std::vector<double>> node_send, node_recv;

    /// The owned and ghost cells of the triangulation in the domain, with
    /// their structured index.
    using KnownCells =
      std::vector<std::pair<std::array<int, dim>,
                            typename Triangulation<dim>::active_cell_iterator>>;
    /// The parts of create(): the p4est triangulation (coarse blocks
    /// refined globally), partitioned by @p cell_cost if given; the local box,
    /// the cell status and the owned cells (fills @p known); the ghost exchange
    /// pattern; the node layout and the shared-node pattern.
    void
    create_triangulation(
      const std::function<unsigned int(const Point<dim> &)> &cell_cost);
    void
    set_local_box(KnownCells &known);
    void
    set_ghost_pattern(const KnownCells &known);
    void
    set_node_pattern(const KnownCells &known);
  };

  /// Tent (multilinear) weights of the 2^dim corners of cell @p ijk for a
  /// point at @p x, each times @p scale: corner k has bit d set for the
  /// upper node in direction d (the order of first_node_of_cell() plus the
  /// corner offsets). @p x0 is the grid origin and @p ih = 1/h.
  template <int dim, typename PointType>
  inline void
  tent_weights(const PointType            &x,
               const PointType            &x0,
               const double                ih,
               const std::array<int, dim> &ijk,
               const double                scale,
               double (&w)[1u << dim])
  {
    w[0] = scale;
    for (int d = 0; d < dim; ++d)
      {
        const double       xi   = (x[d] - x0[d]) * ih - ijk[d];
        const unsigned int half = 1u << d;
        for (unsigned int k = 0; k < half; ++k)
          {
            w[k + half] = w[k] * xi;
            w[k] *= 1. - xi;
          }
      }
  }
} // namespace femp

#endif
