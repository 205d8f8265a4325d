// Background grid layout: ghost exchange of cell fields and the sum of
// shared node values over ranks. Every owned cell adds 1 to each of its
// 2^dim nodes and writes its global lexicographic index into a cell field;
// after sum_shared_nodes() every node of an owned cell must hold the number
// of cells around it, and after update_ghosts() every ghost cell its own
// index, on any number of ranks.
#include "test_tools.h"

using namespace femp_test;

template <int dim>
void
check(Checks &checks, MPI_Comm comm)
{
  Point<dim> hi;
  for (int d = 0; d < dim; ++d)
    hi[d] = (d == 0 ? 13 : 7) * 0.5;
  BackgroundGrid<dim> grid(box<dim>(Point<dim>(), hi, 0.5), comm);
  grid.create();
  const auto &n      = grid.n_cells();
  auto        nodes  = grid.make_node_field();
  auto        cells  = grid.make_field(-1.);
  auto        linear = [&](const std::array<int, dim> &ijk) {
    double g = 0, m = 1;
    for (int d = 0; d < dim; ++d)
      g += m * ijk[d], m *= n[d];
    return g;
  };
  for (const auto idx : grid.owned_cells())
    {
      cells[idx] = linear(grid.global_index(idx));
      for (unsigned int c = 0; c < (1u << dim); ++c)
        {
          auto node = grid.global_index(idx);
          for (int d = 0; d < dim; ++d)
            node[d] += (c >> d) & 1;
          nodes[grid.local_node_index(node)] += 1;
        }
    }
  grid.sum_shared_nodes(nodes);
  grid.update_ghosts(cells);
  double node_errors = 0, ghost_errors = 0;
  for (const auto node : grid.owned_cell_nodes())
    {
      // Global node index from the flat one.
      std::size_t          rest = node;
      std::array<int, dim> ijk;
      for (int d = dim - 1; d >= 0; --d)
        {
          ijk[d] = grid.box_lower()[d] + int(rest / grid.node_strides()[d]);
          rest %= grid.node_strides()[d];
        }
      double expected = 1;
      for (int d = 0; d < dim; ++d)
        expected *= (ijk[d] == 0 || ijk[d] == int(n[d])) ? 1 : 2;
      node_errors += nodes[node] != expected;
    }
  for (std::size_t idx = 0; idx < grid.n_local(); ++idx)
    if (grid.cell_status()[idx] == BackgroundGrid<dim>::ghost)
      ghost_errors += cells[idx] != linear(grid.global_index(idx));
  checks.at_most(std::to_string(dim) + "D: wrong node sums",
                 Utilities::MPI::sum(node_errors, comm),
                 0);
  checks.at_most(std::to_string(dim) + "D: wrong ghost values",
                 Utilities::MPI::sum(ghost_errors, comm),
                 0);
}

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  Checks                           checks(MPI_COMM_WORLD);
  check<2>(checks, MPI_COMM_WORLD);
  check<3>(checks, MPI_COMM_WORLD);
  return checks.exit_code();
}
