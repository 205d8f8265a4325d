// femp: FluidSolidForces, the load of the melt on the solid when flow and
// solid run together (paper eq. 13, the fluid forces; doc/solid.md "Flow
// and solid together"): the pressure and viscous forces of the fluid on
// the faces of the solid cells (IncompressibleFlow::fluid_forces_on_solid)
// spread to the faces' grid nodes, where the solid takes them as external
// nodal forces held over its sub-steps.
//
// Share rule: the force through a face of an owned solid cell goes to the
// face's 2^(dim-1) nodes, to node I the share
//   F_face / 2^(dim-1) * min(1, m_I / (m_ref / 2)),
// m_I = sum_p N_I(x_p) m_p over the cell's solid points, m_ref = rho h^dim
// / 2^dim the share of a full cell. A full cell gets the face force exactly
// (equal shares: the traction on the face), also when its points have
// moved by up to a quarter cell; a node that holds only a small part of a
// point's mass gets a force in proportion, so its acceleration is at most
// twice that of a node of a full cell (a whole face force on such a node
// made the 3D track scene blow up). Spreading over the points with their
// tents instead was stable but put half of the face force on the far nodes
// of the cell (the stress under the interface 0.47 short in
// coupled_pool_on_solid). Cells of the FE zone as it stands (a hand-over
// raises it): equal shares. Cells with no
// solid point (powder only): no force; unmelted powder carries no stress.
#ifndef femp_fluid_solid_forces_h
#define femp_fluid_solid_forces_h

#include <femp/flow/incompressible_flow.h>
#include <femp/grid/background_grid.h>
#include <femp/grid/material_points.h>
#include <femp/solid/solid_fem.h>

#include <array>
#include <vector>

namespace femp
{
  template <int dim>
  class FluidSolidForces
  {
  public:
    /// Face forces, one cell field per face and component: entry
    /// dim * (2 d + side) + e is component e of the force through face
    /// (d, side) of the cell, N (2D: N/m).
    using FaceForces = std::array<std::vector<double>, 2 * dim * dim>;
    using NodeForces = std::array<std::vector<double>, dim>;

    /// @p density: of the solid metal, kg/m^3; @p fe_zone: the FE zone of
    /// the solid (equal shares inside it; see follow_zone()).
    FluidSolidForces(const BackgroundGrid<dim>                &grid,
                     const MaterialPoints<dim>                &points,
                     const double                              density,
                     const typename SolidFEM<dim>::Parameters &fe_zone);

    /// Take the FE zone from @p zone at each spread instead of the
    /// parameters' box: the solid's zone as it is now
    /// (SolidSubCycle::fe_zone(), which a hand-over raises). @p zone must
    /// outlive this object.
    void
    follow_zone(const FeZone<dim> &zone)
    {
      followed_zone = &zone;
    }

    /// The forces of the last fluid step of @p flow to the nodes.
    void
    update(const IncompressibleFlow<dim> &flow);

    /// Spread @p face_force to the nodes of the owned cells (partial sums
    /// of this rank over the local node box; the solid sums over ranks).
    /// @p cells: the owned cells (increasing) outside which @p face_force
    /// is zero; nullptr: look at every owned cell.
    void
    spread(const FaceForces                 &face_force,
           const std::vector<std::uint32_t> *cells = nullptr);

    /// The nodal forces, one array per direction over the local node box.
    const NodeForces &
    nodal_forces() const
    {
      return node_force;
    }

  private:
    const BackgroundGrid<dim> &grid;
    const MaterialPoints<dim> &points;
    const double               density;
    const FeZone<dim>          fe_zone;
    /// follow_zone(): the zone read at each spread instead of fe_zone.
    const FeZone<dim> *followed_zone = nullptr;
    FaceForces         face_force;
    NodeForces         node_force;
    // The cells where face_force may be non-zero (the flow's last call),
    // and those whose corners the last spread wrote: only they are reset,
    // so a few liquid drops cost a few cells, not passes over the grid.
    std::vector<std::uint32_t> face_cells, spread_cells;

    /// Share of each corner of owned cell @p c (the rule above).
    std::array<double, (1u << dim)>
    corner_shares(const std::size_t c) const;
  };
} // namespace femp

#endif
