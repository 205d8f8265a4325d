// femp: the metal attached to the substrate (see the header): a flood fill
// over the cells with alpha > 1/2 from the bottom row of the domain,
// distributed over the ranks through the ghost layer.
#include <deal.II/base/mpi.h>

#include <femp/heat/attached_metal.h>

#include <algorithm>
#include <limits>

namespace femp
{
  template <int dim>
  std::vector<std::uint8_t>
  attached_metal_cells(const BackgroundGrid<dim> &grid,
                       const std::vector<double> &alpha,
                       unsigned int              *sweeps)
  {
    using Grid         = BackgroundGrid<dim>;
    const auto &st     = grid.strides();
    const auto &status = grid.cell_status();
    const auto  metal  = [&](const std::size_t i) { return alpha[i] > 0.5; };

    // label: 1 for attached cells (alpha > 1/2); a double field for the
    // ghost exchange.
    std::vector<double>        label = grid.make_field(0.);
    std::vector<std::uint32_t> stack;
    const auto                 visit = [&](const std::size_t i) {
      if (status[i] == Grid::owned && label[i] == 0 && metal(i))
        {
          label[i] = 1;
          stack.push_back(i);
        }
    };
    for (const auto idx : grid.owned_cells())
      if (grid.global_index(idx)[dim - 1] == 0)
        visit(idx);

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
            for (int d = 0; d < dim; ++d)
              {
                visit(idx + st[d]);
                visit(idx - st[d]);
              }
          }
        ++n_sweeps;
        before = label;
        grid.update_ghosts(label);
        // Ghost cells that became attached seed their owned neighbours.
        for (std::size_t i = 0; i < label.size(); ++i)
          if (status[i] == Grid::ghost && label[i] != 0 && before[i] == 0)
            {
              const auto ijk = grid.global_index(i);
              for (int d = 0; d < dim; ++d)
                for (const int s : {-1, 1})
                  {
                    auto nb = ijk;
                    nb[d] += s;
                    if (grid.in_box(nb))
                      visit(grid.local_index(nb));
                  }
            }
        const unsigned long long n_new = stack.size();
        if (Utilities::MPI::sum(n_new, grid.communicator()) == 0)
          break;
      }
    if (sweeps)
      *sweeps = n_sweeps;

    // Counted: attached, or partly filled next to an attached cell (the
    // labels of the ghosts are current after the last exchange).
    std::vector<std::uint8_t> counted(label.size(), 0);
    for (const auto idx : grid.owned_cells())
      {
        bool c = label[idx] != 0;
        if (!c && alpha[idx] > 0)
          for (int d = 0; d < dim && !c; ++d)
            c = label[idx + st[d]] != 0 || label[idx - st[d]] != 0;
        counted[idx] = c;
      }
    return counted;
  }

  template <int dim>
  double
  attached_metal_max_temperature(const BackgroundGrid<dim> &grid,
                                 const std::vector<double> &T,
                                 const std::vector<double> &alpha)
  {
    const auto   counted  = attached_metal_cells(grid, alpha);
    const double lowest   = std::numeric_limits<double>::lowest();
    double       local[2] = {lowest, lowest}; // counted, all metal
    for (const auto idx : grid.owned_cells())
      if (alpha[idx] > 0)
        {
          local[1] = std::max(local[1], T[idx]);
          if (counted[idx])
            local[0] = std::max(local[0], T[idx]);
        }
    double global[2];
    Utilities::MPI::max(ArrayView<const double>(local, 2),
                        grid.communicator(),
                        ArrayView<double>(global, 2));
    return global[0] > lowest ? global[0] : global[1];
  }

  template std::vector<std::uint8_t>
  attached_metal_cells(const BackgroundGrid<2> &,
                       const std::vector<double> &,
                       unsigned int *);
  template std::vector<std::uint8_t>
  attached_metal_cells(const BackgroundGrid<3> &,
                       const std::vector<double> &,
                       unsigned int *);
  template double
  attached_metal_max_temperature(const BackgroundGrid<2> &,
                                 const std::vector<double> &,
                                 const std::vector<double> &);
  template double
  attached_metal_max_temperature(const BackgroundGrid<3> &,
                                 const std::vector<double> &,
                                 const std::vector<double> &);
} // namespace femp
