// femp: explicit MPM for the fusible solid, MUSL variant with FLIP or APIC
// velocity transfer (paper eqs. 11-13; see solid_mpm.h for the algorithm,
// the choice of variant and the cell-crossing rules).
#include <deal.II/base/mpi.h>

#include <femp/grid/cell_state.h>
#include <femp/solid/mpm_kernels.h>
#include <femp/solid/solid_mpm.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <type_traits>

namespace femp
{
  using namespace mpm_kernels;

  template <int dim>
  SolidMPM<dim>::SolidMPM(const BackgroundGrid<dim> &grid,
                          const SolidMaterial       &material,
                          MaterialPoints<dim>       &points)
      : SolidPointStore<dim>(grid, material, points)
      , zone_face_tolerance(0.5 * points.point_spacing())
  {
    const auto &s = grid.node_strides();
    for (unsigned int a = 0; a < n_corners; ++a)
      {
        corner_offset[a] = 0;
        for (int d = 0; d < dim; ++d)
          if (a & (1u << d))
            corner_offset[a] += s[d];
      }
  }

  template <int dim>
  void
  SolidMPM<dim>::gather(const std::vector<std::uint8_t> &excluded_cell,
                        const double                     mass_scaling,
                        const bool                       same_members)
  {
    this->gather_members(excluded_cell, mass_scaling, same_members);
    // The P2G buffer of the fused pass: zero again, and its node list anew.
    clear_next();
    next_ready         = false;
    steps_since_gather = 0;
    for (const auto n : next_nodes)
      node_mark[n] = 0;
    next_nodes.clear();
    node_mark.resize(grid.n_local_nodes(), 0);
    for (const auto c : reached_cells)
      cell_mark[c] = 0;
    reached_cells.clear();
    cell_mark.resize(grid.n_local(), 0);
    lost      = false;
    left_rank = 0;
    for (std::size_t p = 0; p < node0.size(); ++p)
      if (p == 0 || node0[p] != node0[p - 1])
        mark_cell_nodes(cell[p], node0[p]);
    sum_energies();
  }

  template <int dim>
  void
  SolidMPM<dim>::mark_cell_nodes(const std::size_t idx, const std::size_t n0)
  {
    if (!cell_mark[idx])
      cell_mark[idx] = 1, reached_cells.push_back(idx);
    for (unsigned int a = 0; a < n_corners; ++a)
      {
        const std::size_t n = n0 + corner_offset[a];
        if (!node_mark[n])
          node_mark[n] = 1, next_nodes.push_back(n);
      }
  }

  template <int dim>
  void
  SolidMPM<dim>::clear_next()
  {
    if (next_dirty)
      for (auto &f : next)
        if (!f.empty()) // the stiffness rows: with the floor only
          for (const auto n : next_nodes)
            f[n] = 0;
    next_dirty = false;
  }

  template <int dim>
  void
  SolidMPM<dim>::resort()
  {
    // Points that entered a cell of a neighbour rank go there with the
    // others that changed cells (scatter(): only the cells they left are
    // looked at, their new cells are ghost cells here; deal.II's global sort
    // of every point, about 500 ns per point, only if that fails). Then
    // gather again: the members of this rank changed.
    this->scatter();
    const std::vector<std::uint8_t> mask = excluded;
    gather(mask, scaling);
  }

  template <int dim>
  void
  SolidMPM<dim>::sum_energies()
  {
    const double h = grid.h();
    kinetic        = 0;
    weight_momentum.fill(0.);
    for (std::size_t p = 0; p < true_mass.size(); ++p)
      {
        double v2 = 0;
        for (int d = 0; d < dim; ++d)
          {
            v2 += v[d][p] * v[d][p];
            weight_momentum[d] += true_mass[p] * v[d][p];
          }
        if (apic)
          add_affine_kinetic<dim>(x, corner, C, p, h, v2);
        kinetic += 0.5 * (true_mass[p] * scaling) * v2;
      }
  }

  template <int dim>
  void
  SolidMPM<dim>::p2g(SolidNodeFields<dim> &nodes, const Tensor<1, dim> &gravity)
  {
    // Mass, momentum (dim), force (dim) and, with the light-node mass
    // floor, the stiffness row sums.
    const unsigned int nf = 1 + 2 * dim + (stiffness_rows ? 1 : 0);
    double            *nodes_out[2 + 2 * dim] = {nodes.mass.data()};
    for (int d = 0; d < dim; ++d)
      nodes_out[1 + d]                     = nodes.momentum[d].data(),
                    nodes_out[1 + dim + d] = nodes.force[d].data();
    if (stiffness_rows)
      {
        AssertDimension(nodes.stiffness.size(), nodes.mass.size());
        nodes_out[1 + 2 * dim] = nodes.stiffness.data();
      }
    // Sums of the fused pass of the last update_stresses(): add them (the
    // caller zeroed the nodes; a plain copy would not do for nodes it did
    // not zero) and leave the buffer zero.
    if (next_ready && gravity == p2g_gravity)
      {
        for (unsigned int k = 0; k < nf; ++k)
          {
            double *const out = nodes_out[k];
            double *const buf = next[k].data();
            for (const auto I : next_nodes)
              out[I] += buf[I], buf[I] = 0;
          }
        next_ready = next_dirty = false;
        return;
      }
    clear_next();
    next_ready   = false;
    have_gravity = true;
    p2g_gravity  = gravity;
    if (centroid_volumetric())
      compute_centroids();

    const std::size_t   n = true_mass.size();
    const P2GInput<dim> in{x,
                           corner,
                           v,
                           C,
                           true_mass,
                           volume,
                           visc,
                           sigma,
                           node0,
                           scaling,
                           grid.h(),
                           gravity,
                           cell,
                           cell_centroid};
    // The transfer, the floor and the volumetric strain rate are
    // compile-time constants inside the loop (measured: 7-20 % faster than
    // a run-time branch per point).
    auto run = [&](auto transfer, auto floor, auto bbar) {
      constexpr bool A = decltype(transfer)::value;
      constexpr bool G = decltype(floor)::value;
      constexpr bool B = decltype(bbar)::value;
      CellScatter<n_corners, 1 + 2 * dim + G, point_lanes<dim>> out(
        corner_offset, nodes_out);
      p2g_blocks<A, G, B>(in, 0, n, n, out);
    };
    auto run_b = [&](auto transfer, auto floor) {
      if (centroid_volumetric())
        run(transfer, floor, std::true_type());
      else
        run(transfer, floor, std::false_type());
    };
    if (apic && stiffness_rows)
      run_b(std::true_type(), std::true_type());
    else if (apic)
      run_b(std::true_type(), std::false_type());
    else if (stiffness_rows)
      run_b(std::false_type(), std::true_type());
    else
      run_b(std::false_type(), std::false_type());
  }

  template <int dim>
  void
  SolidMPM<dim>::compute_centroids()
  {
    const std::size_t nc = grid.n_local();
    cell_volume.resize(nc, 0.);
    for (int d = 0; d < dim; ++d)
      cell_centroid[d].resize(nc, 0.);
    // Every point's cell is among the reached cells (gather(),
    // finish_points()).
    for (const auto c : reached_cells)
      {
        cell_volume[c] = 0;
        for (int d = 0; d < dim; ++d)
          cell_centroid[d][c] = 0;
      }
    const double ih = 1. / grid.h();
    for (std::size_t p = 0; p < true_mass.size(); ++p)
      {
        const auto   c = cell[p];
        const double V = volume[p];
        cell_volume[c] += V;
        for (int d = 0; d < dim; ++d)
          cell_centroid[d][c] += V * ((x[d][p] - corner[d][p]) * ih);
      }
    for (const auto c : reached_cells)
      if (cell_volume[c] > 0)
        {
          const double iV = 1. / cell_volume[c];
          for (int d = 0; d < dim; ++d)
            cell_centroid[d][c] *= iV;
        }
  }

  template <int dim>
  void
  SolidMPM<dim>::set_stiffness_rows(const bool on)
  {
    // The fused buffer of the next P2G was summed with or without them.
    clear_next();
    next_ready     = false;
    stiffness_rows = on;
  }

  template <int dim>
  void
  SolidMPM<dim>::g2p(SolidNodeFields<dim> &nodes, const double dt)
  {
    const double  h = grid.h(), ih = 1. / h;
    const double *vel[dim], *acc[dim];
    double       *mom[dim];
    for (int d = 0; d < dim; ++d)
      {
        vel[d] = nodes.velocity[d].data();
        acc[d] = nodes.force[d].data(); // f_I / m_I at this point
        mom[d] = nodes.momentum[d].data();
      }
    const std::size_t n = true_mass.size();
    for (int d = 0; d < dim; ++d) // FLIP only (APIC: the grid velocity is v)
      xdot[d].resize(apic ? 0 : n);
    // Blocks of W points as in p2g(): nodal values gathered lane
    // by lane, the interpolation and the re-map contributions in SIMD, the
    // re-map added to the nodes in point order.
    constexpr unsigned int W = point_lanes<dim>;
    using VD                 = typename SimdOf<W>::type;
    PointArrays<dim> pa{x,
                        corner,
                        v,
                        xdot,
                        C,
                        true_mass,
                        volume,
                        visc,
                        sigma,
                        eps_p,
                        cell,
                        node0};
    // The transfer is a compile-time constant inside the loop (measured:
    // 7-20 % faster than a run-time branch per point).
    auto loop = [&](auto transfer) {
      constexpr bool                 A = decltype(transfer)::value;
      CellScatter<n_corners, dim, W> remap(corner_offset, mom);
      // Monomial coefficients of the nodal velocity (and FLIP: the nodal
      // acceleration) of the cell of the last one-cell block; the blocks
      // of a cell share them (the points are sorted by cell).
      constexpr std::size_t none      = std::size_t(-1);
      std::size_t           coef_cell = none;
      VD                    cv[dim][n_corners], ca[dim][n_corners];
      for (std::size_t p0 = 0; p0 < n; p0 += W)
        {
          const PointBlock<W> blk(p0, n);
          prefetch_g2p_block<dim, A>(pa, p0, n);
          VD xi[dim], N[n_corners];
          block_xi<dim>(pa.x, pa.corner, blk, ih, xi);
          weights<dim>(xi, N);
          std::size_t n0[W];
          for (unsigned int l = 0; l < W; ++l)
            n0[l] = pa.node0[blk.pl[l]];
          g2p_coefficients<dim, A>(
            vel, acc, corner_offset, n0, cv, ca, coef_cell);
          VD vp[dim], Cn[dim][dim];
          g2p_velocity<dim, A>(pa, blk, p0, xi, cv, ca, ih, dt, vp, Cn);
          VD nmom[n_corners][dim];
          remap_momentum<dim, A>(pa, blk, p0, xi, N, vp, Cn, h, scaling, nmom);
          remap.add(nmom, n0, blk.nl);
        }
    };
    if (apic)
      loop(std::true_type());
    else
      loop(std::false_type());
  }

  template <int dim>
  double
  SolidMPM<dim>::update_stresses(const SolidNodeFields<dim> &nodes,
                                 const double                dt,
                                 const std::vector<double>  &T_old,
                                 const std::vector<double>  &T_new)
  {
    const double  h = grid.h();
    const double *vel[dim];
    for (int d = 0; d < dim; ++d)
      vel[d] = nodes.velocity[d].data();
    double            work = 0;
    const std::size_t n    = true_mass.size();
    left_rank              = 0;
    lost                   = false;
    kinetic                = 0;
    min_volume             = std::numeric_limits<double>::infinity();
    weight_momentum.fill(0.);
    const StressStep<dim> st = stress_step<dim>(
      mat, vel, corner_offset, T_old, T_new, dt, h, scaling, cell_centroid);
    CellModuli moduli = first_cell_moduli(mat, cell, n, T_old, T_new);
    // Fused P2G of the next step (see solid_mpm.h), into the buffer next:
    // from the second step after a gather on (the benchmark's and a coupled
    // run's sub-cycling), so that a run of one step per gather pays nothing
    // for it, nor a rank without points (no buffer). The buffer is zero
    // here (p2g() consumed or cleared it). Not with the centroid's
    // volumetric strain rate: its P2G needs the centroids of the moved
    // points of whole cells (p2g(), compute_centroids()).
    // Nor with the pressure smoothing: the next P2G needs the smoothed
    // stresses of all points.
    const bool smooth = mat.pressure_smoothing;
    if (smooth)
      save_pressure_state(T_new);
    const bool fuse = n > 0 && steps_since_gather > 0 && have_gravity &&
                      !centroid_volumetric() && !smooth;
    ++steps_since_gather;
    const unsigned int nf = 1 + 2 * dim + (stiffness_rows ? 1 : 0);
    double            *next_out[2 + 2 * dim] = {};
    if (fuse)
      {
        for (unsigned int k = 0; k < nf; ++k)
          {
            next[k].resize(grid.n_local_nodes(), 0.);
            next_out[k] = next[k].data();
          }
        next_dirty = true;
      }
    // Blocks of W points (point_lanes), one point per lane of a vector (GCC
    // vector extension, see constitutive.h): shape functions, velocity
    // gradient, constitutive update (update_stress_block), work, viscous
    // pressure, volume and move in SIMD; a partial last block repeats its
    // last point in the spare lanes and stores nothing from them. The sums
    // (work, kinetic energy, momentum) are taken in point order and the
    // arithmetic per point is that of the scalar formulation.
    constexpr unsigned int W = point_lanes<dim>;
    using VD                 = typename SimdOf<W>::type;
    PointArrays<dim> pa{x,
                        corner,
                        v,
                        xdot,
                        C,
                        true_mass,
                        volume,
                        visc,
                        sigma,
                        eps_p,
                        cell,
                        node0};
    auto loop = [&](auto transfer, auto fused, auto floor, auto bbar) {
      constexpr bool                             A = decltype(transfer)::value;
      constexpr bool                             F = decltype(fused)::value;
      constexpr bool                             G = decltype(floor)::value;
      constexpr bool                             B = decltype(bbar)::value;
      CellScatter<n_corners, 1 + 2 * dim + G, W> out(corner_offset, next_out);
      const P2GInput<dim>                        in{x,
                             corner,
                             v,
                             C,
                             true_mass,
                             volume,
                             visc,
                             sigma,
                             node0,
                             scaling,
                             h,
                             p2g_gravity,
                             cell,
                             cell_centroid};
      // Chunks of points: stress update and move, then (fused) the P2G of
      // the chunk's points, whose data are still in the L1 cache.
      constexpr std::size_t chunk = 16 * W;
      // Monomial coefficients of the nodal velocity of the cell of the
      // last one-cell block (see g2p()).
      constexpr std::size_t none      = std::size_t(-1);
      std::size_t           coef_cell = none;
      VD                    cv[dim][n_corners];
      // Sums of the lanes of the blocks (lanes of a partial block that
      // are not in use are masked by use); summed at the end.
      VD work_v = {}, kinetic_v = {}, momentum_v[dim] = {};
      VD vmin = VD{} + std::numeric_limits<double>::infinity();
      for (std::size_t c0 = 0; c0 < n; c0 += chunk)
        {
          const std::size_t c1 = std::min(n, c0 + chunk);
          for (std::size_t p0 = c0; p0 < c1; p0 += W)
            {
              const PointBlock<W> blk(p0, n);
              prefetch_stress_block<dim, A>(pa, p0, n);
              VD use, m, mg;
              stress_block<dim, B>(st,
                                   pa,
                                   blk,
                                   p0,
                                   coef_cell,
                                   cv,
                                   moduli,
                                   work_v,
                                   vmin,
                                   use,
                                   m,
                                   mg);
              if (!move_block<dim, A>(
                    st, pa, blk, p0, use, m, mg, kinetic_v, momentum_v))
                finish_points<A>(p0, blk.nl);
            }
          if constexpr (F)
            p2g_blocks<A, G, B>(in, c0, c1, n, out);
        }
      work += lane_total(work_v);
      kinetic += lane_total(kinetic_v);
      for (unsigned int l = 0; l < W; ++l)
        min_volume = std::min(min_volume, vmin[l]);
      for (int d = 0; d < dim; ++d)
        weight_momentum[d] += lane_total(momentum_v[d]);
    };
    const std::true_type  yes;
    const std::false_type no;
    // The volumetric strain rate, a compile-time constant as the others;
    // the fused loops are never run with the centroid (fuse above), so
    // they are not compiled with it.
    auto loop_b = [&](auto transfer, auto fused, auto floor) {
      if constexpr (decltype(fused)::value)
        loop(transfer, fused, floor, no);
      else if (centroid_volumetric())
        loop(transfer, fused, floor, yes);
      else
        loop(transfer, fused, floor, no);
    };
    if (apic && fuse && stiffness_rows)
      loop_b(yes, yes, yes);
    else if (apic && fuse)
      loop_b(yes, yes, no);
    else if (apic)
      loop_b(yes, no, no);
    else if (fuse && stiffness_rows)
      loop_b(no, yes, yes);
    else if (fuse)
      loop_b(no, yes, no);
    else
      loop_b(no, no, no);
    if (smooth)
      work += smooth_pressure_increment();
    next_ready = fuse && !lost && left_rank == 0;
    return work;
  }

  template <int dim>
  void
  SolidMPM<dim>::save_pressure_state(const std::vector<double> &T_new)
  {
    const std::size_t n  = true_mass.size();
    const double      ih = 1. / grid.h();
    const double      Tm = mat.melt_temperature();
    ps_mean.resize(n);
    ps_volume.resize(n);
    ps_node0.resize(n);
    for (int d = 0; d < dim; ++d)
      ps_xi[d].resize(n);
    for (std::size_t p = 0; p < n; ++p)
      {
        ps_mean[p]   = (sigma[0][p] + sigma[1][p] + sigma[2][p]) * (1. / 3);
        ps_volume[p] = T_new[cell[p]] < Tm ? volume[p] : 0.;
        ps_node0[p]  = node0[p];
        for (int d = 0; d < dim; ++d)
          ps_xi[d][p] = (x[d][p] - corner[d][p]) * ih;
      }
  }

  template <int dim>
  double
  SolidMPM<dim>::smooth_pressure_increment()
  {
    // The tents of the cell of the stress update at the saved coordinates
    // (corner a: bit d set for the upper node in direction d).
    auto tents = [&](const std::size_t p, double(&N)[n_corners]) {
      for (unsigned int a = 0; a < n_corners; ++a)
        {
          double w = 1;
          for (int d = 0; d < dim; ++d)
            w *= ((a >> d) & 1) ? ps_xi[d][p] : 1 - ps_xi[d][p];
          N[a] = w;
        }
    };
    // The point's increment of tr(sigma)/3 since save_pressure_state().
    auto increment = [&](const std::size_t p) {
      return (sigma[0][p] + sigma[1][p] + sigma[2][p]) * (1. / 3) - ps_mean[p];
    };
    const std::size_t n = ps_mean.size();
    ps_weight.assign(grid.n_local_nodes(), 0.);
    ps_sum.assign(grid.n_local_nodes(), 0.);
    double N[n_corners];
    for (std::size_t p = 0; p < n; ++p)
      {
        const double V = ps_volume[p];
        if (V == 0)
          continue;
        const double dm = increment(p);
        tents(p, N);
        for (unsigned int a = 0; a < n_corners; ++a)
          {
            const std::size_t I = ps_node0[p] + corner_offset[a];
            ps_weight[I] += V * N[a];
            ps_sum[I] += V * N[a] * dm;
          }
      }
    grid.sum_shared_nodes(ps_weight);
    grid.sum_shared_nodes(ps_sum);
    double dwork = 0;
    for (std::size_t p = 0; p < n; ++p)
      {
        const double V = ps_volume[p];
        if (V == 0)
          continue;
        const double dm = increment(p);
        tents(p, N);
        double smoothed = 0;
        for (unsigned int a = 0; a < n_corners; ++a)
          {
            const std::size_t I = ps_node0[p] + corner_offset[a];
            if (ps_weight[I] > 0)
              smoothed += N[a] * ps_sum[I] / ps_weight[I];
          }
        const double shift = smoothed - dm;
        for (unsigned int c = 0; c < 3; ++c)
          sigma[c][p] += shift;
        dwork += 0.5 * shift * (volume[p] - V);
      }
    return dwork;
  }

  template <int dim>
  void
  SolidMPM<dim>::hold_in_domain(const std::size_t p, Point<dim> &xp)
  {
    const double h = grid.h();
    for (int d = 0; d < dim; ++d)
      {
        const double lo = grid.origin()[d];
        const double hi = lo + (grid.n_cells()[d] - 1e-6) * h;
        if (xp[d] < lo)
          {
            xp[d] = lo, v[d][p] = std::max(v[d][p], 0.);
            if (!xdot[d].empty())
              xdot[d][p] = std::max(xdot[d][p], 0.);
          }
        else if (xp[d] > hi)
          {
            xp[d] = hi, v[d][p] = std::min(v[d][p], 0.);
            if (!xdot[d].empty())
              xdot[d][p] = std::min(xdot[d][p], 0.);
          }
        x[d][p] = xp[d];
      }
    ++held;
  }

  template <int dim>
  typename SolidMPM<dim>::ZoneExit
  SolidMPM<dim>::nearest_zone_exit(const Point<dim>           &xp,
                                   const std::array<int, dim> &ijk,
                                   const double                limit) const
  {
    // Per direction the nearer face of the cell and the point's depth
    // below it (the farther face is more than half a cell away, farther
    // than any limit used here).
    const double            h = grid.h();
    std::array<int, dim>    side;
    std::array<double, dim> depth;
    for (int d = 0; d < dim; ++d)
      {
        const double lower = grid.origin()[d] + ijk[d] * h;
        const double a = xp[d] - lower, b = lower + h - xp[d];
        side[d]  = a <= b ? -1 : 1;
        depth[d] = std::max(0., std::min(a, b));
      }
    // Across one face, or an edge or corner (two or three faces): the
    // nearest that ends in a cell outside the zone. With the zone a box
    // of cells that is the face crossed, or at the box's edges and
    // corners the nearer of the faces crossed; a cell outside the zone
    // behind an edge only (a zone with a step) is reached across both
    // faces.
    ZoneExit best;
    for (unsigned int f = 1; f < (1u << dim); ++f)
      {
        double               r2     = 0;
        bool                 usable = true;
        std::array<int, dim> target = ijk;
        for (int d = 0; d < dim; ++d)
          if (f & (1u << d))
            {
              usable = usable && depth[d] <= limit;
              r2 += depth[d] * depth[d];
              target[d] += side[d];
              usable =
                usable && target[d] >= 0 && target[d] < int(grid.n_cells()[d]);
            }
        if (!usable || !(r2 < best.distance2) || !grid.in_box(target) ||
            excluded[grid.local_index(target)])
          continue;
        best.faces     = f;
        best.side      = side;
        best.cell      = target;
        best.distance2 = r2;
      }
    return best;
  }

  template <int dim>
  bool
  SolidMPM<dim>::hold_on_zone_face(const std::size_t     p,
                                   Point<dim>           &xp,
                                   std::array<int, dim> &ijk)
  {
    if (!hold_at_zone)
      return false;
    const auto e = nearest_zone_exit(xp, ijk, zone_face_tolerance);
    if (e.faces == 0)
      return false;
    // On each face crossed, inside the cell outside the zone (a millionth
    // of a cell beyond the face, so that the handler's sort finds it there
    // too); no velocity into the zone across it.
    const double h  = grid.h();
    double       v2 = 0; // of the components removed
    for (int d = 0; d < dim; ++d)
      if (e.faces & (1u << d))
        {
          v2 += v[d][p] * v[d][p];
          const double face =
            grid.origin()[d] + (ijk[d] + (e.side[d] > 0 ? 1 : 0)) * h;
          xp[d]   = face + e.side[d] * 1e-6 * h;
          x[d][p] = xp[d];
          if (e.side[d] > 0)
            {
              v[d][p] = std::max(v[d][p], 0.);
              if (!xdot[d].empty())
                xdot[d][p] = std::max(xdot[d][p], 0.);
            }
          else
            {
              v[d][p] = std::min(v[d][p], 0.);
              if (!xdot[d].empty())
                xdot[d][p] = std::min(xdot[d][p], 0.);
            }
          v2 -= v[d][p] * v[d][p];
        }
    held_kinetic += 0.5 * (true_mass[p] * scaling) * v2;
    ijk = e.cell;
    // Top: across a face normal to the last direction; lateral: across one
    // normal to another (both at a concave edge of a zone with a step).
    if (e.faces & (1u << (dim - 1)))
      ++held_at_top;
    if (e.faces & ((1u << (dim - 1)) - 1))
      ++held_at_lateral;
    return true;
  }

  // The points of a block of update_stresses() of which one left its cell
  // or the rank, point by point: kinetic energy and momentum, the cell
  // crossing (see solid_mpm.h) and the APIC affine part of the kinetic
  // energy with the tents of the new cell.
  template <int dim>
  template <bool A>
  void
  SolidMPM<dim>::finish_points(const std::size_t p0, const unsigned int nl)
  {
    const double h = grid.h();
    for (unsigned int l = 0; l < nl; ++l)
      {
        const std::size_t p = p0 + l;
        // Kinetic energy and momentum (APIC: the affine part is added
        // after the cell crossing, with the tents of the new cell).
        double v2 = 0;
        for (int d = 0; d < dim; ++d)
          {
            v2 += v[d][p] * v[d][p];
            weight_momentum[d] += true_mass[p] * v[d][p];
          }

        // Cell crossing (see solid_mpm.h).
        bool inside = true;
        for (int d = 0; d < dim; ++d)
          inside =
            inside && x[d][p] >= corner[d][p] && x[d][p] <= corner[d][p] + h;
        if (!inside)
          {
            Point<dim> xp;
            for (int d = 0; d < dim; ++d)
              xp[d] = x[d][p];
            // With the melt flow, points that solidified as spatter (ejected
            // melt, moving with the fluid's velocity) can reach the domain's
            // faces; like the flow's points they are held there: put back on
            // the face, the outward velocity removed (its kinetic energy
            // leaves through the next transfer). Without the melt flow a
            // point leaving the domain stops the run.
            if (flow_owns_fluid && !grid.in_domain(xp))
              hold_in_domain(p, xp);
            auto ijk = grid.cell_of(xp);
            // A point that crossed a face of the FE zone by less than half
            // a point spacing is held on that face (see solid_mpm.h).
            const bool in_domain = grid.in_domain(xp);
            if (in_domain && grid.in_box(ijk) &&
                excluded[grid.local_index(ijk)] &&
                !hold_on_zone_face(p, xp, ijk))
              {
                if (!lost)
                  {
                    // How deep: the nearest way out at any distance.
                    const auto e = nearest_zone_exit(
                      xp, ijk, std::numeric_limits<double>::infinity());
                    escaped    = xp;
                    escaped_at = e.faces != 0 ?
                                   std::sqrt(e.distance2) :
                                   std::numeric_limits<double>::quiet_NaN();
                  }
                lost = true;
                continue;
              }
            if (!in_domain)
              {
                if (!lost)
                  escaped = xp, escaped_at = -1;
                lost = true;
                continue;
              }
            const auto idx = grid.in_box(ijk) ? grid.local_index(ijk) : 0;
            if (!grid.in_box(ijk) ||
                grid.cell_status()[idx] != BackgroundGrid<dim>::owned)
              {
                // Its old cell, where scatter() finds it to send it to the
                // neighbour rank.
                left_cells.push_back(cell[p]);
                left_rank_points.push_back(p);
                moved_cell = true;
                ++left_rank;
                continue;
              }
            if (idx != cell[p]) // not held back in its own cell
              {
                left_cells.push_back(cell[p]);
                cell[p]  = idx;
                node0[p] = grid.first_node_of_cell(idx);
                for (int d = 0; d < dim; ++d)
                  corner[d][p] = grid.origin()[d] + ijk[d] * h;
                moved_cell = true;
                mark_cell_nodes(idx, node0[p]);
              }
          }
        // APIC: affine part with the tents of the cell that now holds
        // the point (those of the next P2G). Points that left the rank
        // are counted by the gather of resort().
        if (A)
          add_affine_kinetic<dim>(x, corner, C, p, h, v2);
        kinetic += 0.5 * (true_mass[p] * scaling) * v2;
      }
  }

  template <int dim>
  double
  SolidMPM<dim>::elastic_energy(const std::vector<double> &T) const
  {
    double u = 0;
    double s[n_stress];
    for (std::size_t p = 0; p < true_mass.size(); ++p)
      {
        for (unsigned int c = 0; c < n_stress; ++c)
          s[c] = sigma[c][p];
        u += volume[p] * elastic_energy_density(mat, s, T[cell[p]]);
      }
    return u;
  }

  template <int dim>
  std::pair<double, unsigned int>
  SolidMPM<dim>::cell_stress_xx(const std::size_t idx) const
  {
    double       s = 0;
    unsigned int n = 0;
    for (std::size_t p = 0; p < true_mass.size(); ++p)
      if (cell[p] == idx)
        s += sigma[0][p], ++n;
    return {n > 0 ? s / n : 0., n};
  }

  template <int dim>
  void
  SolidMPM<dim>::add_cell_fields(std::vector<std::vector<double>> &f,
                                 std::vector<double>              &count) const
  {
    for (std::size_t p = 0; p < true_mass.size(); ++p)
      {
        SymmetricTensor<2, 3> s;
        for (unsigned int i = 0; i < 3; ++i)
          for (unsigned int j = i; j < 3; ++j)
            s[i][j] = sigma[sidx(i, j)][p];
        for (unsigned int i = 0; i < 3; ++i)
          f[i][cell[p]] += s[i][i];
        f[3][cell[p]] += von_mises(s);
        f[4][cell[p]] += eps_p[p];
        count[cell[p]] += 1;
      }
  }

  template <int dim>
  void
  SolidMPM<dim>::add_cell_state(const std::vector<std::uint8_t>    &mask,
                                std::vector<std::array<double, 8>> &sums) const
  {
    for (std::size_t p = 0; p < true_mass.size(); ++p)
      if (mask[cell[p]])
        {
          auto &a = sums[cell[p]];
          for (unsigned int c = 0; c < n_stress; ++c)
            a[c] += sigma[c][p];
          a[6] += eps_p[p];
          a[7] += 1;
        }
  }

  template <int dim>
  bool
  SolidMPM<dim>::find_non_finite(Point<dim> &where) const
  {
    for (std::size_t p = 0; p < true_mass.size(); ++p)
      {
        bool bad = false;
        for (unsigned int c = 0; c < n_stress; ++c)
          bad = bad || !std::isfinite(sigma[c][p]);
        for (int d = 0; d < dim; ++d)
          bad = bad || !std::isfinite(v[d][p]) || !std::isfinite(x[d][p]);
        if (bad)
          {
            for (int d = 0; d < dim; ++d)
              where[d] = corner[d][p] + 0.5 * grid.h();
            return true;
          }
      }
    return false;
  }

  template <int dim>
  bool
  SolidMPM<dim>::find_collapsed(Point<dim> &where, double &V) const
  {
    for (std::size_t p = 0; p < true_mass.size(); ++p)
      if (!(volume[p] > 0))
        {
          for (int d = 0; d < dim; ++d)
            where[d] = x[d][p];
          V = volume[p];
          return true;
        }
    return false;
  }

  template <int dim>
  void
  SolidMPM<dim>::load_state(std::vector<StateReader> &parts)
  {
    Store::load_state(parts);
    for (int d = 0; d < dim; ++d)
      xdot[d].clear();
    kinetic = 0;
    weight_momentum.fill(0.);
    lost      = false;
    left_rank = 0;
  }

  template class SolidMPM<2>;
  template class SolidMPM<3>;
} // namespace femp
