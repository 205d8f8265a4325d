// femp: the free surface of the metal for the heat equation (1) (see the
// header): surface cells with |grad alpha|, the first-surface cells of the
// laser and the cells of detached drops, once per change of alpha.
#include <deal.II/base/mpi.h>
#include <deal.II/base/tensor.h>

#include <femp/heat/metal_surface.h>

#include <algorithm>
#include <mpi.h>

namespace femp
{
  using namespace dealii;

  template <int dim>
  MetalSurface<dim>::MetalSurface(const BackgroundGrid<dim> &grid,
                                  const Material            &material,
                                  const double reference_temperature,
                                  const bool   detached_drops)
      : grid(grid)
      , mat(material)
      , reference_temperature(reference_temperature)
      , detached_drops(detached_drops)
  {
  }

  template <int dim>
  void
  MetalSurface<dim>::update(const std::vector<double> &alpha,
                            const MetalBodies<dim>    *bodies)
  {
    // Surface cells: owned metal cells with a non-zero alpha gradient. At the
    // domain boundary alpha is extended with zero gradient, so the box faces
    // are not free surfaces.
    surface.clear();
    const auto  &st = grid.strides();
    const auto  &n  = grid.n_cells();
    const double h  = grid.h();
    // Per vertical column (3D: i + n_x j), the topmost owned cell with
    // alpha >= 1/2 (below); found in the same pass.
    const unsigned int n_columns = dim == 3 ? n[0] * n[1] : n[0];
    const auto         column    = [&](const auto &ijk) {
      return dim == 3 ? ijk[0] + n[0] * ijk[1] : ijk[0];
    };
    std::vector<int> top(n_columns, -1);
    grid.for_each_owned_cell([&](const std::size_t idx, const auto &ijk) {
      if (alpha[idx] <= 0)
        return;
      if (alpha[idx] >= 0.5)
        {
          const auto col = column(ijk);
          top[col]       = std::max(top[col], ijk[dim - 1]);
        }
      Tensor<1, dim> g;
      for (int d = 0; d < dim; ++d)
        {
          const double am = ijk[d] > 0 ? alpha[idx - st[d]] : alpha[idx];
          const double ap =
            ijk[d] < int(n[d]) - 1 ? alpha[idx + st[d]] : alpha[idx];
          g[d] = (ap - am) / (2 * h);
        }
      const double norm = g.norm();
      if (norm > 1e-12 / h)
        surface.push_back({std::uint32_t(idx), norm});
    });

    // Detached drops: a drop of at most K = 'Detached drop cells'
    // face-connected metal cells with no other metal face neighbour inside
    // the domain (MetalBodies finds them) has no surface for the central
    // differences of alpha (a cell between two metal neighbours, or between
    // two gas cells, sees a zero difference) or only a small one, and no
    // metal to conduct to, so without a model of the gas round it a spatter
    // drop keeps its temperature. The drop is taken as a sphere of its metal
    // volume (2D: a cylinder) in still gas, diameter d: surface per cell
    // volume 2 dim alpha/d for each of its cells, over which it loses q(T)
    // (convection, radiation, evaporation) plus the conduction of a sphere
    // in still gas, Nu k_g/d (T - T_ref) with Nu = 2 (a drop of 2-10 um at
    // 1 m/s relative to argon has Re < 1, where Nu stays near 2).
    drops.clear();
    if (detached_drops && bodies)
      for (const auto &drop : bodies->detached_drops())
        drops.push_back({drop.index,
                         2 * dim * alpha[drop.index] / drop.diameter,
                         2 * mat.gas_conductivity / drop.diameter});

    // First-surface cells: per vertical column, the topmost cell with
    // alpha >= 1/2 over all ranks (one reduction per change of alpha). The
    // beam meets metal in the surface cells from the one below it upward
    // (a flat surface through a half-filled cell spreads |grad alpha| over
    // that cell and the full one below). The column's flux is shared among
    // them in proportion to the loss weight w |grad alpha| (w with c_m at
    // T_ref), so that the laser and the surface losses act on the same
    // cells with the same weights and a partly filled cell gets per unit
    // heat capacity what its part of the surface gets; the shares of a
    // column sum to 1/h, the absorbed power stays eta P. A column without
    // surface cells there (a metal top at the box face) gives q/h to its
    // topmost cell with alpha >= 1/2, as before.
    MPI_Allreduce(MPI_IN_PLACE,
                  top.data(),
                  n_columns,
                  MPI_INT,
                  MPI_MAX,
                  grid.communicator());
    const double rho_c_ref =
      mat.density * mat.specific_heat.value(reference_temperature);
    const double rho_g_c_g = mat.gas_density * mat.gas_specific_heat;
    auto         weight    = [&](const SurfaceCell &sc) {
      const double a = alpha[sc.index];
      return 2 * (a * rho_c_ref + (1 - a) * rho_g_c_g) /
             (rho_c_ref + rho_g_c_g) * sc.grad_alpha;
    };
    auto column_of = [&](const std::uint32_t idx, int &k) {
      const auto ijk = grid.global_index(idx);
      k              = ijk[dim - 1];
      return column(ijk);
    };
    std::vector<double> column_weight(n_columns, 0.);
    for (const auto &sc : surface)
      {
        int        k;
        const auto col = column_of(sc.index, k);
        if (k >= top[col] - 1)
          column_weight[col] += weight(sc);
      }
    MPI_Allreduce(MPI_IN_PLACE,
                  column_weight.data(),
                  n_columns,
                  MPI_DOUBLE,
                  MPI_SUM,
                  grid.communicator());
    first.clear();
    for (const auto &sc : surface)
      {
        int        k;
        const auto col = column_of(sc.index, k);
        if (k >= top[col] - 1 && column_weight[col] > 0)
          first.push_back({sc.index, weight(sc) / (column_weight[col] * h)});
      }
    grid.for_each_owned_cell([&](const std::size_t idx, const auto &ijk) {
      const auto col = column(ijk);
      if (top[col] == ijk[dim - 1] && !(column_weight[col] > 0))
        first.push_back({std::uint32_t(idx), 1. / h});
    });
  }

  template class MetalSurface<2>;
  template class MetalSurface<3>;
} // namespace femp
