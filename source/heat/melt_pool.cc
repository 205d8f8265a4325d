// femp: melt-pool size (length, width, depth) from the cell temperatures,
// with the isotherm located by linear interpolation between cell centres.
// Only melt connected to colder metal counts: liquid spatter flying through
// the gas (melt cells with no path of melt cells to colder metal) is left
// out, so a droplet above the bed does not stretch the pool's box, and once
// the track has solidified a drop still liquid in the gas is no pool.
// The same measurement restricted to the cells below the original substrate
// top, at the solidus, gives the fusion zone as a metallographic cross-
// section of the track shows it (width and depth in the substrate).
#include <deal.II/base/mpi.h>

#include <femp/heat/melt_pool.h>

#include <limits>

namespace femp
{
  namespace
  {
    /// Box of the region T >= T_iso of metal cells with centre below
    /// @p z_top, connected to colder metal; crossings interpolated.
    template <int dim>
    struct IsothermBox
    {
      std::array<double, dim> lo, hi;
      double                  volume = 0;
    };

    template <int dim>
    IsothermBox<dim>
    isotherm_box(const BackgroundGrid<dim> &grid,
                 const std::vector<double> &T,
                 const std::vector<double> &alpha,
                 const double               T_iso,
                 const double               z_top)
    {
      const auto      &st  = grid.strides();
      const auto      &n   = grid.n_cells();
      const double     h   = grid.h();
      const double     big = std::numeric_limits<double>::max();
      IsothermBox<dim> box;
      box.lo.fill(big);
      box.hi.fill(-big);
      const MPI_Comm comm  = grid.communicator();
      const auto     below = [&](const std::size_t i) {
        return grid.cell_center(i)[dim - 1] < z_top;
      };
      const auto melt = [&](const std::size_t i) {
        return alpha[i] > 0 && T[i] >= T_iso && below(i);
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

      // The pool: melt cells connected through melt face neighbours to a
      // melt cell that touches colder metal. Seeds first, then grow: local
      // sweeps until nothing changes on this rank, a ghost exchange, and
      // again until no rank changes. With no seed, every melt cell counts
      // when no metal is colder (everything molten); otherwise the melt is
      // only detached drops, and there is no pool.
      std::vector<double> in_pool(alpha.size(), 0.);
      unsigned int        n_seeds[2] = {0, 0}; // seeds, colder metal cells
      for (const auto idx : grid.owned_cells())
        {
          if (alpha[idx] > 0 && T[idx] < T_iso)
            ++n_seeds[1];
          if (melt(idx))
            face_neighbours(idx, [&](const std::size_t nb) {
              if (alpha[nb] > 0 && T[nb] < T_iso && in_pool[idx] == 0)
                {
                  in_pool[idx] = 1;
                  ++n_seeds[0];
                }
            });
        }
      unsigned int n_global[2];
      Utilities::MPI::sum(ArrayView<const unsigned int>(n_seeds, 2),
                          comm,
                          ArrayView<unsigned int>(n_global, 2));
      if (n_global[0] == 0)
        {
          if (n_global[1] == 0)
            for (const auto idx : grid.owned_cells())
              in_pool[idx] = melt(idx) ? 1 : 0;
        }
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

      for (const auto idx : grid.owned_cells())
        {
          if (in_pool[idx] == 0 || !melt(idx))
            continue;
          const double Tc = T[idx];
          box.volume += std::pow(h, dim);
          const auto       ijk = grid.global_index(idx);
          const Point<dim> c   = grid.cell_center(idx);
          for (int d = 0; d < dim; ++d)
            {
              // Default: the pool reaches the cell centre; extend to the
              // interpolated crossing towards a colder metal neighbour, or
              // to the cell face at gas or the domain boundary (upward: at
              // most to z_top).
              for (const int side : {-1, 1})
                {
                  double     x = c[d];
                  const bool inside =
                    side < 0 ? ijk[d] > 0 : ijk[d] < int(n[d]) - 1;
                  if (inside)
                    {
                      const std::size_t nb = idx + side * st[d];
                      if (alpha[nb] > 0 && T[nb] < T_iso)
                        x += side * h * (Tc - T_iso) / (Tc - T[nb]);
                      else if (alpha[nb] <= 0)
                        x += side * 0.5 * h;
                    }
                  else
                    x += side * 0.5 * h;
                  if (d == dim - 1)
                    x = std::min(x, z_top);
                  box.lo[d] = std::min(box.lo[d], x);
                  box.hi[d] = std::max(box.hi[d], x);
                }
            }
        }
      for (int d = 0; d < dim; ++d)
        {
          box.lo[d] = Utilities::MPI::min(box.lo[d], comm);
          box.hi[d] = Utilities::MPI::max(box.hi[d], comm);
        }
      box.volume = Utilities::MPI::sum(box.volume, comm);
      return box;
    }
  } // namespace

  template <int dim>
  MeltPoolSize
  measure_melt_pool(const BackgroundGrid<dim>       &grid,
                    const std::vector<double>       &T,
                    const std::vector<double>       &alpha,
                    const double                     T_melt,
                    const double                     surface_height,
                    const double                     T_solidus,
                    const std::vector<std::uint8_t> *workpiece)
  {
    const double big = std::numeric_limits<double>::max();
    MeltPoolSize r;
    double       Tmax = -big;
    for (const auto idx : grid.owned_cells())
      if (alpha[idx] > 0)
        Tmax = std::max(Tmax, T[idx]);
    r.T_max = Utilities::MPI::max(Tmax, grid.communicator());

    // With the workpiece given, other metal (detached drops, powder not
    // touching it) is taken as gas by the isotherm boxes.
    std::vector<double> workpiece_alpha;
    if (workpiece)
      {
        workpiece_alpha = alpha;
        for (const auto idx : grid.owned_cells())
          if (!(*workpiece)[idx])
            workpiece_alpha[idx] = 0;
        grid.update_ghosts(workpiece_alpha);
      }
    const std::vector<double> &metal = workpiece ? workpiece_alpha : alpha;

    const auto pool = isotherm_box(grid, T, metal, T_melt, big);
    r.volume        = pool.volume;
    if (r.volume > 0)
      {
        for (int d = 0; d < dim; ++d)
          {
            r.lower[d] = pool.lo[d];
            r.upper[d] = pool.hi[d];
          }
        r.length = pool.hi[0] - pool.lo[0];
        r.width  = dim == 3 ? pool.hi[1] - pool.lo[1] : pool.hi[0] - pool.lo[0];
        r.depth  = std::max(0., surface_height - pool.lo[dim - 1]);
      }

    const auto fusion = isotherm_box(grid, T, metal, T_solidus, surface_height);
    if (fusion.volume > 0)
      {
        r.solidus_width =
          dim == 3 ? fusion.hi[1] - fusion.lo[1] : fusion.hi[0] - fusion.lo[0];
        r.solidus_depth = std::max(0., surface_height - fusion.lo[dim - 1]);
      }
    return r;
  }

  template MeltPoolSize
  measure_melt_pool<2>(const BackgroundGrid<2> &,
                       const std::vector<double> &,
                       const std::vector<double> &,
                       double,
                       double,
                       double,
                       const std::vector<std::uint8_t> *);
  template MeltPoolSize
  measure_melt_pool<3>(const BackgroundGrid<3> &,
                       const std::vector<double> &,
                       const std::vector<double> &,
                       double,
                       double,
                       double,
                       const std::vector<std::uint8_t> *);
} // namespace femp
