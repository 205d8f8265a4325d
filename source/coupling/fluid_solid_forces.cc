// femp: FluidSolidForces, the fluid forces on the solid's grid nodes (paper
// eq. 13; the share rule is in the header).
#include <femp/coupling/fluid_solid_forces.h>

#include <cmath>

namespace femp
{
  template <int dim>
  FluidSolidForces<dim>::FluidSolidForces(
    const BackgroundGrid<dim>                &grid,
    const MaterialPoints<dim>                &points,
    const double                              density,
    const typename SolidFEM<dim>::Parameters &fe_zone)
      : grid(grid)
      , points(points)
      , density(density)
      , fe_zone(fe_zone.zone(grid.origin(), grid.h()))
  {
    for (int d = 0; d < dim; ++d)
      node_force[d] = grid.make_node_field();
  }

  template <int dim>
  void
  FluidSolidForces<dim>::update(const IncompressibleFlow<dim> &flow)
  {
    flow.fluid_forces_on_solid(face_force, face_cells);
    spread(face_force, &face_cells);
  }

  template <int dim>
  std::array<double, (1u << dim)>
  FluidSolidForces<dim>::corner_shares(const std::size_t c) const
  {
    constexpr unsigned int n_corners = 1u << dim;
    using P        = typename MaterialPoints<dim>::PropertyIndex;
    const double h = grid.h(), ih = 1. / h;
    const double m_ref = density * std::pow(h, dim) / n_corners;
    const auto  &x0    = grid.origin();
    const auto   ijk   = grid.global_index(c);
    std::array<double, n_corners> share;
    // 1 in the FE zone, else min(1, 2 m_I / m_ref).
    if ((followed_zone ? *followed_zone : fe_zone).contains_cell(ijk))
      {
        share.fill(1.);
        return share;
      }
    share.fill(0.);
    for (const auto &particle :
         points.particle_handler().particles_in_cell(grid.cell_iterator(c)))
      {
        const auto v = particle.get_properties();
        if (v[P::state] != MaterialPoints<dim>::solid)
          continue;
        const Point<dim> &x = particle.get_location();
        double            w[n_corners];
        tent_weights<dim>(x, x0, ih, ijk, v[P::mass] / (0.5 * m_ref), w);
        for (unsigned int k = 0; k < n_corners; ++k)
          share[k] += w[k];
      }
    for (auto &s : share)
      s = std::min(1., s);
    return share;
  }

  template <int dim>
  void
  FluidSolidForces<dim>::spread(const FaceForces                 &F,
                                const std::vector<std::uint32_t> *cells)
  {
    constexpr unsigned int             n_corners = 1u << dim;
    const auto                        &ns        = grid.node_strides();
    std::array<std::size_t, n_corners> offset;
    for (unsigned int k = 0; k < n_corners; ++k)
      {
        offset[k] = 0;
        for (int d = 0; d < dim; ++d)
          if ((k >> d) & 1)
            offset[k] += ns[d];
      }
    // Only the corners of the cells spread last time hold forces.
    for (const auto c : spread_cells)
      for (unsigned int k = 0; k < n_corners; ++k)
        for (int d = 0; d < dim; ++d)
          node_force[d][grid.first_node_of_cell(c) + offset[k]] = 0;
    spread_cells.clear();
    for (const auto c : cells ? *cells : grid.owned_cells())
      {
        bool any = false;
        for (const auto &f : F)
          any = any || f[c] != 0;
        if (!any)
          continue;
        spread_cells.push_back(c);
        const std::size_t n0    = grid.first_node_of_cell(c);
        const auto        share = corner_shares(c);
        for (int d = 0; d < dim; ++d)
          for (unsigned int side = 0; side < 2; ++side)
            {
              const unsigned int f = dim * (2 * d + side);
              for (unsigned int k = 0; k < n_corners; ++k)
                if (((k >> d) & 1) == side)
                  for (int e = 0; e < dim; ++e)
                    node_force[e][n0 + offset[k]] +=
                      F[f + e][c] * share[k] / (n_corners / 2);
            }
      }
  }

  template class FluidSolidForces<2>;
  template class FluidSolidForces<3>;
} // namespace femp
