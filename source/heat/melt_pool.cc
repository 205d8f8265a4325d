// femp: melt-pool size (length, width, depth) from the cell temperatures,
// with the isotherm located by linear interpolation between cell centres.
// Only melt connected to colder metal counts: liquid spatter flying through
// the gas (melt cells with no path of melt cells to colder metal) is left
// out, so a droplet above the bed does not stretch the pool's box.
#include <deal.II/base/mpi.h>

#include <femp/heat/melt_pool.h>

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
    const MPI_Comm comm = grid.communicator();
    const auto melt = [&](const std::size_t i) {
      return alpha[i] > 0 && T[i] >= T_melt;
    };
    const auto face_neighbours = [&](const std::size_t idx, auto &&f) {
      const auto ijk = grid.global_index(idx);
      for (int d = 0; d < dim; ++d)
        {
          if (ijk[d] > 0)
            f(idx - st[d]);
          if (ijk[d] < int(n[d]) - 1)
            f(idx + st[d]);
        }
    };

    // The pool: melt cells connected through melt face neighbours to a melt
    // cell that touches colder metal. Seeds first, then grow: local sweeps
    // until nothing changes on this rank, a ghost exchange, and again until
    // no rank changes. With no seed at all (everything molten) every melt
    // cell counts.
    std::vector<double> in_pool(alpha.size(), 0.);
    unsigned int        n_seeds = 0;
    for (const auto idx : grid.owned_cells())
      if (melt(idx))
        face_neighbours(idx, [&](const std::size_t nb) {
          if (alpha[nb] > 0 && T[nb] < T_melt && in_pool[idx] == 0)
            {
              in_pool[idx] = 1;
              ++n_seeds;
            }
        });
    if (Utilities::MPI::sum(n_seeds, comm) == 0)
      for (const auto idx : grid.owned_cells())
        in_pool[idx] = melt(idx) ? 1 : 0;
    else
      for (;;)
        {
          grid.update_ghosts(in_pool);
          unsigned int added = 0;
          for (bool changed = true; changed;)
            {
              changed = false;
              for (const auto idx : grid.owned_cells())
                if (in_pool[idx] == 0 && melt(idx))
                  face_neighbours(idx, [&](const std::size_t nb) {
                    if (in_pool[nb] != 0 && in_pool[idx] == 0)
                      {
                        in_pool[idx] = 1;
                        changed      = true;
                        ++added;
                      }
                  });
            }
          if (Utilities::MPI::sum(added, comm) == 0)
            break;
        }

    double volume = 0, Tmax = -big;
    for (const auto idx : grid.owned_cells())
      {
        if (alpha[idx] <= 0)
          continue;
        const double Tc = T[idx];
        Tmax = std::max(Tmax, Tc);
        if (Tc < T_melt || in_pool[idx] == 0)
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
