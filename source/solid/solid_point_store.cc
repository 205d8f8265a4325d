// femp: the solid points of the material point method as flat arrays:
// gather (full copy, kept, or merged where cells changed), write-back and
// relocation, the exchange with the melt by particle id, detached drops set
// aside, and the checkpoint of the members (see solid_point_store.h).
#include <deal.II/base/mpi.h>

#include <femp/grid/cell_state.h>
#include <femp/solid/solid_point_store.h>

#include <algorithm>
#include <cmath>
#include <type_traits>

namespace femp
{
  template <int dim>
  SolidPointStore<dim>::SolidPointStore(const BackgroundGrid<dim> &grid,
                                        const SolidMaterial       &material,
                                        MaterialPoints<dim>       &points)
      : grid(grid)
      , mat(material)
      , points(points)
      , apic(material.velocity_transfer ==
             SolidMaterial::VelocityTransfer::apic)
  {
  }

  template <int dim>
  void
  SolidPointStore<dim>::gather_members(
    const std::vector<std::uint8_t> &excluded_cell,
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
    moved_cell      = false;
  }

  template <int dim>
  void
  SolidPointStore<dim>::find_members(
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
      if (apic && (velocity || !flow_affine))
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
  SolidPointStore<dim>::set_aside_cells(const std::vector<std::uint32_t> &cells)
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
  SolidPointStore<dim>::read_member(const std::size_t   p,
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
  SolidPointStore<dim>::copy_members()
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
  SolidPointStore<dim>::merge_members()
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
  SolidPointStore<dim>::set_exchange_cells()
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
  std::array<double, dim + 3>
  SolidPointStore<dim>::fastest_member() const
  {
    std::array<double, dim + 3> r;
    r.fill(0.);
    r[0]                      = -1;
    const std::size_t n       = true_mass.size();
    std::size_t       best    = n;
    double            v2_best = -1;
    for (std::size_t p = 0; p < n; ++p)
      {
        double v2 = 0;
        for (int d = 0; d < dim; ++d)
          v2 += v[d][p] * v[d][p];
        if (v2 > v2_best)
          v2_best = v2, best = p;
      }
    if (best == n)
      return r;
    r[0] = std::sqrt(v2_best);
    for (int d = 0; d < dim; ++d)
      r[1 + d] = x[d][best];
    // The members share the cell index of the best one (any order).
    double m = 0, count = 0;
    for (std::size_t p = 0; p < n; ++p)
      if (cell[p] == cell[best])
        m += true_mass[p], count += 1;
    r[1 + dim] = count;
    r[2 + dim] = m / (mat.density() * std::pow(grid.h(), dim));
    return r;
  }

  template <int dim>
  typename SolidPointStore<dim>::Exchange
  SolidPointStore<dim>::exchange_since_gather() const
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
            if (!member && solid && !out && away)
              {
                // Set aside: at rest once a gather has seen it there.
                bool moving = false;
                for (int d = 0; d < dim; ++d)
                  moving = moving || q[P::velocity + d] != 0;
                if (apic)
                  for (unsigned int k = 0; k < dim * dim; ++k)
                    moving = moving || q[P::affine_velocity + k] != 0;
                if (moving)
                  e.n_stopped += 1;
                continue;
              }
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
            const double speed = std::sqrt(v2);
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
              {
                e.n_solidified += 1, e.k_solidified += k;
                e.v_solidified = std::max(e.v_solidified, speed);
              }
          }
      }
    return e;
  }

  template <int dim>
  void
  SolidPointStore<dim>::write_back()
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
  SolidPointStore<dim>::scatter()
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
  SolidPointStore<dim>::save_state(StateWriter &out) const
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
  SolidPointStore<dim>::load_state(std::vector<StateReader> &parts)
  {
    for (int d = 0; d < dim; ++d)
      x[d].clear(), v[d].clear(), corner[d].clear();
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
    moved_cell = false;
    left_rank_points.clear();
  }

  template class SolidPointStore<2>;
  template class SolidPointStore<3>;
} // namespace femp
