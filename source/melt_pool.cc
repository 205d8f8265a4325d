// femp: melt-pool size (length, width, depth) from the cell temperatures,
// with the isotherm located by linear interpolation between cell centres.
#include <deal.II/base/mpi.h>

#include <femp/melt_pool.h>

#include <limits>

namespace femp
{
  template <int dim>
  MeltPoolSize
  measure_melt_pool(const BackgroundGrid<dim> &grid,
                    const std::vector<double> &T,
                    const std::vector<double> &alpha,
                    const double               T_melt,
                    const double               surface_height)
  {
    const auto &st = grid.strides();
    const auto &n  = grid.n_cells();
    const double h = grid.h();
    const double big = std::numeric_limits<double>::max();
    std::array<double, dim> lo, hi;
    lo.fill(big);
    hi.fill(-big);
    double volume = 0, Tmax = -big;
    for (const auto idx : grid.owned_cells())
      {
        if (alpha[idx] <= 0)
          continue;
        const double Tc = T[idx];
        Tmax = std::max(Tmax, Tc);
        if (Tc < T_melt)
          continue;
        volume += std::pow(h, dim);
        const auto       ijk = grid.global_index(idx);
        const Point<dim> c   = grid.cell_center(idx);
        for (int d = 0; d < dim; ++d)
          {
            // Default: the pool reaches the cell centre; extend to the
            // interpolated crossing towards a colder metal neighbour, or to
            // the cell face at gas or the domain boundary.
            for (const int side : {-1, 1})
              {
                double x = c[d];
                const bool inside = side < 0 ? ijk[d] > 0 : ijk[d] < int(n[d]) - 1;
                if (inside)
                  {
                    const std::size_t nb = idx + side * st[d];
                    if (alpha[nb] > 0 && T[nb] < T_melt)
                      x += side * h * (Tc - T_melt) / (Tc - T[nb]);
                    else if (alpha[nb] <= 0)
                      x += side * 0.5 * h;
                  }
                else
                  x += side * 0.5 * h;
                lo[d] = std::min(lo[d], x);
                hi[d] = std::max(hi[d], x);
              }
          }
      }
    MeltPoolSize r;
    const MPI_Comm comm = grid.communicator();
    for (int d = 0; d < dim; ++d)
      {
        lo[d] = Utilities::MPI::min(lo[d], comm);
        hi[d] = Utilities::MPI::max(hi[d], comm);
      }
    r.volume = Utilities::MPI::sum(volume, comm);
    r.T_max  = Utilities::MPI::max(Tmax, comm);
    if (r.volume > 0)
      {
        for (int d = 0; d < dim; ++d)
          {
            r.lower[d] = lo[d];
            r.upper[d] = hi[d];
          }
        r.length = hi[0] - lo[0];
        r.width  = dim == 3 ? hi[1] - lo[1] : hi[0] - lo[0];
        r.depth  = std::max(0., surface_height - lo[dim - 1]);
      }
    return r;
  }

  template MeltPoolSize
  measure_melt_pool<2>(const BackgroundGrid<2> &, const std::vector<double> &,
                       const std::vector<double> &, double, double);
  template MeltPoolSize
  measure_melt_pool<3>(const BackgroundGrid<3> &, const std::vector<double> &,
                       const std::vector<double> &, double, double);
} // namespace femp
