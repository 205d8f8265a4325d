// femp: explicit MPM for the fusible solid, MUSL variant (paper eqs. 11-13;
// see solid_mpm.h for the algorithm and the choice of variant).
#include <femp/solid_mpm.h>

#include <cmath>

namespace femp
{
  namespace
  {
    constexpr unsigned int
    voigt_3(const unsigned int i, const unsigned int j)
    {
      return i == j ? i : 3 + i + j - 1; // xy -> 3, xz -> 4, yz -> 5
    }
  } // namespace


  template <int dim>
  SolidMPM<dim>::SolidMPM(const BackgroundGrid<dim> &grid,
                          const SolidMaterial &      material,
                          MaterialPoints<dim> &      points)
    : grid(grid)
    , mat(material)
    , points(points)
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
    x.clear(), v.clear(), corner.clear(), mass.clear(), true_mass.clear();
    volume.clear(), visc.clear(), cell.clear(), node0.clear(), stress.clear(), handle.clear();
    auto &     handler = points.particle_handler();
    const auto h       = grid.h();
    for (auto it = handler.begin(); it != handler.end(); ++it)
      {
        const ArrayView<double> q = it->get_properties();
        if (q[P::state] == MaterialPoints<dim>::fluid)
          {
            // Melted: no stress and no hardening memory, so that the point
            // starts stress-free when it solidifies again.
            for (unsigned int c = P::stress; c < P::stress + dim * (dim + 1) / 2; ++c)
              q[c] = 0;
            q[P::plastic_strain]   = 0;
            q[P::viscous_pressure] = 0;
            if constexpr (dim == 2)
              q[P::stress_zz] = 0;
          }
        if (q[P::state] != MaterialPoints<dim>::solid)
          continue;
        const Point<dim> p   = it->get_location();
        const auto       ijk = grid.cell_of(p);
        const auto       idx = grid.local_index(ijk);
        if (excluded_cell[idx])
          continue;
        std::array<double, dim> xp, vp, c;
        for (int d = 0; d < dim; ++d)
          {
            xp[d] = p[d];
            vp[d] = q[P::velocity + d];
            c[d]  = grid.origin()[d] + ijk[d] * h;
          }
        x.push_back(xp), v.push_back(vp), corner.push_back(c);
        true_mass.push_back(q[P::mass]);
        mass.push_back(q[P::mass] * mass_scaling);
        volume.push_back(q[P::volume]);
        visc.push_back(q[P::viscous_pressure]);
        cell.push_back(idx);
        node0.push_back(grid.first_node_of_cell(idx));
        StressPoint s;
        if (dim == 2)
          {
            s.sigma[0][0] = q[P::stress + 0];
            s.sigma[1][1] = q[P::stress + 1];
            s.sigma[0][1] = q[P::stress + 2];
            s.sigma[2][2] = q[P::stress_zz];
          }
        else
          for (unsigned int i = 0; i < 3; ++i)
            for (unsigned int j = i; j < 3; ++j)
              s.sigma[i][j] = q[P::stress + voigt_3(i, j)];
        s.eps_p = q[P::plastic_strain];
        stress.push_back(s);
        handle.push_back(it);
      }
  }


  template <int dim>
  void
  SolidMPM<dim>::scatter()
  {
    using P = typename MaterialPoints<dim>::PropertyIndex;
    for (std::size_t p = 0; p < mass.size(); ++p)
      {
        auto                    it = handle[p];
        const ArrayView<double> q  = it->get_properties();
        Point<dim>              xp;
        for (int d = 0; d < dim; ++d)
          {
            xp[d]              = x[p][d];
            q[P::velocity + d] = v[p][d];
          }
        it->set_location(xp);
        const auto &s = stress[p].sigma;
        if (dim == 2)
          {
            q[P::stress + 0] = s[0][0];
            q[P::stress + 1] = s[1][1];
            q[P::stress + 2] = s[0][1];
            q[P::stress_zz]  = s[2][2];
          }
        else
          for (unsigned int i = 0; i < 3; ++i)
            for (unsigned int j = i; j < 3; ++j)
              q[P::stress + voigt_3(i, j)] = s[i][j];
        q[P::plastic_strain] = stress[p].eps_p;
        q[P::volume]         = volume[p];
        q[P::viscous_pressure] = visc[p];
      }
  }


  template <int dim>
  inline void
  SolidMPM<dim>::shape(const std::size_t p, double *N, double (*dN)[dim]) const
  {
    const double ih = 1. / grid.h();
    double       xi[dim], w[dim][2], g[dim][2];
    for (int d = 0; d < dim; ++d)
      {
        xi[d]   = (x[p][d] - corner[p][d]) * ih;
        w[d][0] = 1 - xi[d], w[d][1] = xi[d];
        g[d][0] = -ih, g[d][1] = ih;
      }
    for (unsigned int a = 0; a < n_corners; ++a)
      {
        const unsigned int b0 = a & 1, b1 = (a >> 1) & 1;
        if constexpr (dim == 2)
          {
            N[a]     = w[0][b0] * w[1][b1];
            dN[a][0] = g[0][b0] * w[1][b1];
            dN[a][1] = w[0][b0] * g[1][b1];
          }
        else
          {
            const unsigned int b2 = (a >> 2) & 1;
            N[a]     = w[0][b0] * w[1][b1] * w[2][b2];
            dN[a][0] = g[0][b0] * w[1][b1] * w[2][b2];
            dN[a][1] = w[0][b0] * g[1][b1] * w[2][b2];
            dN[a][2] = w[0][b0] * w[1][b1] * g[2][b2];
          }
      }
  }


  template <int dim>
  void
  SolidMPM<dim>::p2g(SolidNodeFields<dim> &nodes,
                     const Tensor<1, dim> &gravity) const
  {
    double N[n_corners], dN[n_corners][dim];
    for (std::size_t p = 0; p < mass.size(); ++p)
      {
        shape(p, N, dN);
        const auto & s  = stress[p].sigma;
        const double V  = volume[p];
        const double m  = mass[p];
        const double mg = true_mass[p];
        const double qv = visc[p];
        for (unsigned int a = 0; a < n_corners; ++a)
          {
            const std::size_t I = node0[p] + corner_offset[a];
            nodes.mass[I] += N[a] * m;
            for (int i = 0; i < dim; ++i)
              {
                double f = mg * gravity[i] * N[a] - V * qv * dN[a][i];
                for (int j = 0; j < dim; ++j)
                  f -= V * s[i][j] * dN[a][j];
                nodes.momentum[i][I] += N[a] * m * v[p][i];
                nodes.force[i][I] += f;
              }
          }
      }
  }


  template <int dim>
  bool
  SolidMPM<dim>::g2p(const SolidNodeFields<dim> &nodes, const double dt)
  {
    double     N[n_corners], dN[n_corners][dim];
    bool       ok = true;
    const double h = grid.h();
    for (std::size_t p = 0; p < mass.size(); ++p)
      {
        shape(p, N, dN);
        double pic[dim];
        for (int i = 0; i < dim; ++i)
          pic[i] = 0;
        for (unsigned int a = 0; a < n_corners; ++a)
          {
            const std::size_t I = node0[p] + corner_offset[a];
            for (int i = 0; i < dim; ++i)
              {
                v[p][i] += dt * N[a] * nodes.force[i][I]; // force = f/m here
                pic[i] += N[a] * nodes.velocity[i][I];
              }
          }
        for (int i = 0; i < dim; ++i)
          {
            x[p][i] += dt * pic[i];
          }
        for (int d = 0; d < dim; ++d)
          if (!(x[p][d] >= corner[p][d] && x[p][d] <= corner[p][d] + h))
            {
              if (ok)
                for (int e = 0; e < dim; ++e)
                  escaped[e] = x[p][e];
              ok = false;
            }
      }
    return ok;
  }


  template <int dim>
  void
  SolidMPM<dim>::p2g_momentum(SolidNodeFields<dim> &nodes) const
  {
    double N[n_corners], dN[n_corners][dim];
    for (std::size_t p = 0; p < mass.size(); ++p)
      {
        shape(p, N, dN);
        for (unsigned int a = 0; a < n_corners; ++a)
          {
            const std::size_t I = node0[p] + corner_offset[a];
            for (int i = 0; i < dim; ++i)
              nodes.momentum[i][I] += N[a] * mass[p] * v[p][i];
          }
      }
  }


  template <int dim>
  double
  SolidMPM<dim>::update_stresses(const SolidNodeFields<dim> &nodes,
                                 const double                dt,
                                 const std::vector<double> & T_old,
                                 const std::vector<double> & T_new)
  {
    double       N[n_corners], dN[n_corners][dim];
    double       work = 0;
    const double b1   = mat.bulk_viscosity, h = grid.h();
    for (std::size_t p = 0; p < mass.size(); ++p)
      {
        shape(p, N, dN);
        Tensor<2, 3> L;
        for (unsigned int a = 0; a < n_corners; ++a)
          {
            const std::size_t I = node0[p] + corner_offset[a];
            for (int i = 0; i < dim; ++i)
              {
                const double vi = nodes.velocity[i][I] * dt;
                for (int j = 0; j < dim; ++j)
                  L[i][j] += vi * dN[a][j];
              }
          }
        const SymmetricTensor<2, 3> s_old = stress[p].sigma;
        update_stress(mat, L, T_old[cell[p]], T_new[cell[p]], stress[p]);
        double w = 0;
        for (int i = 0; i < dim; ++i)
          for (int j = 0; j < dim; ++j)
            w += (s_old[i][j] + stress[p].sigma[i][j]) * L[i][j];
        double trL = 0;
        for (int i = 0; i < dim; ++i)
          trL += L[i][i];
        // Viscous pressure of the forces of this step, then the new one.
        work += 0.5 * volume[p] * w + volume[p] * visc[p] * trL;
        if (b1 > 0)
          visc[p] = b1 * h * std::sqrt(mat.p_wave_modulus(T_new[cell[p]]) *
                                       mass[p] / volume[p]) *
                    trL / dt;
        volume[p] *= 1 + trL;
      }
    return work;
  }


  template <int dim>
  double
  SolidMPM<dim>::kinetic_energy() const
  {
    double k = 0;
    for (std::size_t p = 0; p < mass.size(); ++p)
      {
        double v2 = 0;
        for (int d = 0; d < dim; ++d)
          v2 += v[p][d] * v[p][d];
        k += 0.5 * mass[p] * v2;
      }
    return k;
  }


  template <int dim>
  double
  SolidMPM<dim>::gravity_power(const Tensor<1, dim> &gravity) const
  {
    double w = 0;
    for (std::size_t p = 0; p < mass.size(); ++p)
      for (int d = 0; d < dim; ++d)
        w += true_mass[p] * gravity[d] * v[p][d];
    return w;
  }


  template <int dim>
  std::pair<double, unsigned int>
  SolidMPM<dim>::cell_stress_xx(const std::size_t idx) const
  {
    double       s = 0;
    unsigned int n = 0;
    for (std::size_t p = 0; p < mass.size(); ++p)
      if (cell[p] == idx)
        s += stress[p].sigma[0][0], ++n;
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
        sxx[cell[p]] += stress[p].sigma[0][0];
        vm[cell[p]] += von_mises(stress[p].sigma);
        count[cell[p]] += 1;
      }
  }


  template <int dim>
  bool
  SolidMPM<dim>::find_non_finite(Point<dim> &where) const
  {
    for (std::size_t p = 0; p < mass.size(); ++p)
      {
        bool bad = !std::isfinite(stress[p].sigma.norm());
        for (int d = 0; d < dim; ++d)
          bad = bad || !std::isfinite(v[p][d]) || !std::isfinite(x[p][d]);
        if (bad)
          {
            for (int d = 0; d < dim; ++d)
              where[d] = corner[p][d] + 0.5 * grid.h();
            return true;
          }
      }
    return false;
  }


  template class SolidMPM<2>;
  template class SolidMPM<3>;
} // namespace femp
