// femp: the bodies of metal of alpha (see the header): the detached drops
// (a search over the cells with few metal neighbours, K rounds through the
// ghost layer) and the workpiece (a flood fill over the face-connected
// metal cells, alpha > 0, from the bottom row of the domain, distributed
// over the ranks through the ghost layer), and the peak temperatures of the
// attached and the detached metal.
#include <deal.II/base/mpi.h>

#include <femp/grid/metal_bodies.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

namespace femp
{
  template <int dim>
  MetalBodies<dim>::MetalBodies(const BackgroundGrid<dim> &grid,
                                const unsigned int         max_drop_cells)
      : grid(grid)
      , max_drop_cells(max_drop_cells)
  {
  }

  template <int dim>
  void
  MetalBodies<dim>::update(const std::vector<double> &a)
  {
    alpha             = a;
    workpiece_current = false;
    find_detached_drops();
  }

  template <int dim>
  std::vector<std::uint32_t>
  MetalBodies<dim>::detached_cells() const
  {
    std::vector<std::uint32_t> c;
    c.reserve(drops.size());
    for (const auto &d : drops)
      c.push_back(d.index);
    return c;
  }

  template <int dim>
  const std::vector<std::uint8_t> &
  MetalBodies<dim>::workpiece_cells()
  {
    if (!workpiece_current)
      {
        workpiece         = attached_metal_cells(grid, alpha);
        workpiece_current = true;
      }
    return workpiece;
  }

  template <int dim>
  MetalPeakTemperatures
  MetalBodies<dim>::peak_temperatures(const std::vector<double> &T)
  {
    return metal_peak_temperatures(grid, T, alpha, workpiece_cells());
  }

  template <int dim>
  void
  MetalBodies<dim>::find_detached_drops()
  {
    drops.clear();
    if (max_drop_cells == 0)
      return;
    const unsigned int K         = max_drop_cells;
    const auto        &st        = grid.strides();
    const auto        &n         = grid.n_cells();
    const double       h         = grid.h();
    const auto         global_id = [&](const std::size_t idx) {
      const auto ijk = grid.global_index(idx);
      double     id  = 0;
      for (int d = dim - 1; d >= 0; --d)
        id = id * n[d] + ijk[d];
      return id;
    };
    // Visit the metal face neighbours inside the domain of local cell idx
    // (global index ijk).
    const auto for_metal_neighbours_at =
      [&](const std::size_t idx, const auto &ijk, auto &&f) {
        for (int d = 0; d < dim; ++d)
          {
            if (ijk[d] > 0 && alpha[idx - st[d]] > 0)
              f(idx - st[d]);
            if (ijk[d] < int(n[d]) - 1 && alpha[idx + st[d]] > 0)
              f(idx + st[d]);
          }
      };
    const auto for_metal_neighbours = [&](const std::size_t idx, auto &&f) {
      for_metal_neighbours_at(idx, grid.global_index(idx), f);
    };
    // Metal face neighbours per owned metal cell, to the ghost layer.
    if (neighbour_count.size() != alpha.size())
      neighbour_count.assign(alpha.size(), 0.);
    std::vector<double>       &count = neighbour_count; // zero here
    std::vector<std::uint32_t> active;
    grid.for_each_owned_cell([&](const std::size_t idx, const auto &ijk) {
      if (alpha[idx] <= 0)
        return;
      unsigned int m = 0;
      for_metal_neighbours_at(idx, ijk, [&](std::size_t) { ++m; });
      count[idx] = m;
      if (m < K)
        active.push_back(idx);
    });
    if (Utilities::MPI::sum(active.size(), grid.communicator()) == 0)
      {
        std::fill(count.begin(), count.end(), 0.);
        return;
      }
    grid.update_ghosts(count);
    if (drop_sets.size() != K + 1 || drop_sets[0].size() != alpha.size())
      drop_sets.assign(K + 1, std::vector<double>(alpha.size(), 0.));
    std::vector<double> &size = drop_sets[K];
    for (const auto idx : active)
      size[idx] = 1, drop_sets[0][idx] = global_id(idx);
    std::vector<double> set;
    for (unsigned int round = 0; round < K; ++round)
      {
        for (auto &field : drop_sets)
          grid.update_ghosts(field);
        for (const auto idx : active)
          {
            if (size[idx] > K)
              continue; // a larger body
            set.clear();
            for (unsigned int k = 0; k < size[idx]; ++k)
              set.push_back(drop_sets[k][idx]);
            bool larger = false;
            for_metal_neighbours(idx, [&](const std::size_t nb) {
              larger = larger || count[nb] >= K || size[nb] > K;
            });
            if (!larger)
              {
                for_metal_neighbours(idx, [&](const std::size_t nb) {
                  for (unsigned int k = 0; k < size[nb]; ++k)
                    set.push_back(drop_sets[k][nb]);
                });
                std::sort(set.begin(), set.end());
                set.erase(std::unique(set.begin(), set.end()), set.end());
              }
            if (larger || set.size() > K)
              {
                size[idx] = K + 1;
                continue;
              }
            for (unsigned int k = 0; k < set.size(); ++k)
              drop_sets[k][idx] = set[k];
            size[idx] = set.size();
          }
        // Cells of larger bodies keep their mark (K + 1) for the
        // neighbours; only the others go on.
        active.erase(std::remove_if(active.begin(),
                                    active.end(),
                                    [&](const std::uint32_t idx) {
                                      return size[idx] > K;
                                    }),
                     active.end());
        if (Utilities::MPI::sum(active.size(), grid.communicator()) == 0)
          break;
      }
    // What is left are the drops' cells. Their metal fractions, from all
    // ranks (drops are few).
    std::vector<double> mine; // global index, alpha, ...
    for (const auto idx : active)
      mine.insert(mine.end(), {global_id(idx), alpha[idx]});
    std::map<double, double> alpha_of;
    for (const auto &part :
         Utilities::MPI::all_gather(grid.communicator(), mine))
      for (std::size_t i = 0; i + 1 < part.size(); i += 2)
        alpha_of[part[i]] = part[i + 1];
    for (const auto idx : active)
      {
        double a = 0;
        for (unsigned int k = 0; k < size[idx]; ++k)
          a += alpha_of.at(drop_sets[k][idx]);
        const double V = a * std::pow(h, dim);
        const double d =
          dim == 3 ? std::cbrt(6 * V / M_PI) : std::sqrt(4 * V / M_PI);
        drops.push_back({idx, V, d});
      }
    std::fill(count.begin(), count.end(), 0.);
  }

  template <int dim>
  std::vector<double>
  label_metal_bodies(const BackgroundGrid<dim> &grid,
                     const std::vector<double> &alpha,
                     const std::vector<double> &seeds,
                     unsigned int              *sweeps)
  {
    using Grid         = BackgroundGrid<dim>;
    const auto &st     = grid.strides();
    const auto &status = grid.cell_status();
    const auto  metal  = [&](const std::size_t i) { return alpha[i] > 0; };

    // label: the least seed label that reached the cell so far (0: none);
    // a double field for the ghost exchange. Labels only fall, so a cell
    // whose label changed passes it on.
    std::vector<double>        label = grid.make_field(0.);
    std::vector<std::uint32_t> stack;
    const auto visit = [&](const std::size_t i, const double lab) {
      if (status[i] == Grid::owned && metal(i) &&
          (label[i] == 0 || lab < label[i]))
        {
          label[i] = lab;
          stack.push_back(i);
        }
    };
    for (const auto idx : grid.owned_cells())
      if (seeds[idx] > 0)
        visit(idx, seeds[idx]);

    // Owned cells always have a neighbour entry (ghost or padding) in the
    // box, so idx +- stride stays inside it.
    std::vector<double> before;
    unsigned int        n_sweeps = 0;
    for (;;)
      {
        while (!stack.empty())
          {
            const std::size_t idx = stack.back();
            stack.pop_back();
            const double lab = label[idx];
            for (int d = 0; d < dim; ++d)
              {
                visit(idx + st[d], lab);
                visit(idx - st[d], lab);
              }
          }
        ++n_sweeps;
        before = label;
        grid.update_ghosts(label);
        // Ghost cells whose label changed pass it to their owned
        // neighbours.
        for (std::size_t i = 0; i < label.size(); ++i)
          if (status[i] == Grid::ghost && label[i] != before[i])
            {
              const auto ijk = grid.global_index(i);
              for (int d = 0; d < dim; ++d)
                for (const int s : {-1, 1})
                  {
                    auto nb = ijk;
                    nb[d] += s;
                    if (grid.in_box(nb))
                      visit(grid.local_index(nb), label[i]);
                  }
            }
        const unsigned long long n_new = stack.size();
        if (Utilities::MPI::sum(n_new, grid.communicator()) == 0)
          break;
      }
    if (sweeps)
      *sweeps = n_sweeps;
    for (std::size_t i = 0; i < label.size(); ++i)
      if (status[i] != Grid::owned)
        label[i] = 0;
    return label;
  }

  template <int dim>
  std::vector<std::uint8_t>
  attached_metal_cells(const BackgroundGrid<dim> &grid,
                       const std::vector<double> &alpha,
                       unsigned int              *sweeps)
  {
    // One label, 1, from the metal cells of the bottom row: a flood fill.
    std::vector<double> seeds = grid.make_field(0.);
    for (const auto idx : grid.owned_cells())
      if (grid.global_index(idx)[dim - 1] == 0)
        seeds[idx] = 1;
    const std::vector<double> label =
      label_metal_bodies(grid, alpha, seeds, sweeps);
    std::vector<std::uint8_t> attached(label.size(), 0);
    for (const auto idx : grid.owned_cells())
      attached[idx] = label[idx] != 0;
    return attached;
  }

  template <int dim>
  MetalPeakTemperatures
  metal_peak_temperatures(const BackgroundGrid<dim>       &grid,
                          const std::vector<double>       &T,
                          const std::vector<double>       &alpha,
                          const std::vector<std::uint8_t> &attached)
  {
    const double lowest   = std::numeric_limits<double>::lowest();
    double       local[2] = {lowest, lowest}; // attached, detached
    for (const auto idx : grid.owned_cells())
      if (alpha[idx] > 0)
        {
          double &m = local[attached[idx] ? 0 : 1];
          m         = std::max(m, T[idx]);
        }
    double global[2];
    Utilities::MPI::max(ArrayView<const double>(local, 2),
                        grid.communicator(),
                        ArrayView<double>(global, 2));
    MetalPeakTemperatures p;
    if (global[0] > lowest)
      p.attached = global[0];
    if (global[1] > lowest)
      p.detached = global[1];
    return p;
  }

  template <int dim>
  MetalPeakTemperatures
  metal_peak_temperatures(const BackgroundGrid<dim> &grid,
                          const std::vector<double> &T,
                          const std::vector<double> &alpha)
  {
    return metal_peak_temperatures(grid,
                                   T,
                                   alpha,
                                   attached_metal_cells(grid, alpha));
  }

  template class MetalBodies<2>;
  template class MetalBodies<3>;
  template std::vector<std::uint8_t>
  attached_metal_cells(const BackgroundGrid<2> &,
                       const std::vector<double> &,
                       unsigned int *);
  template std::vector<std::uint8_t>
  attached_metal_cells(const BackgroundGrid<3> &,
                       const std::vector<double> &,
                       unsigned int *);
  template std::vector<double>
  label_metal_bodies(const BackgroundGrid<2> &,
                     const std::vector<double> &,
                     const std::vector<double> &,
                     unsigned int *);
  template std::vector<double>
  label_metal_bodies(const BackgroundGrid<3> &,
                     const std::vector<double> &,
                     const std::vector<double> &,
                     unsigned int *);
#define FEMP_INSTANTIATE(D)                               \
  template MetalPeakTemperatures metal_peak_temperatures( \
    const BackgroundGrid<D> &,                            \
    const std::vector<double> &,                          \
    const std::vector<double> &);                         \
  template MetalPeakTemperatures metal_peak_temperatures( \
    const BackgroundGrid<D> &,                            \
    const std::vector<double> &,                          \
    const std::vector<double> &,                          \
    const std::vector<std::uint8_t> &);
  FEMP_INSTANTIATE(2)
  FEMP_INSTANTIATE(3)
#undef FEMP_INSTANTIATE
} // namespace femp
