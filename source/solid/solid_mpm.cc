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
      : grid(grid)
      , mat(material)
      , points(points)
      , apic(material.velocity_transfer ==
             SolidMaterial::VelocityTransfer::apic)
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
    using P = typename MaterialPoints<dim>::PropertyIndex;
    const bool apic_now =
      mat.velocity_transfer == SolidMaterial::VelocityTransfer::apic;
    AssertThrow(points.n_properties() >= P::n_used(true, apic_now),
                ExcMessage("SolidMPM: the material points do not carry the "
                           "solid (or APIC) properties"));
    // The same members in the same pool slots and order as at the last
    // gather: nobody but write_back() has changed their state since (the
    // flow writes fluid points only, the temperature step their state,
    // which exchange_since_gather() checked), so the arrays are kept.
    const bool keep = same_members && gathered && apic_now == apic &&
                      excluded_cell == excluded && aside_changed.empty() &&
                      points.layout_unchanged(gathered_layout, cell);
    // Otherwise, the same handler layout (no re-sort or re-index): only the
    // cells whose points changed are read again.
    const bool merge =
      !keep && gathered && apic_now == apic && excluded_cell == excluded &&
      points.layout_mark().generation == gathered_layout.generation;
    apic = apic_now;
    if (!gathered || excluded_cell != excluded)
      {
        excluded = excluded_cell;
        set_exchange_cells();
      }
    scaling = mass_scaling;
    ++gathers;
    gather_aside_n = gather_aside_k = 0;
    left_cells.clear();
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
    if (keep)
      ++gathers_kept;
    else if (merge)
      {
        ++gathers_merged;
        merge_members();
#ifdef DEBUG
        // Debug builds: the merge must give what a full copy gives.
        {
          const auto xs = x, vs = v, cs = corner, ss = sigma;
          const auto Cs = C;
          const auto m = true_mass, vo = volume, vi = visc, e = eps_p;
          const auto ce = cell, no = node0;
          const auto ha = handle, mi = member_id;
          copy_members();
          Assert(xs == x && vs == v && cs == corner && Cs == C && ss == sigma &&
                   m == true_mass && vo == volume && vi == visc && e == eps_p &&
                   ce == cell && no == node0 && ha == handle && mi == member_id,
                 ExcMessage("the merged gather differs from a full copy"));
        }
#endif
      }
    else
      copy_members();
    for (const auto c : aside_changed)
      aside_changed_mark[c] = 0;
    aside_changed.clear();
    left_rank_points.clear();
    gathered        = true;
    gathered_layout = points.layout_mark();
    moved_cell = lost = false;
    left_rank         = 0;
    for (std::size_t p = 0; p < node0.size(); ++p)
      if (p == 0 || node0[p] != node0[p - 1])
        mark_cell_nodes(cell[p], node0[p]);
    sum_energies();
  }

  template <int dim>
  void
  SolidMPM<dim>::find_members(
    const std::size_t                                    c,
    std::vector<std::pair<unsigned int, std::uint32_t>> &out)
  {
    using P         = typename MaterialPoints<dim>::PropertyIndex;
    auto      &pool = points.particle_handler_for_update().get_property_pool();
    const auto handles           = points.cell_point_handles(c);
    const std::size_t     n_cell = handles.size();
    constexpr std::size_t ahead  = 16;
    // No stress, hardening memory, viscous pressure or affine velocity
    // (and, with @p velocity, no velocity): a point that left the solid.
    const auto clear_solid_state = [this](const ArrayView<double> &q,
                                          const bool               velocity) {
      for (unsigned int k = P::stress; k < P::stress + dim * (dim + 1) / 2; ++k)
        q[k] = 0;
      if (velocity)
        for (int d = 0; d < dim; ++d)
          q[P::velocity + d] = 0;
      q[P::plastic_strain]   = 0;
      q[P::viscous_pressure] = 0;
      if constexpr (dim == 2)
        q[P::stress_zz] = 0;
      if (apic)
        for (unsigned int k = 0; k < dim * dim; ++k)
          q[P::affine_velocity + k] = 0;
    };
    for (std::size_t i = 0; i < n_cell; ++i)
      {
        if (i + ahead < n_cell)
          {
            const auto hn = handles[i + ahead];
            __builtin_prefetch(pool.get_properties(hn).data() + P::state, 1);
            __builtin_prefetch(&pool.get_location(hn), 0);
          }
        const auto              hp = handles[i];
        const ArrayView<double> q  = pool.get_properties(hp);
        if (q[P::state] == MaterialPoints<dim>::fluid)
          {
            // Melted: no stress, no hardening memory, no momentum (without
            // the melt flow a melted point is at rest; its kinetic energy
            // was booked as removed by melting), so that it solidifies
            // again stress-free and at rest (doc/solid.md "Melting and
            // re-solidification"). With the flow, its velocity is the
            // flow's (doc/solid.md "Flow and solid together").
            clear_solid_state(q, !flow_owns_fluid);
          }
        if (q[P::state] != MaterialPoints<dim>::solid)
          continue;
        const auto idx = grid.local_index(grid.cell_of(pool.get_location(hp)));
        if (excluded[idx])
          continue;
        if (set_aside(idx))
          {
            // A detached drop (set_aside_cells()): at rest and
            // stress-free, out of the solid. A point still moving was
            // carried in by the solid since the last gather (points set
            // aside before are at rest): counted, with its kinetic
            // energy (inertial mass, APIC affine part), for resort().
            double v2 = 0;
            for (int d = 0; d < dim; ++d)
              v2 += q[P::velocity + d] * q[P::velocity + d];
            if (apic)
              {
                const auto  &xp  = pool.get_location(hp);
                const auto   ijk = grid.global_index(idx);
                const double h   = grid.h();
                for (int j = 0; j < dim; ++j)
                  {
                    const double xi = (xp[j] - grid.origin()[j]) / h - ijk[j];
                    for (int i = 0; i < dim; ++i)
                      v2 += q[P::affine_velocity + i * dim + j] *
                            q[P::affine_velocity + i * dim + j] * h * h * xi *
                            (1 - xi);
                  }
              }
            if (v2 > 0)
              gather_aside_n += 1,
                gather_aside_k += 0.5 * q[P::mass] * scaling * v2;
            clear_solid_state(q, true);
            continue;
          }
        out.emplace_back(hp, idx);
      }
  }

  template <int dim>
  void
  SolidMPM<dim>::set_aside_cells(const std::vector<std::uint32_t> &cells)
  {
    if (cells == aside_cells)
      return;
    if (aside.empty())
      {
        aside.assign(grid.n_local(), 0);
        aside_changed_mark.assign(grid.n_local(), 0);
      }
    const auto mark = [this](const std::uint32_t c) {
      if (!aside_changed_mark[c])
        aside_changed_mark[c] = 1, aside_changed.push_back(c);
    };
    for (const auto c : aside_cells)
      aside[c] = 0, mark(c);
    for (const auto c : cells)
      aside[c] = 1, mark(c);
    aside_cells = cells;
  }

  template <int dim>
  void
  SolidMPM<dim>::read_member(const std::size_t   p,
                             const unsigned int  hp,
                             const std::uint32_t idx)
  {
    using P    = typename MaterialPoints<dim>::PropertyIndex;
    auto &pool = points.particle_handler_for_update().get_property_pool();
    const ArrayView<const double> q   = pool.get_properties(hp);
    const Point<dim>             &xp  = pool.get_location(hp);
    const auto                    ijk = grid.global_index(idx);
    handle[p]                         = hp;
    cell[p]                           = idx;
    for (int d = 0; d < dim; ++d)
      {
        corner[d][p] = grid.origin()[d] + ijk[d] * grid.h();
        x[d][p]      = xp[d];
        v[d][p]      = q[P::velocity + d];
      }
    if (apic)
      for (unsigned int c = 0; c < dim * dim; ++c)
        C[c][p] = q[P::affine_velocity + c];
    true_mass[p] = q[P::mass];
    volume[p]    = q[P::volume];
    visc[p]      = q[P::viscous_pressure];
    node0[p]     = grid.first_node_of_cell(idx);
    if constexpr (dim == 2)
      {
        sigma[0][p] = q[P::stress + 0];
        sigma[1][p] = q[P::stress + 1];
        sigma[2][p] = q[P::stress_zz];
        sigma[3][p] = q[P::stress + 2];
        sigma[4][p] = 0.;
        sigma[5][p] = 0.;
      }
    else
      for (unsigned int c = 0; c < n_stress; ++c) // same order
        sigma[c][p] = q[P::stress + c];
    eps_p[p]      = q[P::plastic_strain];
    const auto id = pool.get_id(hp);
    member_id[p]  = id;
    if (id / 64 >= member_bits.size())
      member_bits.resize(id / 64 + 1, 0);
    member_bits[id / 64] |= std::uint64_t(1) << (id % 64);
  }

  namespace
  {
    /// Resizes every per-point array of @p arrays to @p n (the arrays
    /// filled by index: no zero fill needed, but resize() does it).
    template <typename... V>
    void
    resize_all(const std::size_t n, V &...arrays)
    {
      (arrays.resize(n), ...);
    }
  } // namespace

  template <int dim>
  void
  SolidMPM<dim>::copy_members()
  {
    // Cell by cell in increasing flat index, from MaterialPoints' per-cell
    // cache of pool handles, but the FE zone's deeper cells (neither
    // members nor fluid there, see exchange_cell): a first pass finds the
    // points that take part (pool handle, cell), the second copies their
    // state into the arrays, with prefetches ahead.
    const auto &occupied = points.occupied_cells();
    found.clear();
    found.reserve(points.particle_handler().n_locally_owned_particles());
    for (std::size_t c = 0; c < occupied.size(); ++c)
      if (exchange_cell.empty() || exchange_cell[occupied[c].first])
        find_members(c, found);
    const std::size_t n = found.size();
    for (int d = 0; d < dim; ++d)
      resize_all(n, x[d], v[d], corner[d]);
    for (auto &c : C)
      c.resize(apic ? n : 0);
    for (auto &s : sigma)
      s.resize(n);
    resize_all(
      n, true_mass, volume, visc, eps_p, cell, node0, handle, member_id);
    // Membership by particle id, for exchange_since_gather().
    member_bits.assign(
      points.particle_handler().get_next_free_particle_index() / 64 + 1, 0);
    auto &pool = points.particle_handler_for_update().get_property_pool();
    constexpr std::size_t ahead = 16;
    for (std::size_t p = 0; p < n; ++p)
      {
        if (p + ahead < n)
          {
            const auto    hn = found[p + ahead].first;
            const double *r  = pool.get_properties(hn).data();
            for (unsigned int c = 0; c < pool.n_properties_per_slot(); c += 8)
              __builtin_prefetch(r + c, 0);
            __builtin_prefetch(&pool.get_location(hn), 0);
          }
        read_member(p, found[p].first, found[p].second);
      }
  }

  template <int dim>
  void
  SolidMPM<dim>::merge_members()
  {
    // The members of the cells whose points neither came, went nor changed
    // state since the last gather (MaterialPoints::cell_changed_since())
    // are the same points in the same order, and the arrays hold their
    // state (written back by the last scatter(); handles are stable while
    // the handler is not re-indexed): they stay, unless the cell was set
    // aside or given back since (set_aside_cells()). The changed cells are
    // looked at as copy_members() would, and both are merged in increasing
    // cell index, the order of copy_members().
    const auto &occupied = points.occupied_cells();
    found.clear();
    for (std::size_t c = 0; c < occupied.size(); ++c)
      {
        const auto idx = occupied[c].first;
        if ((exchange_cell.empty() || exchange_cell[idx]) &&
            changed_since_gather(idx))
          find_members(c, found);
      }
    const std::size_t n_old = handle.size();
    merge_source.clear();
    merge_source.reserve(n_old + found.size());
    // Points that left for another rank: cell[] holds the last cell they
    // crossed into on this rank, which need not be a cell the relocation
    // changed (a point that moved A -> B here and then on to the other
    // rank was removed from A, where the handler still had it).
    std::sort(left_rank_points.begin(), left_rank_points.end());
    std::size_t l = 0;
    std::size_t j = 0;
    for (std::size_t p = 0; p < n_old; ++p)
      {
        const auto idx = cell[p];
        while (l < left_rank_points.size() && left_rank_points[l] < p)
          ++l;
        const bool left =
          l < left_rank_points.size() && left_rank_points[l] == p;
        if (left || changed_since_gather(idx))
          {
            // Dropped: read again below if still a member here.
            member_bits[member_id[p] / 64] &=
              ~(std::uint64_t(1) << (member_id[p] % 64));
            continue;
          }
        while (j < found.size() && found[j].second < idx)
          merge_source.push_back(~std::int64_t(j++));
        merge_source.push_back(std::int64_t(p));
      }
    while (j < found.size())
      merge_source.push_back(~std::int64_t(j++));
    const std::size_t n = merge_source.size();
    // The kept entries as runs of consecutive entries (most of them: only
    // the changed cells break them), copied run by run.
    struct Run
    {
      std::size_t to, from, length;
    };
    std::vector<Run> runs;
    for (std::size_t k = 0; k < n; ++k)
      if (merge_source[k] >= 0)
        {
          const auto from = static_cast<std::size_t>(merge_source[k]);
          if (!runs.empty() && runs.back().to + runs.back().length == k &&
              runs.back().from + runs.back().length == from)
            ++runs.back().length;
          else
            runs.push_back({k, from, 1});
        }
    // Field by field: the kept entries move to their new places.
    auto move_field = [&](auto &field) {
      using T   = typename std::decay_t<decltype(field)>::value_type;
      auto &out = [&]() -> std::vector<T> & {
        if constexpr (std::is_same_v<T, double>)
          return merge_buffer_double;
        else if constexpr (std::is_same_v<T, std::uint32_t>)
          return merge_buffer_u32;
        else
          return merge_buffer_index;
      }();
      out.resize(n);
      for (const auto &r : runs)
        std::copy(field.begin() + r.from,
                  field.begin() + r.from + r.length,
                  out.begin() + r.to);
      field.swap(out);
    };
    for (int d = 0; d < dim; ++d)
      move_field(x[d]), move_field(v[d]), move_field(corner[d]);
    if (apic)
      for (auto &c : C)
        move_field(c);
    for (auto &s : sigma)
      move_field(s);
    move_field(true_mass), move_field(volume), move_field(visc);
    move_field(eps_p), move_field(cell), move_field(node0);
    move_field(handle), move_field(member_id);
    for (std::size_t k = 0; k < n; ++k)
      if (merge_source[k] < 0)
        {
          const auto &f = found[~merge_source[k]];
          read_member(k, f.first, f.second);
        }
  }

  template <int dim>
  void
  SolidMPM<dim>::set_exchange_cells()
  {
    // Outside the FE zone, and the zone's cells with a neighbour (faces,
    // edges, corners) outside it or beyond the local box.
    exchange_cell.assign(grid.n_local(), 1);
    if (excluded.size() != grid.n_local())
      return;
    for (std::size_t idx = 0; idx < grid.n_local(); ++idx)
      {
        if (!excluded[idx])
          continue;
        const auto ijk  = grid.global_index(idx);
        bool       near = false;
        for (unsigned int k = 0; k < std::pow(3u, dim) && !near; ++k)
          {
            auto         nb = ijk;
            unsigned int r  = k;
            for (int d = 0; d < dim; ++d, r /= 3)
              nb[d] += int(r % 3) - 1;
            near = !grid.in_box(nb) || !excluded[grid.local_index(nb)];
          }
        exchange_cell[idx] = near;
      }
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
  typename SolidMPM<dim>::Exchange
  SolidMPM<dim>::exchange_since_gather() const
  {
    using P = typename MaterialPoints<dim>::PropertyIndex;
    Exchange   e;
    const auto h = grid.h(), ih = 1. / h;
    // Over the points of the cells outside the FE zone and its first
    // layer (exchange_cell; the zone's deeper points are solid, below the
    // solidus by the zone's guard, and never members), cell by cell from
    // MaterialPoints' cache, prefetching state and position.
    // At a gather every point is a member exactly when it is solid and
    // outside the excluded cells (a kept gather: the exchange found no
    // point for which this failed). A cell whose points neither changed
    // state nor came or went since (MaterialPoints::cell_changed_since())
    // keeps that, so only the others are looked at: in the cooling a few
    // cells where points solidify or members crossed a face, not every
    // point of the powder and the MPM zone.
    auto                 &pool = points.particle_handler().get_property_pool();
    const auto           &occupied = points.occupied_cells();
    constexpr std::size_t ahead    = 16;
    for (std::size_t c = 0; c < occupied.size(); ++c)
      {
        const auto idx = occupied[c].first;
        if (!exchange_cell.empty() && !exchange_cell[idx])
          continue;
        if (gathered && !changed_since_gather(idx))
          continue;
        const auto        handles = points.cell_point_handles(c);
        const std::size_t n_cell  = handles.size();
        for (std::size_t i = 0; i < n_cell; ++i)
          {
            if (i + ahead < n_cell)
              {
                const auto hn = handles[i + ahead];
                __builtin_prefetch(pool.get_properties(hn).data() + P::state,
                                   0);
                __builtin_prefetch(&pool.get_location(hn), 0);
              }
            const auto                    hp     = handles[i];
            const ArrayView<const double> q      = pool.get_properties(hp);
            const bool                    member = is_member(pool.get_id(hp));
            const bool solid = q[P::state] == MaterialPoints<dim>::solid;
            if (!member &&
                !solid) // (neither before nor now: the cell does not matter)
              continue;
            const Point<dim> xp   = pool.get_location(hp);
            const auto       ijk  = grid.cell_of(xp);
            const auto       cidx = grid.local_index(ijk);
            const bool       out  = excluded[cidx];
            const bool       away = set_aside(cidx);
            if (member == (solid && !out && !away))
              continue;
            if (member && solid && out) // now in a cell of the FE zone
              {
                if (e.n_lost == 0)
                  e.lost_at = xp;
                e.n_lost += 1;
                continue;
              }
            // Kinetic energy as the points had it in (or bring it to) the
            // solid: inertial mass, APIC affine part with the tents of the
            // cell.
            double v2 = 0;
            for (int d = 0; d < dim; ++d)
              v2 += q[P::velocity + d] * q[P::velocity + d];
            if (apic)
              for (int j = 0; j < dim; ++j)
                {
                  const double xi = (xp[j] - grid.origin()[j]) * ih - ijk[j];
                  const double D  = h * h * xi * (1 - xi);
                  for (int i = 0; i < dim; ++i)
                    v2 += q[P::affine_velocity + i * dim + j] *
                          q[P::affine_velocity + i * dim + j] * D;
                }
            const double k = 0.5 * q[P::mass] * scaling * v2;
            if (member && solid) // now in a detached drop
              e.n_set_aside += 1, e.k_set_aside += k;
            else if (member)
              e.n_melted += 1, e.k_melted += k;
            else
              e.n_solidified += 1, e.k_solidified += k;
          }
      }
    return e;
  }

  template <int dim>
  void
  SolidMPM<dim>::write_back()
  {
    using P    = typename MaterialPoints<dim>::PropertyIndex;
    auto &pool = points.particle_handler_for_update().get_property_pool();
    const std::size_t     n     = true_mass.size();
    constexpr std::size_t ahead = 8;
    for (std::size_t p = 0; p < n; ++p)
      {
        if (p + ahead < n) // the pool slots written a few points ahead
          {
            const auto hn = handle[p + ahead];
            double    *r  = pool.get_properties(hn).data();
            for (unsigned int c = 0; c < pool.n_properties_per_slot(); c += 8)
              __builtin_prefetch(r + c, 1);
            __builtin_prefetch(&pool.get_location(hn), 1);
          }
        const auto              hp = handle[p];
        const ArrayView<double> q  = pool.get_properties(hp);
        Point<dim>              xp;
        for (int d = 0; d < dim; ++d)
          {
            xp[d]              = x[d][p];
            q[P::velocity + d] = v[d][p];
          }
        pool.set_location(hp, xp);
        if constexpr (dim == 2)
          {
            q[P::stress + 0] = sigma[0][p];
            q[P::stress + 1] = sigma[1][p];
            q[P::stress + 2] = sigma[3][p];
            q[P::stress_zz]  = sigma[2][p];
          }
        else
          for (unsigned int c = 0; c < n_stress; ++c)
            q[P::stress + c] = sigma[c][p];
        if (apic)
          for (unsigned int c = 0; c < dim * dim; ++c)
            q[P::affine_velocity + c] = C[c][p];
        q[P::plastic_strain]   = eps_p[p];
        q[P::volume]           = volume[p];
        q[P::viscous_pressure] = visc[p];
      }
  }

  template <int dim>
  void
  SolidMPM<dim>::scatter()
  {
    write_back();
    // Points that changed cells: move them in the handler, to the owner
    // where the new cell is a ghost cell (cell by cell, looking only in the
    // cells they left; deal.II's global sort only if that fails).
    if (Utilities::MPI::logical_or(moved_cell, grid.communicator()))
      {
        std::sort(left_cells.begin(), left_cells.end());
        left_cells.erase(std::unique(left_cells.begin(), left_cells.end()),
                         left_cells.end());
        if (!points.relocate_points(&left_cells))
          points.points_moved();
      }
    left_cells.clear();
    moved_cell = false;
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
    scatter();
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
                           gravity};
    // The transfer and the floor are compile-time constants inside the
    // loop (measured: 7-20 % faster than a run-time branch per point).
    auto run = [&](auto transfer, auto floor) {
      constexpr bool A = decltype(transfer)::value;
      constexpr bool G = decltype(floor)::value;
      CellScatter<n_corners, 1 + 2 * dim + G, point_lanes<dim>> out(
        corner_offset, nodes_out);
      p2g_blocks<A, G>(in, 0, n, n, out);
    };
    if (apic && stiffness_rows)
      run(std::true_type(), std::true_type());
    else if (apic)
      run(std::true_type(), std::false_type());
    else if (stiffness_rows)
      run(std::false_type(), std::true_type());
    else
      run(std::false_type(), std::false_type());
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
    const StressStep<dim> st =
      stress_step<dim>(mat, vel, corner_offset, T_old, T_new, dt, h, scaling);
    CellModuli moduli = first_cell_moduli(mat, cell, n, T_old, T_new);
    // Fused P2G of the next step (see solid_mpm.h), into the buffer next:
    // from the second step after a gather on (the benchmark's and a coupled
    // run's sub-cycling), so that a run of one step per gather pays nothing
    // for it, nor a rank without points (no buffer). The buffer is zero
    // here (p2g() consumed or cleared it).
    const bool fuse = n > 0 && steps_since_gather > 0 && have_gravity;
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
    auto             loop = [&](auto transfer, auto fused, auto floor) {
      constexpr bool                             A = decltype(transfer)::value;
      constexpr bool                             F = decltype(fused)::value;
      constexpr bool                             G = decltype(floor)::value;
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
                             p2g_gravity};
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
              stress_block(st,
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
            p2g_blocks<A, G>(in, c0, c1, n, out);
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
    if (apic && fuse && stiffness_rows)
      loop(yes, yes, yes);
    else if (apic && fuse)
      loop(yes, yes, no);
    else if (apic)
      loop(yes, no, no);
    else if (fuse && stiffness_rows)
      loop(no, yes, yes);
    else if (fuse)
      loop(no, yes, no);
    else
      loop(no, no, no);
    next_ready = fuse && !lost && left_rank == 0;
    return work;
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
            const auto ijk = grid.cell_of(xp);
            if (!grid.in_domain(xp) ||
                (grid.in_box(ijk) && excluded[grid.local_index(ijk)]))
              {
                if (!lost)
                  escaped = xp;
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
            left_cells.push_back(cell[p]);
            cell[p]  = idx;
            node0[p] = grid.first_node_of_cell(idx);
            for (int d = 0; d < dim; ++d)
              corner[d][p] = grid.origin()[d] + ijk[d] * h;
            moved_cell = true;
            mark_cell_nodes(idx, node0[p]);
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
  SolidMPM<dim>::save_state(StateWriter &out) const
  {
    out.put(scaling);
    std::vector<std::uint64_t> ids; // sorted
    for (std::size_t w = 0; w < member_bits.size(); ++w)
      for (unsigned int b = 0; b < 64; ++b)
        if ((member_bits[w] >> b) & 1u)
          ids.push_back(64 * w + b);
    out.put_vector(ids);
    const std::size_t          n = true_mass.size();
    std::vector<std::uint64_t> keys(n);
    for (std::size_t p = 0; p < n; ++p)
      keys[p] = global_cell_number(grid, grid.global_index(cell[p]));
    out.put_vector(keys);
    for (const auto &s : sigma)
      out.put_vector(s);
    out.put_vector(eps_p);
  }

  template <int dim>
  void
  SolidMPM<dim>::load_state(std::vector<StateReader> &parts)
  {
    for (int d = 0; d < dim; ++d)
      x[d].clear(), v[d].clear(), corner[d].clear(), xdot[d].clear();
    for (auto &c : C)
      c.clear();
    for (auto &s : sigma)
      s.clear();
    true_mass.clear(), volume.clear(), visc.clear();
    eps_p.clear(), cell.clear(), node0.clear(), handle.clear();
    member_bits.clear();
    left_cells.clear();
    gathered       = false; // the next gather() copies
    const double h = grid.h();
    for (std::size_t f = 0; f < parts.size(); ++f)
      {
        StateReader &in = parts[f];
        const double s  = in.get<double>();
        if (f == 0)
          scaling = s;
        // The members of every part: the partition of the resumed run may
        // differ from the one that wrote them (another number of ranks, or
        // the same number with other cell costs), and only this rank's
        // points are ever looked up.
        const auto ids = in.get_vector<std::uint64_t>();
        for (const auto id : ids)
          {
            if (id / 64 >= member_bits.size())
              member_bits.resize(id / 64 + 1, 0);
            member_bits[id / 64] |= std::uint64_t(1) << (id % 64);
          }
        const auto keys = in.get_vector<std::uint64_t>();
        std::array<std::vector<double>, n_stress> sg;
        for (auto &c : sg)
          c = in.get_vector<double>();
        const auto ep = in.get_vector<double>();
        for (std::size_t p = 0; p < keys.size(); ++p)
          {
            const auto idx = owned_local_index(grid, keys[p]);
            if (idx < 0)
              continue;
            cell.push_back(idx);
            node0.push_back(grid.first_node_of_cell(idx));
            const auto ijk = grid.global_index(idx);
            for (int d = 0; d < dim; ++d)
              corner[d].push_back(grid.origin()[d] + ijk[d] * h);
            for (unsigned int c = 0; c < n_stress; ++c)
              sigma[c].push_back(sg[c][p]);
            eps_p.push_back(ep[p]);
          }
      }
    // Read before the next gather(): cell, stress and plastic strain; the
    // other arrays keep the common length, zero.
    const std::size_t n = cell.size();
    for (int d = 0; d < dim; ++d)
      x[d].assign(n, 0.), v[d].assign(n, 0.);
    if (apic)
      for (auto &c : C)
        c.assign(n, 0.);
    true_mass.assign(n, 0.), volume.assign(n, 0.), visc.assign(n, 0.);
    kinetic = 0;
    weight_momentum.fill(0.);
    moved_cell = lost = false;
    left_rank         = 0;
    left_rank_points.clear();
  }

  template class SolidMPM<2>;
  template class SolidMPM<3>;
} // namespace femp
