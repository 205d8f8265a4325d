// femp: explicit finite elements of the constant-solid zone (paper eqs.
// 6-10): one-point hexahedra/quadrilaterals with Flanagan-Belytschko
// hourglass forces and lumped mass; see solid_fem.h.
#include <femp/input_checks.h>
#include <femp/solid_fem.h>

#include <algorithm>
#include <cmath>

namespace femp
{
  template <int dim>
  void
  SolidFEM<dim>::Parameters::declare_parameters(ParameterHandler &prm)
  {
    prm.enter_subsection("Solid FEM");
    prm.declare_entry("Use finite elements", "false", Patterns::Bool(),
                      "Discretize the constant-solid zone below by finite "
                      "elements (FEMP). If false, all solid is material "
                      "points (all-MPM).");
    prm.declare_entry("Zone lower corner", "0, 0, 0", Patterns::Anything(),
                      "Lower corner of the box of the finite-element zone, m "
                      "(dim coordinates). It must lie on grid lines inside the "
                      "domain. Points inside the zone carry temperature only.");
    prm.declare_entry("Zone upper corner", "0, 0, 0", Patterns::Anything(),
                      "Upper corner of the finite-element zone, m (dim "
                      "coordinates); on grid lines, inside the domain, above "
                      "the lower corner in every direction.");
    prm.declare_entry("Hourglass coefficient", "0.1", Patterns::Double(),
                      "kappa of the Flanagan-Belytschko hourglass stiffness "
                      "k = kappa M V sum|b_a|^2 / 2^dim, -; range [0, 1]; 0 "
                      "switches hourglass control off (for stability studies "
                      "only).");
    prm.leave_subsection();
  }


  template <int dim>
  void
  SolidFEM<dim>::Parameters::parse_parameters(ParameterHandler &prm)
  {
    prm.enter_subsection("Solid FEM");
    enabled      = prm.get_bool("Use finite elements");
    hourglass_coefficient = prm.get_double("Hourglass coefficient");
    if (enabled)
      {
        lower_corner = parse_point<dim>(prm.get("Zone lower corner"),
                                        "Solid FEM/Zone lower corner");
        upper_corner = parse_point<dim>(prm.get("Zone upper corner"),
                                        "Solid FEM/Zone upper corner");
      }
    prm.leave_subsection();
    require(hourglass_coefficient >= 0 && hourglass_coefficient <= 1,
            "Solid FEM/Hourglass coefficient", hourglass_coefficient,
            "it must lie in [0, 1]");
  }


  template <int dim>
  void
  SolidFEM<dim>::Parameters::check(
    const typename BackgroundGrid<dim>::Parameters &g) const
  {
    if (!enabled)
      return;
    for (int d = 0; d < dim; ++d)
      {
        for (int c = 0; c < 2; ++c)
          {
            const double x    = c == 0 ? lower_corner[d] : upper_corner[d];
            const double r    = (x - g.lower_corner[d]) / g.cell_size;
            const std::string name =
              std::string("Solid FEM/Zone ") + (c == 0 ? "lower" : "upper") +
              " corner";
            require(std::abs(r - std::round(r)) < 1e-6, name, x,
                    "every coordinate must lie on a grid line (lower corner "
                    "of the domain plus a whole number of cells)");
            require(x >= g.lower_corner[d] - 1e-12 * g.cell_size &&
                      x <= g.upper_corner[d] + 1e-12 * g.cell_size,
                    name, x, "it must lie inside the domain");
          }
        require(upper_corner[d] > lower_corner[d], "Solid FEM/Zone upper corner",
                upper_corner[d],
                "it must exceed the lower corner in every direction");
      }
  }


  template <int dim>
  SolidFEM<dim>::SolidFEM(const Parameters &         prm,
                          const BackgroundGrid<dim> &grid,
                          const SolidMaterial &      material)
    : prm(prm)
    , grid(grid)
    , mat(material)
  {
    const auto &s = grid.node_strides();
    for (unsigned int a = 0; a < n_corners; ++a)
      {
        corner_offset[a] = 0;
        for (int d = 0; d < dim; ++d)
          {
            const bool up = a & (1u << d);
            sign[a][d]    = up ? 1. : -1.;
            if (up)
              corner_offset[a] += s[d];
          }
        if constexpr (dim == 2)
          gamma[0][a] = sign[a][0] * sign[a][1];
        else
          {
            gamma[0][a] = sign[a][0] * sign[a][1];
            gamma[1][a] = sign[a][1] * sign[a][2];
            gamma[2][a] = sign[a][0] * sign[a][2];
            gamma[3][a] = sign[a][0] * sign[a][1] * sign[a][2];
          }
      }
  }


  template <int dim>
  void
  SolidFEM<dim>::setup(const double mass_scaling)
  {
    mass_scale     = mass_scaling;
    const double h = grid.h();
    V              = std::pow(h, dim);
    const double b = 1. / (std::pow(2., dim - 1) * h);
    bb             = n_corners * dim * b * b;
    in_zone_cell.assign(grid.n_local(), 0);
    element_of_cell.assign(grid.n_local(), -1);
    element_cell.clear(), element_node0.clear(), stress.clear();
    node_mass.assign(grid.n_local_nodes(), 0.);
    true_node_mass.assign(grid.n_local_nodes(), 0.);
    for (int d = 0; d < dim; ++d)
      {
        vel[d].assign(grid.n_local_nodes(), 0.);
        disp[d].assign(grid.n_local_nodes(), 0.);
      }
    if (!prm.enabled)
      return;
    for (std::size_t idx = 0; idx < grid.n_local(); ++idx)
      {
        if (grid.cell_status()[idx] == BackgroundGrid<dim>::outside)
          continue;
        const Point<dim> c  = grid.cell_center(idx);
        bool             in = true;
        for (int d = 0; d < dim; ++d)
          in = in && c[d] > prm.lower_corner[d] && c[d] < prm.upper_corner[d];
        in_zone_cell[idx] = in;
      }
    std::vector<std::uint8_t> is_node(grid.n_local_nodes(), 0);
    for (const auto idx : grid.owned_cells())
      if (in_zone_cell[idx])
        {
          element_of_cell[idx] = element_cell.size();
          element_cell.push_back(idx);
          const std::size_t n0 = grid.first_node_of_cell(idx);
          element_node0.push_back(n0);
          for (unsigned int a = 0; a < n_corners; ++a)
            {
              node_mass[n0 + corner_offset[a]] +=
                mat.density * V * mass_scaling / n_corners;
              true_node_mass[n0 + corner_offset[a]] +=
                mat.density * V / n_corners;
              is_node[n0 + corner_offset[a]] = 1;
            }
        }
    stress.resize(element_cell.size());
    visc.assign(element_cell.size(), 0.);
    grid.sum_shared_nodes(node_mass);
    grid.sum_shared_nodes(true_node_mass);
    fe_nodes.clear();
    for (std::size_t n = 0; n < is_node.size(); ++n)
      if (is_node[n])
        fe_nodes.push_back(n);
  }


  template <int dim>
  void
  SolidFEM<dim>::add_forces(SolidNodeFields<dim> &                 nodes,
                            std::array<std::vector<double>, dim> &hourglass,
                            const Tensor<1, dim> &                 gravity,
                            const std::vector<double> &            T) const
  {
    const double bscale = V / (std::pow(2., dim - 1) * grid.h());
    const double nu     = mat.poisson_ratio;
    const double mfac   = (1 - nu) / ((1 + nu) * (1 - 2 * nu));
    const double mg     = mat.density * V / n_corners;
    for (std::size_t e = 0; e < element_cell.size(); ++e)
      {
        const std::size_t n0 = element_node0[e];
        const auto &      s  = stress[e].sigma;
        for (unsigned int a = 0; a < n_corners; ++a)
          {
            const std::size_t I = n0 + corner_offset[a];
            for (int i = 0; i < dim; ++i)
              {
                double f = visc[e] * sign[a][i];
                for (int j = 0; j < dim; ++j)
                  f += s[i][j] * sign[a][j];
                nodes.force[i][I] += mg * gravity[i] - bscale * f;
              }
          }
        if (prm.hourglass_coefficient > 0)
          {
            const double k = prm.hourglass_coefficient *
                             mat.youngs_modulus.value(T[element_cell[e]]) *
                             mfac * V * bb / n_corners;
            for (int i = 0; i < dim; ++i)
              for (unsigned int al = 0; al < n_hg; ++al)
                {
                  double q = 0;
                  for (unsigned int a = 0; a < n_corners; ++a)
                    q += gamma[al][a] * disp[i][n0 + corner_offset[a]];
                  for (unsigned int a = 0; a < n_corners; ++a)
                    hourglass[i][n0 + corner_offset[a]] -= k * gamma[al][a] * q;
                }
          }
      }
  }


  template <int dim>
  void
  SolidFEM<dim>::add_mass_momentum(SolidNodeFields<dim> &nodes,
                                   const bool            with_mass) const
  {
    // Element by element (partial sums of this rank): a transition node may
    // be a node of owned cells of a rank that owns none of its elements, so
    // the FE share must go through the same sum over ranks as the points'.
    const double m = mat.density * V * mass_scale / n_corners;
    for (std::size_t e = 0; e < element_cell.size(); ++e)
      for (unsigned int a = 0; a < n_corners; ++a)
        {
          const std::size_t I = element_node0[e] + corner_offset[a];
          if (with_mass)
            nodes.mass[I] += m;
          for (int d = 0; d < dim; ++d)
            nodes.momentum[d][I] += m * vel[d][I];
        }
  }


  template <int dim>
  void
  SolidFEM<dim>::update_nodes(const SolidNodeFields<dim> &                 nodes,
                              const std::array<std::vector<double>, dim> &hg,
                              const std::vector<std::uint8_t> &constrained,
                              const double                     dt)
  {
    for (const auto n : fe_nodes)
      for (int d = 0; d < dim; ++d)
        {
          double v = nodes.velocity[d][n];
          if (!(constrained[n] & (1u << d)))
            v += dt * hg[d][n] / node_mass[n];
          vel[d][n] = v;
          disp[d][n] += dt * v;
        }
  }


  template <int dim>
  double
  SolidFEM<dim>::update_stresses(const double               dt,
                                 const std::vector<double> &T_old,
                                 const std::vector<double> &T_new)
  {
    const double b     = dt / (std::pow(2., dim - 1) * grid.h());
    const double rho_s = mat.density * mass_scale;
    double       work  = 0;
    for (std::size_t e = 0; e < element_cell.size(); ++e)
      {
        const std::size_t n0 = element_node0[e];
        Tensor<2, 3>      L;
        for (unsigned int a = 0; a < n_corners; ++a)
          {
            const std::size_t I = n0 + corner_offset[a];
            for (int i = 0; i < dim; ++i)
              {
                const double vi = vel[i][I] * b;
                for (int j = 0; j < dim; ++j)
                  L[i][j] += vi * sign[a][j];
              }
          }
        const SymmetricTensor<2, 3> s_old = stress[e].sigma;
        const std::size_t           c     = element_cell[e];
        update_stress(mat, L, T_old[c], T_new[c], stress[e]);
        double w = 0;
        for (int i = 0; i < dim; ++i)
          for (int j = 0; j < dim; ++j)
            w += (s_old[i][j] + stress[e].sigma[i][j]) * L[i][j];
        double trL = 0;
        for (int i = 0; i < dim; ++i)
          trL += L[i][i];
        work += 0.5 * V * w + V * visc[e] * trL;
        if (mat.bulk_viscosity > 0)
          visc[e] = mat.bulk_viscosity * grid.h() *
                    std::sqrt(mat.p_wave_modulus(T_new[c]) * rho_s) * trL / dt;
      }
    return work;
  }


  template <int dim>
  double
  SolidFEM<dim>::kinetic_energy() const
  {
    // By element shares, so that every node counts once over all ranks.
    const double m = mat.density * V * mass_scale / n_corners;
    double       k = 0;
    for (std::size_t e = 0; e < element_cell.size(); ++e)
      for (unsigned int a = 0; a < n_corners; ++a)
        {
          const std::size_t I = element_node0[e] + corner_offset[a];
          for (int d = 0; d < dim; ++d)
            k += 0.5 * m * vel[d][I] * vel[d][I];
        }
    return k;
  }


  template <int dim>
  double
  SolidFEM<dim>::gravity_power(const Tensor<1, dim> &g) const
  {
    const double m = mat.density * V / n_corners;
    double       w = 0;
    for (std::size_t e = 0; e < element_cell.size(); ++e)
      for (unsigned int a = 0; a < n_corners; ++a)
        {
          const std::size_t I = element_node0[e] + corner_offset[a];
          for (int d = 0; d < dim; ++d)
            w += m * g[d] * vel[d][I];
        }
    return w;
  }


  template <int dim>
  double
  SolidFEM<dim>::hourglass_energy(const std::vector<double> &T,
                                  const bool                 reference) const
  {
    const double nu   = mat.poisson_ratio;
    const double mfac = (1 - nu) / ((1 + nu) * (1 - 2 * nu));
    const double kappa = reference ? 0.05 : prm.hourglass_coefficient;
    if (kappa == 0)
      return 0;
    double energy = 0;
    for (std::size_t e = 0; e < element_cell.size(); ++e)
      {
        const double k = kappa * mat.youngs_modulus.value(T[element_cell[e]]) *
                         mfac * V * bb / n_corners;
        for (int i = 0; i < dim; ++i)
          for (unsigned int al = 0; al < n_hg; ++al)
            {
              double q = 0;
              for (unsigned int a = 0; a < n_corners; ++a)
                q += gamma[al][a] * disp[i][element_node0[e] + corner_offset[a]];
              energy += 0.5 * k * q * q;
            }
      }
    return energy;
  }


  template <int dim>
  bool
  SolidFEM<dim>::find_non_finite(Point<dim> &where) const
  {
    for (std::size_t e = 0; e < element_cell.size(); ++e)
      if (!std::isfinite(stress[e].sigma.norm()))
        {
          where = grid.cell_center(element_cell[e]);
          return true;
        }
    return false;
  }


  template class SolidFEM<2>;
  template class SolidFEM<3>;
} // namespace femp
