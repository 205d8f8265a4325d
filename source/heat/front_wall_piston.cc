// femp: the sub-cell film between a boiling surface and the melting front
// (Heat transfer/Front wall piston; doc/equations.md, "Front wall piston";
// the piston of Semak and Matsunawa, J. Phys. D 30 (1997) 2541): the film
// thickness from the mass and energy balances of the expelled melt, and
// the flux it conducts beyond the grid's, moved from the surface cell to
// the cell below it.
#include <deal.II/base/mpi.h>

#include <femp/heat/front_wall_piston.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>

namespace femp
{
  namespace
  {
    constexpr double gas_constant = 8.314462618; // J/(mol K)
  }

  template <int dim>
  FrontWallPiston<dim>::FrontWallPiston(const BackgroundGrid<dim> &grid,
                                        const Material            &material,
                                        const double recoil_coefficient,
                                        const double spot_radius,
                                        const double T_far)
      : grid(grid)
      , mat(material)
      , zeta_p(recoil_coefficient)
      , rim_length(spot_radius / 2)
      , H_melt(material.specific_heat.antiderivative(material.liquidus) -
               material.specific_heat.antiderivative(
                 std::min(T_far, material.liquidus)) +
               material.latent_heat_fusion)
  {
  }

  template <int dim>
  void
  FrontWallPiston<dim>::film(const double T_s, double &delta, double &v_d) const
  {
    delta = v_d     = 0;
    const double dT = T_s - mat.liquidus;
    if (!(dT > 0) || !(zeta_p > 0) || !(H_melt > 0))
      return;
    const double Tv  = mat.evaporation_temperature;
    const double p_r = zeta_p * mat.ambient_pressure *
                       std::exp(mat.latent_heat_evaporation * mat.molar_mass *
                                (T_s - Tv) / (gas_constant * T_s * Tv));
    const double u  = std::sqrt(2 * p_r / mat.density);
    const double k  = mat.conductivity.value(0.5 * (T_s + mat.liquidus));
    const double rH = mat.density * H_melt;
    delta           = std::sqrt(k * dT * rim_length / (u * rH));
    v_d             = k * dT / (delta * rH);
  }

  template <int dim>
  void
  FrontWallPiston<dim>::add_transfer(
    const std::vector<double>                                  &T,
    const std::vector<double>                                  &alpha,
    const std::vector<double>                                  &gamma,
    const std::vector<double>                                  &laser_density,
    const std::vector<double>                                  &loss_weight,
    const std::function<double(double)>                        &q_evap,
    const std::vector<typename MetalSurface<dim>::SurfaceCell> &surface,
    std::vector<double>                                        &source,
    std::vector<std::uint32_t>                                 &source_cells)
  {
    const auto  &st     = grid.strides();
    const auto  &n      = grid.n_cells();
    const auto  &status = grid.cell_status();
    const double h      = grid.h();
    const double ih     = 1. / h;
    const double face   = std::pow(h, dim - 1);
    const double Tv     = mat.evaporation_temperature;
    n_piston            = 0;
    moved_power         = 0;
    delta_min           = 0;
    std::map<unsigned int, std::vector<double>> outgoing;
    auto give = [&](const std::size_t j, const double s) {
      source[j] += s;
      const auto it =
        std::lower_bound(source_cells.begin(), source_cells.end(), j);
      if (it == source_cells.end() || *it != j)
        source_cells.insert(it, std::uint32_t(j));
    };
    for (const auto &sc : surface)
      {
        const std::size_t i  = sc.index;
        const double      Ti = T[i];
        if (!(Ti > Tv) || alpha[i] <= 0 || !(laser_density[i] > 0))
          continue;
        // Inward direction: the dominant component of grad alpha (central
        // differences, zero gradient at the box faces).
        const auto ijk  = grid.global_index(i);
        int        dmax = -1;
        double     gmax = 0, gsign = 0;
        for (int d = 0; d < dim; ++d)
          {
            const double am = ijk[d] > 0 ? alpha[i - st[d]] : alpha[i];
            const double ap =
              ijk[d] < int(n[d]) - 1 ? alpha[i + st[d]] : alpha[i];
            const double g = ap - am; // towards more metal
            if (std::abs(g) > gmax)
              gmax = std::abs(g), dmax = d, gsign = g > 0 ? 1. : -1.;
          }
        if (dmax < 0 || ijk[dmax] + int(gsign) < 0 ||
            ijk[dmax] + int(gsign) >= int(n[dmax]))
          continue;
        const std::size_t j = gsign > 0 ? i + st[dmax] : i - st[dmax];
        if (alpha[j] <= 0 || !(gamma[j] < 1) || !(T[j] < Ti) ||
            status[j] == BackgroundGrid<dim>::outside)
          continue;
        double delta, v_d;
        film(Ti, delta, v_d);
        if (!(delta > 0) || delta >= h)
          continue;
        // The grid's face conductivity (as the conduction pass finds it).
        const double k_i = alpha[i] * mat.conductivity.value(Ti) +
                           (1 - alpha[i]) * mat.gas_conductivity;
        const double k_j = alpha[j] * mat.conductivity.value(T[j]) +
                           (1 - alpha[j]) * mat.gas_conductivity;
        const double k_ij   = 2 * k_i * k_j / (k_i + k_j + 1e-300);
        const double q_grid = k_ij * (Ti - T[j]) * ih;
        const double q_film =
          mat.conductivity.value(0.5 * (Ti + mat.liquidus)) *
          (Ti - mat.liquidus) / delta;
        // What the surface absorbs and does not evaporate, per face area.
        const double q_net =
          (laser_density[i] - q_evap(Ti) * loss_weight[i]) * h;
        const double F = std::min(q_film, q_net) - q_grid;
        if (!(F > 0))
          continue;
        ++n_piston;
        moved_power += F * face;
        delta_min = n_piston == 1 ? delta : std::min(delta_min, delta);
        source[i] -= F * ih;
        if (status[j] == BackgroundGrid<dim>::owned)
          give(j, F * ih);
        else
          {
            auto  jjk    = ijk;
            auto &buffer = outgoing[grid.cell_iterator(j)->subdomain_id()];
            jjk[dmax] += int(gsign);
            for (int d = 0; d < dim; ++d)
              buffer.push_back(jjk[d]);
            buffer.push_back(F * ih);
          }
      }
    const auto incoming =
      Utilities::MPI::some_to_some(grid.communicator(), outgoing);
    for (const auto &[rank, buffer] : incoming)
      for (std::size_t k = 0; k + dim + 1 <= buffer.size(); k += dim + 1)
        {
          std::array<int, dim> jjk;
          for (int d = 0; d < dim; ++d)
            jjk[d] = static_cast<int>(buffer[k + d]);
          give(grid.local_index(jjk), buffer[k + dim]);
        }
  }

  template class FrontWallPiston<2>;
  template class FrontWallPiston<3>;
} // namespace femp
