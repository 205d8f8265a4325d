// femp: melt-pool size (length, width, depth) from the cell temperatures,
// with the isotherm located by linear interpolation between cell centres.
// Only melt connected to colder metal counts: liquid spatter flying through
// the gas (melt cells with no path of melt cells to colder metal) is left
// out, so a droplet above the bed does not stretch the pool's box, and once
// the track has solidified a drop still liquid in the gas is no pool.
// The same measurement restricted to the cells below the original substrate
// top, at the solidus, gives the fusion zone as a metallographic cross-
// section of the track shows it (width and depth in the substrate).
// The lateral extent (x, and y in 3D) is read at the surface as well: the
// top metal cell of each column (below the substrate top for the fusion
// zone) extrapolates T linearly from its centre and the centre below to
// the surface (the substrate top, or the metal's height in the cell), and
// the isotherm's crossings between neighbouring surface cells are
// interpolated. Where the pool is narrower than the beam its edge meets
// the surface at an angle, and the cell-centre reading (h/2 below the
// surface) alone would be short by an error of first order in h.
#include <deal.II/base/mpi.h>

#include <femp/heat/melt_pool.h>

#include <limits>

namespace femp
{
  namespace
  {
    /// Box of the region T >= T_iso of metal cells with centre below
    /// @p z_top, connected to colder metal; crossings interpolated, the
    /// lateral ones also at the surface (above).
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

      // Grow the set @p in (1 on owned cells, ghosts updated here) by the
      // cells for which @p may(idx) holds, through the neighbours that
      // @p neighbours(idx, f) visits: local sweeps until nothing changes on
      // this rank, a ghost exchange, and again until no rank changes.
      // Collective.
      const auto grow =
        [&](std::vector<double> &in, auto &&may, auto &&neighbours) {
          for (;;)
            {
              grid.update_ghosts(in);
              unsigned int added = 0;
              for (bool changed = true; changed;)
                {
                  changed = false;
                  for (const auto idx : grid.owned_cells())
                    if (in[idx] == 0 && may(idx))
                      neighbours(idx, [&](const std::size_t nb) {
                        if (in[nb] != 0 && in[idx] == 0)
                          {
                            in[idx] = 1;
                            changed = true;
                            ++added;
                          }
                      });
                }
              if (Utilities::MPI::sum(added, comm) == 0)
                break;
            }
        };

      // The pool: melt cells connected through melt face neighbours to a
      // melt cell that touches colder metal: seeds first, then grow. With
      // no seed, every melt cell counts when no metal is colder (everything
      // molten); otherwise the melt is only detached drops, and there is no
      // pool.
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
        grow(in_pool, melt, face_neighbours);
      grid.update_ghosts(in_pool);

      // The surface: the metal cells (centre below z_top) with no such
      // cell above, T extrapolated linearly from the centre and the metal
      // cell below to the surface height: z_top or the metal's height in
      // the cell (alpha h above its lower face), whichever is lower, at
      // most h/2 from the centre. T_surf < 0 marks the other cells.
      constexpr int       up = dim - 1;
      std::vector<double> T_surf(alpha.size(), -1.);
      const auto          counted = [&](const std::size_t i) {
        return alpha[i] > 0 && below(i);
      };
      for (const auto idx : grid.owned_cells())
        {
          if (!counted(idx))
            continue;
          const auto ijk = grid.global_index(idx);
          if (ijk[up] < int(n[up]) - 1 && counted(idx + st[up]))
            continue;
          const double zc = grid.cell_center(idx)[up];
          const double zs =
            std::min(z_top, zc + h * (std::min(alpha[idx], 1.) - 0.5));
          const double dz = std::max(-0.5 * h, std::min(0.5 * h, zs - zc));
          double       Ts = T[idx];
          if (ijk[up] > 0 && counted(idx - st[up]))
            Ts += dz / h * (T[idx] - T[idx - st[up]]);
          T_surf[idx] = Ts;
        }
      grid.update_ghosts(T_surf);
      const auto lateral_neighbours = [&](const std::size_t idx, auto &&f) {
        const auto ijk = grid.global_index(idx);
        for (int d = 0; d < up; ++d)
          {
            if (ijk[d] > 0)
              f(idx - st[d]);
            if (ijk[d] < int(n[d]) - 1)
              f(idx + st[d]);
          }
      };
      // The pool at the surface: the surface cells at or above T_iso there,
      // connected through such lateral neighbours to a surface cell of the
      // pool (a cell just outside the pool at its centre may be inside it
      // at the surface).
      std::vector<double> in_surface(alpha.size(), 0.);
      const auto          hot_surface = [&](const std::size_t i) {
        return T_surf[i] >= T_iso;
      };
      for (const auto idx : grid.owned_cells())
        if (in_pool[idx] != 0 && melt(idx) && hot_surface(idx))
          in_surface[idx] = 1;
      grow(in_surface, hot_surface, lateral_neighbours);
      grid.update_ghosts(in_surface);

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
      // The lateral crossings at the surface: towards a surface cell below
      // T_iso there, interpolated; towards gas or the domain boundary, the
      // cell face; else (the surface steps up, or the neighbour is also in
      // the surface pool) the cell centre.
      for (const auto idx : grid.owned_cells())
        {
          if (in_surface[idx] == 0)
            continue;
          const auto       ijk = grid.global_index(idx);
          const Point<dim> c   = grid.cell_center(idx);
          const double     Ts  = T_surf[idx];
          for (int d = 0; d < up; ++d)
            for (const int side : {-1, 1})
              {
                double     x = c[d];
                const bool inside =
                  side < 0 ? ijk[d] > 0 : ijk[d] < int(n[d]) - 1;
                if (!inside)
                  x += side * 0.5 * h;
                else
                  {
                    const std::size_t nb = idx + side * st[d];
                    if (T_surf[nb] >= 0 && T_surf[nb] < T_iso)
                      x += side * h * (Ts - T_iso) / (Ts - T_surf[nb]);
                    else if (alpha[nb] <= 0)
                      x += side * 0.5 * h;
                  }
                box.lo[d] = std::min(box.lo[d], x);
                box.hi[d] = std::max(box.hi[d], x);
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
                    const std::vector<std::uint8_t> *workpiece,
                    const double                     x_min)
  {
    const double big = std::numeric_limits<double>::max();
    MeltPoolSize r;
    double       Tmax = -big;
    for (const auto idx : grid.owned_cells())
      if (alpha[idx] > 0)
        Tmax = std::max(Tmax, T[idx]);
    r.T_max = Utilities::MPI::max(Tmax, grid.communicator());

    // With the workpiece given, other metal (detached drops, powder not
    // touching it) is taken as gas by the isotherm boxes; so is the metal
    // of the cells with centre x below x_min.
    std::vector<double> counted_alpha;
    const bool          cut = x_min > -std::numeric_limits<double>::max();
    if (workpiece || cut)
      {
        counted_alpha = alpha;
        for (const auto idx : grid.owned_cells())
          if ((workpiece && !(*workpiece)[idx]) ||
              (cut && grid.cell_center(idx)[0] < x_min))
            counted_alpha[idx] = 0;
        grid.update_ghosts(counted_alpha);
      }
    const std::vector<double> &metal =
      (workpiece || cut) ? counted_alpha : alpha;

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
                       const std::vector<std::uint8_t> *,
                       double);
  template MeltPoolSize
  measure_melt_pool<3>(const BackgroundGrid<3> &,
                       const std::vector<double> &,
                       const std::vector<double> &,
                       double,
                       double,
                       double,
                       const std::vector<std::uint8_t> *,
                       double);
} // namespace femp
