// femp: MetalSurface<dim>, the free surface of the metal that the heat
// equation (1) acts on through |grad alpha|, found once per change of the
// metal fraction alpha (by alpha's keeper, PointHeatExchange, beside the
// bodies of metal, MetalBodies) and handed to the heat transfer, which
// deposits the laser and takes the surface losses there:
//   - surface cells: the owned metal cells with a non-zero central
//     difference gradient of alpha, and |grad alpha| (alpha is extended with
//     zero gradient at the domain boundary, so the box faces are not free
//     surfaces): the cells of the evaporation, convection and radiation
//     losses and of the 'gradient' laser deposition;
//   - first-surface cells: per vertical column the cells where the beam
//     first meets metal, with their share of the column's laser flux (the
//     default 'first surface' deposition; doc/method.md, "Heat transfer");
//   - detached cells ('Heat transfer/Detached drops = sphere'): the owned
//     cells of the detached drops of MetalBodies, each losing heat as part
//     of a sphere (2D: a cylinder) of the drop's metal volume in still gas.
#ifndef femp_metal_surface_h
#define femp_metal_surface_h

#include <femp/base/material.h>
#include <femp/grid/background_grid.h>
#include <femp/grid/metal_bodies.h>

#include <cstdint>
#include <vector>

namespace femp
{
  template <int dim>
  class MetalSurface
  {
  public:
    /// A surface cell and its |grad alpha|, 1/m.
    struct SurfaceCell
    {
      std::uint32_t index;
      double        grad_alpha;
    };
    /// An owned cell where the vertical beam first meets metal, with its
    /// share (1/m) of the column's flux q: the cell gets q * share per
    /// volume, the shares of a column sum to 1/h.
    struct LaserCell
    {
      std::uint32_t index;
      double        share;
    };
    /// An owned cell of a detached drop: area per cell volume 2 dim alpha/d
    /// (1/m) and gas coefficient Nu k_g/d, Nu = 2 (W/(m^2 K)), d the
    /// diameter of the drop's sphere.
    struct DetachedCell
    {
      std::uint32_t index;
      double        area;
      double        gas_h;
    };

    /// The weights of the first-surface shares take the metal's heat
    /// capacity at @p reference_temperature (K); @p detached_drops: 'Heat
    /// transfer/Detached drops = sphere'.
    MetalSurface(const BackgroundGrid<dim> &grid,
                 const Material            &material,
                 const double               reference_temperature,
                 const bool                 detached_drops);

    /// alpha changed (owned cells and ghosts): find the lists anew; the
    /// detached cells from the drops of @p bodies, found from the same
    /// alpha (none when nullptr). Collective.
    void
    update(const std::vector<double> &alpha,
           const MetalBodies<dim>    *bodies = nullptr);

    /// The surface cells, in increasing local index.
    const std::vector<SurfaceCell> &
    cells() const
    {
      return surface;
    }
    /// The first-surface cells (the surface cells of the columns first,
    /// then the topmost cells of columns without any).
    const std::vector<LaserCell> &
    first_surface() const
    {
      return first;
    }
    /// The cells of detached drops (empty unless Detached drops = sphere).
    const std::vector<DetachedCell> &
    detached() const
    {
      return drops;
    }

  private:
    const BackgroundGrid<dim> &grid;
    const Material            &mat;
    const double               reference_temperature;
    const bool                 detached_drops;
    std::vector<SurfaceCell>   surface;
    std::vector<LaserCell>     first;
    std::vector<DetachedCell>  drops;
  };
} // namespace femp

#endif
