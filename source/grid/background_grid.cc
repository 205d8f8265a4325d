// femp: the background grid (paper sec. 2.1, eq. 2): triangulation, local
// flat index box and ghost exchange. See include/femp/grid/background_grid.h.
#include <deal.II/base/mpi.h>
#include <deal.II/grid/grid_generator.h>

#include <femp/base/input_checks.h>
#include <femp/base/parameter_table.h>
#include <femp/grid/background_grid.h>

#include <algorithm>
#include <limits>
#include <map>
#include <set>

namespace femp
{
  template <int dim>
  void
  BackgroundGrid<dim>::Parameters::add_parameters(ParameterTable &table)
  {
    ParameterHandler &prm = table.handler();
    table.enter_subsection("Background grid");
    if (table.declaring())
      prm.declare_entry(
        "Lower corner",
        "0, 0, 0",
        Patterns::List(Patterns::Double(), 1, 3),
        "Lower corner of the domain box, in m. A comma-separated "
        "list of 1..3 coordinates; the first dim are used.");
    if (table.declaring())
      prm.declare_entry("Upper corner",
                        "1e-3, 4e-4, 2e-4",
                        Patterns::List(Patterns::Double(), 1, 3),
                        "Upper corner of the domain box, in m. Each extent "
                        "(upper - lower) must be positive and an integer "
                        "multiple of the cell size.");
    table.add("Cell size",
              cell_size,
              Patterns::Double(0.),
              "Edge length h of the cubic background cells, in m; "
              "range (0, domain extent]. The same grid carries "
              "temperature, pressure and nodal velocities.");
    table.add("Partition",
              partition_by_cost,
              {{true, "cost"}, {false, "cells"}},
              "How the grid is split over the MPI ranks. 'cost': "
              "pieces of equal expected work, from the scene's "
              "geometry at the start (a cell counts 1, each material "
              "point expected in it 2, and each point the solid "
              "steps by MPM 40 more: the solid's point loops "
              "dominate a coupled run). 'cells': pieces of equal "
              "numbers of cells. Results agree to round-off; only "
              "the time differs. One rank: no effect.");
    table.leave_subsection();
  }

  template <int dim>
  void
  BackgroundGrid<dim>::Parameters::declare_parameters(ParameterHandler &prm)
  {
    Parameters     defaults;
    ParameterTable table(prm, ParameterTable::Mode::declare);
    defaults.add_parameters(table);
  }

  template <int dim>
  void
  BackgroundGrid<dim>::Parameters::parse_parameters(ParameterHandler &prm)
  {
    ParameterTable table(prm, ParameterTable::Mode::parse);
    add_parameters(table);
    prm.enter_subsection("Background grid");
    lower_corner =
      parse_point<dim>(prm.get("Lower corner"), "Background grid/Lower corner");
    upper_corner =
      parse_point<dim>(prm.get("Upper corner"), "Background grid/Upper corner");
    prm.leave_subsection();

    require(cell_size > 0,
            "Background grid/Cell size",
            cell_size,
            "it must be positive (m)");
    for (int d = 0; d < dim; ++d)
      {
        const double extent = upper_corner[d] - lower_corner[d];
        require(extent > 0,
                "Background grid/Upper corner",
                upper_corner,
                "every coordinate must exceed that of 'Lower corner'");
        const double n = extent / cell_size;
        require(std::abs(n - std::round(n)) < 1e-6 * std::max(1., n) &&
                  std::round(n) >= 1,
                "Background grid/Cell size",
                cell_size,
                "it must divide the domain extent " + num(extent) +
                  " m in direction " + std::to_string(d) +
                  " into a whole number of cells (extent / h = " + num(n) +
                  ")");
      }
  }

  template <int dim>
  BackgroundGrid<dim>::BackgroundGrid(const Parameters &parameters,
                                      MPI_Comm          comm)
      : prm(parameters)
      , comm(comm)
      , tria(comm)
      , inv_h(1. / parameters.cell_size)
  {
  }

  template <int dim>
  std::uint64_t
  BackgroundGrid<dim>::n_global_cells() const
  {
    std::uint64_t n = 1;
    for (int d = 0; d < dim; ++d)
      n *= n_global[d];
    return n;
  }

  template <int dim>
  void
  BackgroundGrid<dim>::create(
    const std::function<unsigned int(const Point<dim> &)> &cell_cost)
  {
    create_triangulation(cell_cost);
    KnownCells known;
    set_local_box(known);
    set_ghost_pattern(known);
    set_node_pattern(known);
  }

  template <int dim>
  void
  BackgroundGrid<dim>::create_triangulation(
    const std::function<unsigned int(const Point<dim> &)> &cell_cost)
  {
    for (int d = 0; d < dim; ++d)
      n_global[d] = static_cast<unsigned int>(std::round(
        (prm.upper_corner[d] - prm.lower_corner[d]) / prm.cell_size));

    // Coarse blocks of 2^r cells per direction, refined r times globally:
    // p4est then handles few trees (deal.II's coarse-cell reordering costs
    // ~50 us per tree). Where a cell count is not a multiple of 2^r, the
    // triangulation (not the domain) is padded on the upper side; padding
    // cells lie outside the domain and are never used or written. Pick the
    // largest r <= 3 whose padding adds at most 10 % cells.
    unsigned int                  r      = 0;
    std::array<unsigned int, dim> n_tria = n_global;
    for (unsigned int level = 3; level > 0; --level)
      {
        const unsigned int            b      = 1u << level;
        double                        padded = 1, exact = 1;
        std::array<unsigned int, dim> n_try;
        for (int d = 0; d < dim; ++d)
          {
            n_try[d] = (n_global[d] + b - 1) / b * b;
            padded *= n_try[d];
            exact *= n_global[d];
          }
        if (padded <= 1.1 * exact)
          {
            r      = level;
            n_tria = n_try;
            break;
          }
      }
    std::vector<unsigned int> repetitions(dim);
    Point<dim>                tria_upper = prm.lower_corner;
    for (int d = 0; d < dim; ++d)
      {
        repetitions[d] = n_tria[d] >> r;
        tria_upper[d] += n_tria[d] * prm.cell_size;
      }
    GridGenerator::subdivided_hyper_rectangle(tria,
                                              repetitions,
                                              prm.lower_corner,
                                              tria_upper);
    if (r > 0)
      tria.refine_global(r);

    // p4est splits its space-filling order of the cells into pieces of
    // equal count; with a cost per cell it splits into pieces of equal
    // cost instead (the same on every rank: a function of the geometry
    // only, so a resumed run gets the same partition).
    if (cell_cost && prm.partition_by_cost &&
        Utilities::MPI::n_mpi_processes(comm) > 1)
      {
        using Tria      = parallel::distributed::Triangulation<dim>;
        auto connection = tria.signals.weight.connect(
          [&](const typename Tria::cell_iterator &cell,
              const typename Tria::CellStatus) {
            return std::max(1u, cell_cost(cell->center()));
          });
        tria.repartition();
        connection.disconnect();
      }
  }

  template <int dim>
  void
  BackgroundGrid<dim>::set_local_box(KnownCells &known)
  {
    // Structured index of each owned and ghost cell, and the local box.
    std::array<int, dim> box_min, box_max;
    box_min.fill(std::numeric_limits<int>::max());
    box_max.fill(std::numeric_limits<int>::min());
    for (const auto &cell : tria.active_cell_iterators())
      if (!cell->is_artificial() && in_domain(cell->center()))
        {
          const auto ijk = cell_of(cell->center());
          known.emplace_back(ijk, cell);
          for (int d = 0; d < dim; ++d)
            {
              box_min[d] = std::min(box_min[d], ijk[d]);
              box_max[d] = std::max(box_max[d], ijk[d]);
            }
        }
    std::size_t n_box = 1;
    for (int d = 0; d < dim; ++d)
      {
        if (known.empty())
          box_min[d] = box_max[d] = 0;
        lo[d]     = box_min[d] - 1; // one padding layer on each side
        size[d]   = box_max[d] - box_min[d] + 3;
        stride[d] = (d == 0 ? 1 : stride[d - 1] * size[d - 1]);
        n_box *= size[d];
      }
    AssertThrow(n_box < std::numeric_limits<std::uint32_t>::max(),
                ExcMessage("Local grid box too large for 32-bit indices."));

    status.assign(n_box, outside);
    cells_of_flat.assign(n_box, {});
    flat_of_active.assign(tria.n_active_cells(), numbers::invalid_unsigned_int);
    owned_list.clear();
    for (const auto &[ijk, cell] : known)
      {
        const std::size_t idx = local_index(ijk);
        status[idx]           = cell->is_locally_owned() ? owned : ghost;
        cells_of_flat[idx]    = cell;
        flat_of_active[cell->active_cell_index()] = idx;
        if (cell->is_locally_owned())
          owned_list.push_back(idx);
      }
    std::sort(owned_list.begin(), owned_list.end());
  }

  template <int dim>
  void
  BackgroundGrid<dim>::set_ghost_pattern(const KnownCells &known)
  {
    // Ghost pattern: tell each owner which of its cells we hold as ghosts.
    auto global_linear = [this](const std::array<int, dim> &ijk) {
      std::uint64_t g = 0, m = 1;
      for (int d = 0; d < dim; ++d)
        {
          g += m * ijk[d];
          m *= n_global[d];
        }
      return g;
    };
    std::map<unsigned int, std::vector<std::uint64_t>> requests;
    std::map<unsigned int, std::vector<std::uint32_t>> recv_map;
    {
      std::vector<std::pair<std::uint64_t, std::size_t>> ghosts;
      for (const auto &[ijk, cell] : known)
        if (cell->is_ghost())
          ghosts.emplace_back(global_linear(ijk), local_index(ijk));
      std::sort(ghosts.begin(), ghosts.end());
      for (const auto &[g, idx] : ghosts)
        {
          const unsigned int owner = cell_iterator(idx)->subdomain_id();
          requests[owner].push_back(g);
          recv_map[owner].push_back(idx);
        }
    }
    const auto incoming = Utilities::MPI::some_to_some(comm, requests);

    std::set<int> ranks;
    for (const auto &r : recv_map)
      ranks.insert(r.first);
    for (const auto &r : incoming)
      ranks.insert(r.first);
    neighbours.assign(ranks.begin(), ranks.end());
    send_indices.assign(neighbours.size(), {});
    recv_indices.assign(neighbours.size(), {});
    for (std::size_t n = 0; n < neighbours.size(); ++n)
      {
        const auto in = incoming.find(neighbours[n]);
        if (in != incoming.end())
          for (const std::uint64_t g : in->second)
            {
              std::array<int, dim> ijk;
              std::uint64_t        rest = g;
              for (int d = 0; d < dim; ++d)
                {
                  ijk[d] = rest % n_global[d];
                  rest /= n_global[d];
                }
              AssertThrow(in_box(ijk) && status[local_index(ijk)] == owned,
                          ExcInternalError());
              send_indices[n].push_back(local_index(ijk));
            }
        const auto rv = recv_map.find(neighbours[n]);
        if (rv != recv_map.end())
          recv_indices[n] = rv->second;
      }
    send_buffers.resize(neighbours.size());
    recv_buffers.resize(neighbours.size());
  }

  template <int dim>
  void
  BackgroundGrid<dim>::set_node_pattern(const KnownCells &known)
  {
    // Nodes: layout, the nodes of owned cells, and per neighbour rank the
    // nodes shared with its owned cells (= nodes of owned cells that are
    // also nodes of a ghost cell it owns).
    n_nodes_box = 1;
    for (int d = 0; d < dim; ++d)
      {
        node_stride[d] = (d == 0 ? 1 : node_stride[d - 1] * (size[d - 1] + 1));
        n_nodes_box *= size[d] + 1;
      }
    const unsigned int n_corners = 1u << dim;
    auto corner = [&](const std::array<int, dim> &cell, const unsigned int c) {
      std::array<int, dim> node = cell;
      for (int d = 0; d < dim; ++d)
        node[d] += (c >> d) & 1;
      return node;
    };
    std::vector<char> of_owned(n_nodes_box, 0);
    for (const auto idx : owned_list)
      for (unsigned int c = 0; c < n_corners; ++c)
        of_owned[local_node_index(corner(global_index(idx), c))] = 1;
    active_nodes.clear();
    for (std::size_t i = 0; i < n_nodes_box; ++i)
      if (of_owned[i])
        active_nodes.push_back(i);
    std::map<int, std::set<std::uint32_t>> shared;
    for (const auto &[ijk, cell] : known)
      if (cell->is_ghost())
        for (unsigned int c = 0; c < n_corners; ++c)
          {
            const auto node = local_node_index(corner(ijk, c));
            if (of_owned[node])
              shared[cell->subdomain_id()].insert(node);
          }
    node_neighbours.clear();
    shared_nodes.clear();
    for (auto &[rank, nodes] : shared)
      {
        node_neighbours.push_back(rank);
        // Local flat order equals global lexicographic order inside a box
        // only per rank; sort by global node index to agree with the peer.
        std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed;
        for (const auto node : nodes)
          {
            std::size_t          rest = node;
            std::uint64_t        g = 0, m = 1;
            std::array<int, dim> ijk;
            for (int d = dim - 1; d >= 0; --d)
              {
                ijk[d] = lo[d] + static_cast<int>(rest / node_stride[d]);
                rest %= node_stride[d];
              }
            for (int d = 0; d < dim; ++d)
              {
                g += m * ijk[d];
                m *= n_global[d] + 1;
              }
            keyed.emplace_back(g, node);
          }
        std::sort(keyed.begin(), keyed.end());
        shared_nodes.emplace_back();
        for (const auto &k : keyed)
          shared_nodes.back().push_back(k.second);
      }
    node_send.resize(node_neighbours.size());
    node_recv.resize(node_neighbours.size());
  }

  template <int dim>
  void
  BackgroundGrid<dim>::sum_shared_nodes(std::vector<double> &field) const
  {
    if (node_neighbours.empty())
      return;
    std::vector<MPI_Request> requests(2 * node_neighbours.size());
    const int                tag = 4712;
    for (std::size_t n = 0; n < node_neighbours.size(); ++n)
      {
        node_recv[n].resize(shared_nodes[n].size());
        MPI_Irecv(node_recv[n].data(),
                  node_recv[n].size(),
                  MPI_DOUBLE,
                  node_neighbours[n],
                  tag,
                  comm,
                  &requests[2 * n]);
        node_send[n].resize(shared_nodes[n].size());
        for (std::size_t i = 0; i < shared_nodes[n].size(); ++i)
          node_send[n][i] = field[shared_nodes[n][i]];
        MPI_Isend(node_send[n].data(),
                  node_send[n].size(),
                  MPI_DOUBLE,
                  node_neighbours[n],
                  tag,
                  comm,
                  &requests[2 * n + 1]);
      }
    MPI_Waitall(requests.size(), requests.data(), MPI_STATUSES_IGNORE);
    for (std::size_t n = 0; n < node_neighbours.size(); ++n)
      for (std::size_t i = 0; i < shared_nodes[n].size(); ++i)
        field[shared_nodes[n][i]] += node_recv[n][i];
  }

  template <int dim>
  void
  BackgroundGrid<dim>::update_ghosts(std::vector<double> &field) const
  {
    if (neighbours.empty())
      return;
    std::vector<MPI_Request> requests;
    requests.reserve(2 * neighbours.size());
    const int tag = 4711;
    for (std::size_t n = 0; n < neighbours.size(); ++n)
      if (!recv_indices[n].empty())
        {
          recv_buffers[n].resize(recv_indices[n].size());
          requests.emplace_back();
          MPI_Irecv(recv_buffers[n].data(),
                    recv_buffers[n].size(),
                    MPI_DOUBLE,
                    neighbours[n],
                    tag,
                    comm,
                    &requests.back());
        }
    for (std::size_t n = 0; n < neighbours.size(); ++n)
      if (!send_indices[n].empty())
        {
          auto &buf = send_buffers[n];
          buf.resize(send_indices[n].size());
          for (std::size_t i = 0; i < buf.size(); ++i)
            buf[i] = field[send_indices[n][i]];
          requests.emplace_back();
          MPI_Isend(buf.data(),
                    buf.size(),
                    MPI_DOUBLE,
                    neighbours[n],
                    tag,
                    comm,
                    &requests.back());
        }
    MPI_Waitall(requests.size(), requests.data(), MPI_STATUSES_IGNORE);
    for (std::size_t n = 0; n < neighbours.size(); ++n)
      for (std::size_t i = 0; i < recv_indices[n].size(); ++i)
        field[recv_indices[n][i]] = recv_buffers[n][i];
  }

  template class BackgroundGrid<2>;
  template class BackgroundGrid<3>;
} // namespace femp
