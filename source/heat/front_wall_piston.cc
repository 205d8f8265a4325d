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
  template <int dim>
  FrontWallPiston<dim>::FrontWallPiston(const BackgroundGrid<dim> &grid,
                                        const Material            &material,
                                        const RecoilLaw           &recoil,
                                        const double               spot_radius,
                                        const double               T_far)
      : grid(grid)
      , mat(material)
      , balance(material, recoil, spot_radius, T_far)
  {
  }

  template <int dim>
  void
  FrontWallPiston<dim>::film(const double T_s, double &delta, double &v_d) const
  {
    balance.film(T_s, delta, v_d);
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
    // A message: kind (0: offer to the cell below the surface, 1: deposit
    // into the melting front, 2: accepted, back to the surface cell), the
    // cell addressed (global ijk), the flux density F/h (W/m^3), the
    // surface cell (global ijk) and the inward direction (d, sign).
    constexpr unsigned int width = 2 * dim + 4;
    using Message                = std::array<double, width>;
    std::vector<Message>                        local;
    std::map<unsigned int, std::vector<double>> outgoing;
    auto route = [&](const std::size_t target, const Message &m) {
      if (status[target] == BackgroundGrid<dim>::owned)
        local.push_back(m);
      else
        {
          auto &buffer = outgoing[grid.cell_iterator(target)->subdomain_id()];
          buffer.insert(buffer.end(), m.begin(), m.end());
        }
    };
    auto exchange = [&]() {
      const auto incoming =
        Utilities::MPI::some_to_some(grid.communicator(), outgoing);
      outgoing.clear();
      std::vector<Message> inbox;
      inbox.swap(local);
      for (const auto &[rank, buffer] : incoming)
        for (std::size_t k = 0; k + width <= buffer.size(); k += width)
          {
            Message m;
            std::copy(buffer.begin() + k,
                      buffer.begin() + k + width,
                      m.begin());
            inbox.push_back(m);
          }
      return inbox;
    };
    auto index_of = [&](const Message &m, const unsigned int first) {
      std::array<int, dim> c;
      for (int d = 0; d < dim; ++d)
        c[d] = static_cast<int>(m[first + d]);
      return grid.local_index(c);
    };
    auto give = [&](const std::size_t j, const double s) {
      source[j] += s;
      const auto it =
        std::lower_bound(source_cells.begin(), source_cells.end(), j);
      if (it == source_cells.end() || *it != j)
        source_cells.insert(it, std::uint32_t(j));
    };
    // Whether a cell holds metal that is not fully liquid: the melting
    // front.
    auto front = [&](const std::size_t c) {
      return status[c] != BackgroundGrid<dim>::outside && alpha[c] > 0 &&
             gamma[c] < 1;
    };

    // Offers: each boiling surface cell to the cell below it.
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
        if (status[j] == BackgroundGrid<dim>::outside || alpha[j] <= 0 ||
            !(T[j] < Ti))
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
        Message m{};
        m[0] = 0;
        for (int d = 0; d < dim; ++d)
          {
            m[1 + d]       = ijk[d] + (d == dmax ? int(gsign) : 0);
            m[2 + dim + d] = ijk[d];
          }
        m[1 + dim]     = F * ih;
        m[2 + 2 * dim] = dmax;
        m[3 + 2 * dim] = gsign;
        route(j, m);
        delta_min = delta_min > 0 ? std::min(delta_min, delta) : delta;
      }
    // The cell below takes the offer if it is the melting front, else
    // (fully liquid: the grid's melt is thicker than a cell) the next cell
    // inward does if it is; the surface cell hears back.
    for (const auto &m : exchange())
      {
        const std::size_t j      = index_of(m, 1);
        const auto        jjk    = grid.global_index(j);
        const int         d      = static_cast<int>(m[2 + 2 * dim]);
        const int         sign   = static_cast<int>(m[3 + 2 * dim]);
        std::size_t       target = j;
        if (!front(j))
          {
            if (jjk[d] + sign < 0 || jjk[d] + sign >= int(n[d]))
              continue;
            target = sign > 0 ? j + st[d] : j - st[d];
            if (!front(target))
              continue;
          }
        Message deposit = m;
        deposit[0]      = 1;
        for (int q = 0; q < dim; ++q)
          deposit[1 + q] = jjk[q] + (target != j && q == d ? sign : 0);
        route(target, deposit);
        Message accept = m;
        accept[0]      = 2;
        route(index_of(m, 2 + dim), accept);
      }
    for (const auto &m : exchange())
      if (m[0] == 1)
        give(index_of(m, 1), m[1 + dim]);
      else
        {
          source[index_of(m, 2 + dim)] -= m[1 + dim];
          ++n_piston;
          moved_power += m[1 + dim] * h * face;
        }
  }

  template class FrontWallPiston<2>;
  template class FrontWallPiston<3>;
} // namespace femp
