// femp: explicit MPM for the fusible solid, MUSL variant with FLIP or APIC
// velocity transfer (paper eqs. 11-13; see solid_mpm.h for the algorithm,
// the choice of variant and the cell-crossing rules).
#include <deal.II/base/mpi.h>

#include <femp/solid_mpm.h>

#include <algorithm>
#include <cmath>
#include <type_traits>

namespace femp
{
  namespace
  {
    /// Index of stress component (i, j) in {xx, yy, zz, xy, xz, yz}.
    constexpr unsigned int
    sidx(const unsigned int i, const unsigned int j)
    {
      return i == j ? i : 2 + i + j; // xy -> 3, xz -> 4, yz -> 5
    }

    /// Tent weights N and gradients dN of the 2^dim corners (corner a has
    /// bit d set when it is the upper node in direction d) at local
    /// coordinates xi, for cell size 1/ih.
    template <int dim>
    inline void
    tents(const double (&xi)[dim], const double ih, double (&N)[1 << dim],
          double (&dN)[1 << dim][dim])
    {
      double w[dim][2], g[2] = {-ih, ih};
      for (int d = 0; d < dim; ++d)
        w[d][0] = 1 - xi[d], w[d][1] = xi[d];
      for (unsigned int a = 0; a < (1u << dim); ++a)
        {
          const unsigned int b0 = a & 1, b1 = (a >> 1) & 1;
          if constexpr (dim == 2)
            {
              N[a]     = w[0][b0] * w[1][b1];
              dN[a][0] = g[b0] * w[1][b1];
              dN[a][1] = w[0][b0] * g[b1];
            }
          else
            {
              const unsigned int b2 = (a >> 2) & 1;
              const double       w12 = w[1][b1] * w[2][b2];
              N[a]     = w[0][b0] * w12;
              dN[a][0] = g[b0] * w12;
              dN[a][1] = w[0][b0] * g[b1] * w[2][b2];
              dN[a][2] = w[0][b0] * w[1][b1] * g[b2];
            }
        }
    }
  } // namespace


  template <int dim>
  SolidMPM<dim>::SolidMPM(const BackgroundGrid<dim> &grid,
                          const SolidMaterial &      material,
                          MaterialPoints<dim> &      points)
    : grid(grid)
    , mat(material)
    , points(points)
    , apic(material.velocity_transfer == SolidMaterial::VelocityTransfer::apic)
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
                        const double                     mass_scaling)
  {
    using P = typename MaterialPoints<dim>::PropertyIndex;
    apic     = mat.velocity_transfer == SolidMaterial::VelocityTransfer::apic;
    AssertThrow(points.n_properties() >=
                  P::n_used(true, apic),
                ExcMessage("SolidMPM: the material points do not carry the "
                           "solid (or APIC) properties"));
    excluded = excluded_cell;
    scaling  = mass_scaling;
    for (int d = 0; d < dim; ++d)
      x[d].clear(), v[d].clear(), corner[d].clear();
    for (auto &c : C)
      c.clear();
    for (auto &s : sigma)
      s.clear();
    mass.clear(), true_mass.clear(), volume.clear(), visc.clear();
    eps_p.clear(), cell.clear(), node0.clear(), handle.clear();
    auto &     handler = points.particle_handler();
    const auto h       = grid.h();
    {
      const std::size_t n = handler.n_locally_owned_particles();
      for (int d = 0; d < dim; ++d)
        x[d].reserve(n), v[d].reserve(n), corner[d].reserve(n);
      if (apic)
        for (auto &c : C)
          c.reserve(n);
      for (auto &s : sigma)
        s.reserve(n);
      mass.reserve(n), true_mass.reserve(n), volume.reserve(n), visc.reserve(n);
      eps_p.reserve(n), cell.reserve(n), node0.reserve(n), handle.reserve(n);
    }
    for (auto it = handler.begin(); it != handler.end(); ++it)
      {
        const ArrayView<double> q = it->get_properties();
        if (q[P::state] == MaterialPoints<dim>::fluid)
          {
            // Melted: no stress, no hardening memory, no affine velocity, so
            // that the point starts stress-free when it solidifies again.
            for (unsigned int c = P::stress; c < P::stress + dim * (dim + 1) / 2; ++c)
              q[c] = 0;
            q[P::plastic_strain]   = 0;
            q[P::viscous_pressure] = 0;
            if constexpr (dim == 2)
              q[P::stress_zz] = 0;
            if (apic)
              for (unsigned int c = 0; c < dim * dim; ++c)
                q[P::affine_velocity + c] = 0;
          }
        if (q[P::state] != MaterialPoints<dim>::solid)
          continue;
        const Point<dim> p   = it->get_location();
        const auto       ijk = grid.cell_of(p);
        const auto       idx = grid.local_index(ijk);
        if (excluded[idx])
          continue;
        for (int d = 0; d < dim; ++d)
          {
            x[d].push_back(p[d]);
            v[d].push_back(q[P::velocity + d]);
            corner[d].push_back(grid.origin()[d] + ijk[d] * h);
          }
        if (apic)
          for (unsigned int c = 0; c < dim * dim; ++c)
            C[c].push_back(q[P::affine_velocity + c]);
        true_mass.push_back(q[P::mass]);
        mass.push_back(q[P::mass] * mass_scaling);
        volume.push_back(q[P::volume]);
        visc.push_back(q[P::viscous_pressure]);
        cell.push_back(idx);
        node0.push_back(grid.first_node_of_cell(idx));
        if constexpr (dim == 2)
          {
            sigma[0].push_back(q[P::stress + 0]);
            sigma[1].push_back(q[P::stress + 1]);
            sigma[2].push_back(q[P::stress_zz]);
            sigma[3].push_back(q[P::stress + 2]);
            sigma[4].push_back(0.);
            sigma[5].push_back(0.);
          }
        else
          for (unsigned int c = 0; c < n_stress; ++c) // same order
            sigma[c].push_back(q[P::stress + c]);
        eps_p.push_back(q[P::plastic_strain]);
        handle.push_back(it);
      }
    moved_cell = lost = false;
    left_rank         = 0;
    sum_energies();
    member_ids.resize(handle.size());
    for (std::size_t p = 0; p < handle.size(); ++p)
      member_ids[p] = handle[p]->get_id();
    std::sort(member_ids.begin(), member_ids.end());
  }


  template <int dim>
  typename SolidMPM<dim>::Exchange
  SolidMPM<dim>::exchange_since_gather() const
  {
    using P = typename MaterialPoints<dim>::PropertyIndex;
    Exchange   e;
    const auto h = grid.h(), ih = 1. / h;
    for (const auto &particle : points.particle_handler())
      {
        const ArrayView<const double> q = particle.get_properties();
        const bool member = std::binary_search(member_ids.begin(),
                                               member_ids.end(),
                                               particle.get_id());
        const bool       solid = q[P::state] == MaterialPoints<dim>::solid;
        const Point<dim> xp    = particle.get_location();
        const auto       ijk   = grid.cell_of(xp);
        const bool       out   = excluded[grid.local_index(ijk)];
        if (member == (solid && !out))
          continue;
        if (member && solid) // now in a cell of the FE zone
          {
            if (e.n_lost == 0)
              e.lost_at = xp;
            e.n_lost += 1;
            continue;
          }
        // Kinetic energy as the points had it in (or bring it to) the
        // solid: inertial mass, APIC affine part with the tents of the cell.
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
        if (member)
          e.n_melted += 1, e.k_melted += k;
        else
          e.n_solidified += 1, e.k_solidified += k;
      }
    return e;
  }


  template <int dim>
  void
  SolidMPM<dim>::write_back()
  {
    using P = typename MaterialPoints<dim>::PropertyIndex;
    for (std::size_t p = 0; p < mass.size(); ++p)
      {
        auto                    it = handle[p];
        const ArrayView<double> q  = it->get_properties();
        Point<dim>              xp;
        for (int d = 0; d < dim; ++d)
          {
            xp[d]              = x[d][p];
            q[P::velocity + d] = v[d][p];
          }
        it->set_location(xp);
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
    // Points bound to new cells of this rank: move them in the handler
    // (cell by cell; deal.II's global sort only if that fails).
    if (Utilities::MPI::logical_or(moved_cell, grid.communicator()))
      if (!points.relocate_points())
        points.points_moved();
    moved_cell = false;
  }


  template <int dim>
  void
  SolidMPM<dim>::resort()
  {
    write_back();
    points.points_moved();
    const std::vector<std::uint8_t> mask = excluded;
    gather(mask, scaling);
  }


  template <int dim>
  void
  SolidMPM<dim>::sum_energies()
  {
    const double h = grid.h(), ih = 1. / h;
    kinetic        = 0;
    weight_momentum.fill(0.);
    for (std::size_t p = 0; p < mass.size(); ++p)
      {
        double v2 = 0;
        for (int d = 0; d < dim; ++d)
          {
            v2 += v[d][p] * v[d][p];
            weight_momentum[d] += true_mass[p] * v[d][p];
          }
        if (apic)
          for (int j = 0; j < dim; ++j)
            {
              const double xi = (x[j][p] - corner[j][p]) * ih;
              const double D  = h * h * xi * (1 - xi);
              for (int i = 0; i < dim; ++i)
                v2 += C[i * dim + j][p] * C[i * dim + j][p] * D;
            }
        kinetic += 0.5 * mass[p] * v2;
      }
  }


  template <int dim>
  void
  SolidMPM<dim>::p2g(SolidNodeFields<dim> &nodes,
                     const Tensor<1, dim> &gravity) const
  {
    const double h = grid.h(), ih = 1. / h;
    double *     nm = nodes.mass.data();
    double *     mom[dim], *frc[dim];
    for (int d = 0; d < dim; ++d)
      mom[d] = nodes.momentum[d].data(), frc[d] = nodes.force[d].data();
    const std::size_t n = mass.size();
    // The transfer is a compile-time constant inside the loop (measured:
    // 7-20 % faster than a run-time branch per point).
    auto loop = [&](auto transfer) {
      constexpr bool A = decltype(transfer)::value;
    for (std::size_t p = 0; p < n; ++p)
      {
        double xi[dim], N[n_corners], dN[n_corners][dim];
        for (int d = 0; d < dim; ++d)
          xi[d] = (x[d][p] - corner[d][p]) * ih;
        tents<dim>(xi, ih, N, dN);
        const double m = mass[p], V = volume[p], mg = true_mass[p];
        double       Vs[dim][dim], g[dim], v0[dim], Ch[dim][dim];
        for (int i = 0; i < dim; ++i)
          {
            for (int j = 0; j < dim; ++j)
              Vs[i][j] = V * sigma[sidx(i, j)][p];
            Vs[i][i] += V * visc[p];
            g[i]  = mg * gravity[i];
            v0[i] = v[i][p];
            for (int j = 0; j < dim; ++j)
              Ch[i][j] = 0;
          }
        // APIC: v_p(x_I) = v_p + C_p (x_I - x_p), x_I - x_p = h (b - xi).
        if constexpr (A)
          for (int i = 0; i < dim; ++i)
            for (int j = 0; j < dim; ++j)
              {
                Ch[i][j] = h * C[i * dim + j][p];
                v0[i] -= Ch[i][j] * xi[j];
              }
        const std::size_t n0 = node0[p];
        for (unsigned int a = 0; a < n_corners; ++a)
          {
            const std::size_t I  = n0 + corner_offset[a];
            const double      mN = m * N[a];
            nm[I] += mN;
            for (int i = 0; i < dim; ++i)
              {
                double va = v0[i];
                for (int j = 0; j < dim; ++j)
                  if ((a >> j) & 1)
                    va += Ch[i][j];
                double f = g[i] * N[a];
                for (int j = 0; j < dim; ++j)
                  f -= Vs[i][j] * dN[a][j];
                mom[i][I] += mN * va;
                frc[i][I] += f;
              }
          }
      }
    };
    if (apic)
      loop(std::true_type());
    else
      loop(std::false_type());
  }


  template <int dim>
  void
  SolidMPM<dim>::g2p(SolidNodeFields<dim> &nodes, const double dt)
  {
    const double  h = grid.h(), ih = 1. / h;
    const double *vel[dim], *acc[dim];
    double *      mom[dim];
    for (int d = 0; d < dim; ++d)
      {
        vel[d] = nodes.velocity[d].data();
        acc[d] = nodes.force[d].data(); // f_I / m_I at this point
        mom[d] = nodes.momentum[d].data();
      }
    const std::size_t n = mass.size();
    for (int d = 0; d < dim; ++d)
      xdot[d].resize(n);
    // The transfer is a compile-time constant inside the loop (measured:
    // 7-20 % faster than a run-time branch per point).
    auto loop = [&](auto transfer) {
      constexpr bool A = decltype(transfer)::value;
    for (std::size_t p = 0; p < n; ++p)
      {
        double xi[dim], N[n_corners], dN[n_corners][dim];
        for (int d = 0; d < dim; ++d)
          xi[d] = (x[d][p] - corner[d][p]) * ih;
        tents<dim>(xi, ih, N, dN);
        const std::size_t n0 = node0[p];
        double            vg[dim] = {}, ag[dim] = {}, Cn[dim][dim] = {};
        for (unsigned int a = 0; a < n_corners; ++a)
          {
            const std::size_t I = n0 + corner_offset[a];
            for (int i = 0; i < dim; ++i)
              {
                const double vi = vel[i][I];
                vg[i] += N[a] * vi;
                if constexpr (A)
                  for (int j = 0; j < dim; ++j)
                    Cn[i][j] += vi * dN[a][j];
                else
                  ag[i] += N[a] * acc[i][I];
              }
          }
        // New velocity and affine matrix; the grid velocity at the point
        // moves it at the end of the step (update_stresses()).
        double vp[dim];
        for (int i = 0; i < dim; ++i)
          {
            vp[i] = apic ? vg[i] : v[i][p] + dt * ag[i];
            v[i][p] = vp[i];
            xdot[i][p] = vg[i];
          }
        // Re-map (MUSL) of the new momentum with the weights of the step
        // (those of the P2G, so that the re-mapped nodal velocity of a node
        // is a mean of point velocities with the node mass).
        const double m = mass[p];
        double       v0[dim], Ch[dim][dim];
        for (int i = 0; i < dim; ++i)
          v0[i] = vp[i];
        if constexpr (A)
          for (int i = 0; i < dim; ++i)
            for (int j = 0; j < dim; ++j)
              {
                C[i * dim + j][p] = Cn[i][j];
                Ch[i][j]          = h * Cn[i][j];
                v0[i] -= Ch[i][j] * xi[j];
              }
        for (unsigned int a = 0; a < n_corners; ++a)
          {
            const std::size_t I  = n0 + corner_offset[a];
            const double      mN = m * N[a];
            for (int i = 0; i < dim; ++i)
              {
                double va = v0[i];
                if constexpr (A)
                  for (int j = 0; j < dim; ++j)
                    if ((a >> j) & 1)
                      va += Ch[i][j];
                mom[i][I] += mN * va;
              }
          }
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
                                 const std::vector<double> & T_old,
                                 const std::vector<double> & T_new)
  {
    const double  b1 = mat.bulk_viscosity, h = grid.h(), ih = 1. / h;
    const double *vel[dim];
    for (int d = 0; d < dim; ++d)
      vel[d] = nodes.velocity[d].data();
    double            work = 0;
    const std::size_t n    = mass.size();
    left_rank              = 0;
    lost                   = false;
    kinetic                = 0;
    weight_momentum.fill(0.);
    const double nu     = mat.poisson_ratio;
    auto         E_cell = cell.empty() ? 0 : cell[0];
    double       E      = n > 0 ? mat.youngs_modulus.value(T_new[E_cell]) : 0.;
    for (std::size_t p = 0; p < n; ++p)
      {
        double xi[dim], N[n_corners], dN[n_corners][dim];
        for (int d = 0; d < dim; ++d)
          xi[d] = (x[d][p] - corner[d][p]) * ih;
        tents<dim>(xi, ih, N, dN);
        double            L[3][3] = {};
        const std::size_t n0      = node0[p];
        for (unsigned int a = 0; a < n_corners; ++a)
          {
            const std::size_t I = n0 + corner_offset[a];
            for (int i = 0; i < dim; ++i)
              {
                const double vi = vel[i][I] * dt;
                for (int j = 0; j < dim; ++j)
                  L[i][j] += vi * dN[a][j];
              }
          }
        double s[n_stress], s_old[n_stress];
        for (unsigned int c = 0; c < n_stress; ++c)
          s[c] = s_old[c] = sigma[c][p];
        // E(T) per cell: the points are sorted by cell, so the table is
        // read once per cell run (kernel and viscous pressure share it).
        const auto   cp = cell[p];
        const double Tn = T_new[cp];
        if (cp != E_cell)
          E_cell = cp, E = mat.youngs_modulus.value(Tn);
        update_stress_array(mat, L, T_old[cp], Tn, E, s, eps_p[p]);
        for (unsigned int c = 0; c < n_stress; ++c)
          sigma[c][p] = s[c];
        // Stress work of the step, sum (sigma_old + sigma_new)/2 : D dt
        // (in-plane components; plane strain has no zz strain).
        double w = 0, trL = 0;
        for (int i = 0; i < dim; ++i)
          {
            trL += L[i][i];
            for (int j = 0; j < dim; ++j)
              w += (s_old[sidx(i, j)] + s[sidx(i, j)]) * L[i][j];
          }
        // Viscous pressure of the forces of this step, then the new one.
        const double V = volume[p];
        work += 0.5 * V * w + V * visc[p] * trL;
        if (b1 > 0)
          visc[p] =
            b1 * h * std::sqrt(E * (1 - nu) / ((1 + nu) * (1 - 2 * nu)) * mass[p] / V) *
            trL / dt;
        volume[p] = V * (1 + trL);

        // Move the point with the grid velocity of the step; kinetic energy
        // (APIC: with the affine part at the new position) and momentum.
        double v2 = 0;
        for (int d = 0; d < dim; ++d)
          {
            x[d][p] += dt * xdot[d][p];
            v2 += v[d][p] * v[d][p];
            weight_momentum[d] += true_mass[p] * v[d][p];
          }

        // Cell crossing (see solid_mpm.h).
        bool inside = true;
        for (int d = 0; d < dim; ++d)
          inside = inside && x[d][p] >= corner[d][p] && x[d][p] <= corner[d][p] + h;
        if (!inside)
          {
            Point<dim> xp;
            for (int d = 0; d < dim; ++d)
              xp[d] = x[d][p];
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
                ++left_rank;
                continue;
              }
            cell[p]  = idx;
            node0[p] = grid.first_node_of_cell(idx);
            for (int d = 0; d < dim; ++d)
              corner[d][p] = grid.origin()[d] + ijk[d] * h;
            moved_cell = true;
          }
        // APIC: affine part with the tents of the cell that now holds the
        // point (those of the next P2G). Points that left the rank are
        // counted by the gather of resort().
        if (apic)
          for (int j = 0; j < dim; ++j)
            {
              const double xj = (x[j][p] - corner[j][p]) * ih;
              const double D  = h * h * xj * (1 - xj);
              for (int i = 0; i < dim; ++i)
                v2 += C[i * dim + j][p] * C[i * dim + j][p] * D;
            }
        kinetic += 0.5 * mass[p] * v2;
      }
    return work;
  }


  template <int dim>
  std::pair<double, unsigned int>
  SolidMPM<dim>::cell_stress_xx(const std::size_t idx) const
  {
    double       s = 0;
    unsigned int n = 0;
    for (std::size_t p = 0; p < mass.size(); ++p)
      if (cell[p] == idx)
        s += sigma[0][p], ++n;
    return {n > 0 ? s / n : 0., n};
  }


  template <int dim>
  void
  SolidMPM<dim>::add_cell_stresses(std::vector<double> &sxx,
                                   std::vector<double> &vm,
                                   std::vector<double> &count) const
  {
    for (std::size_t p = 0; p < mass.size(); ++p)
      {
        SymmetricTensor<2, 3> s;
        for (unsigned int i = 0; i < 3; ++i)
          for (unsigned int j = i; j < 3; ++j)
            s[i][j] = sigma[sidx(i, j)][p];
        sxx[cell[p]] += sigma[0][p];
        vm[cell[p]] += von_mises(s);
        count[cell[p]] += 1;
      }
  }


  template <int dim>
  bool
  SolidMPM<dim>::find_non_finite(Point<dim> &where) const
  {
    for (std::size_t p = 0; p < mass.size(); ++p)
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


  template class SolidMPM<2>;
  template class SolidMPM<3>;
} // namespace femp
