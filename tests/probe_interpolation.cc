// Probe sampling of cell fields: with "cell" a probe returns the value of
// the cell that contains it; with "linear" the multilinear interpolation
// between cell centres, weighted by the metal fraction. A field linear in
// x, y (and z) must be reproduced exactly by "linear" anywhere between the
// first and the last cell centres (the cell value errs by up to half a cell
// times the gradient), and above a metal surface (alpha = 0 in the gas,
// where the field holds a huge value) the interpolated value must come from
// the metal cells only. Same on any number of ranks.
#include <femp/io/output.h>

#include "test_tools.h"

using namespace femp_test;

template <int dim>
void
check(Checks &checks, MPI_Comm comm)
{
  const double h = 0.5;
  Point<dim>   hi;
  for (int d = 0; d < dim; ++d)
    hi[d] = (d == 0 ? 12 : 6) * h;
  BackgroundGrid<dim> grid(box<dim>(Point<dim>(), hi, h), comm);
  grid.create();

  // T = 300 + 10 x + 20 y (+ 30 z) at the cell centres; alpha = 1 below the
  // surface z (or y in 2D) = 2 (four cell rows), 0 above, where T = 1e9.
  const double surface = 4 * h;
  auto         exact   = [](const Point<dim> &x) {
    double T = 300;
    for (int d = 0; d < dim; ++d)
      T += 10 * (d + 1) * x[d];
    return T;
  };
  auto T     = grid.make_field(0.);
  auto alpha = grid.make_field(0.);
  for (const auto idx : grid.owned_cells())
    {
      const auto c = grid.cell_center(idx);
      alpha[idx]   = c[dim - 1] < surface ? 1. : 0.;
      T[idx]       = alpha[idx] > 0 ? exact(c) : 1e9;
    }
  std::vector<typename Output<dim>::Field> fields = {{"T", &T},
                                                     {"alpha", &alpha}};

  // Samples inside the metal, between the centres of the first and the
  // last metal cells (a fixed pseudo-random sequence).
  std::vector<Point<dim>> inside, at_surface;
  unsigned int            seed = 12345;
  auto                    next = [&seed]() {
    seed = 1103515245u * seed + 12345u;
    return (seed >> 8) / double(1u << 24);
  };
  for (int n = 0; n < 200; ++n)
    {
      Point<dim> p, q;
      for (int d = 0; d < dim; ++d)
        {
          const double top = d == dim - 1 ? surface : hi[d];
          p[d]             = 0.5 * h + next() * (top - h);
          q[d]             = p[d];
        }
      // A point in the top half of the top metal cell: the stencil reaches
      // into the gas.
      q[dim - 1] = surface - 0.5 * h + 0.1 * h + 0.3 * h * next();
      inside.push_back(p);
      at_surface.push_back(q);
    }

  for (const bool linear : {false, true})
    {
      typename Output<dim>::Parameters prm;
      prm.probe_linear = linear;
      Output<dim> output(prm, grid);
      const auto  v   = output.sample(inside, fields);
      double      err = 0;
      for (std::size_t i = 0; i < inside.size(); ++i)
        err = std::max(err, std::abs(v[2 * i] - exact(inside[i])));
      const auto s       = output.sample(at_surface, fields);
      double     max_gas = 0;
      for (std::size_t i = 0; i < at_surface.size(); ++i)
        max_gas = std::max(max_gas, s[2 * i]);
      const std::string name =
        std::to_string(dim) + "D " + (linear ? "linear" : "cell");
      if (linear)
        {
          checks.at_most(name + ": max error of a linear field, K", err, 1e-9);
          checks.at_most(name + ": largest value next to the gas, K",
                         max_gas,
                         1e3);
        }
      else
        // Half a cell times the gradient in each direction bounds it; it
        // must be well above zero (the cell value is not interpolated).
        checks.in_range(name + ": max error of a linear field, K",
                        err,
                        1.,
                        0.5 * h * 10 * dim * (dim + 1) / 2);
    }
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
