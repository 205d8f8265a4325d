// femp: sub-cell model of the melting front under a boiling surface (Heat
// transfer/Front wall piston; doc/equations.md, "Front wall piston").
//
// On the front wall of a vapour depression the recoil pressure p_r expels
// the melt that the absorbed flux makes, through a film of a few
// micrometres between the boiling surface and the melting front (the
// "piston" of Semak and Matsunawa, J. Phys. D 30 (1997) 2541). With cells
// of several micrometres the grid holds that film one to two cells thick,
// and its conduction, k (T_i - T_j)/h between the surface cell i and the
// cell j below it, is far smaller than the film's k (T_s - T_l)/delta.
// This model gives the film its own thickness, from two balances and no
// fitted constant:
//   - mass: the melt made over a spot of radius r_b at the drilling speed
//     v_d leaves through the spot's rim at the Bernoulli speed
//     u = sqrt(2 p_r / rho) of the recoil: pi r_b^2 v_d = 2 pi r_b delta u,
//     delta = v_d l / u with l = r_b / 2;
//   - energy at the melting front (a front moving at v_d into solid at
//     T_0): k (T_s - T_l) / delta = rho v_d H, H = e(T_l) - e(T_0) the
//     specific enthalpy that melts the solid (e = C(T) + L_m gamma(T));
// so that delta = sqrt(k (T_s - T_l) l / (u rho H)) and the film's flux
// q_f = k (T_s - T_l)/delta = rho H v_d. In an owned surface cell i that
// boils (T_i > T_v), with its inward face neighbour c (along the dominant
// direction of grad alpha) holding metal, the melting front j is c if c is
// not fully liquid, else the next cell inward if that one is not (the
// grid's melt under a boiling surface is one to two cells thick); the flux
// that the film conducts beyond the grid's,
//   F = max(0, min(q_f, q_net) - k_ic (T_i - T_c)/h),
// moves from i to j (q_net: what cell i absorbs from the laser and does
// not lose by evaporation, per unit face area, so that the film never
// takes more than the absorbed flux and the surface keeps its own
// evaporation; k_ic the grid's harmonic face conductivity). It acts only
// where delta < h. The energy leaves i and enters j in the same step: the
// ledger is unchanged. The offer goes to c's owner, which finds j among
// its cells and ghosts and tells j's owner and i's owner: two message
// rounds per step, so that the result does not depend on the partition
// (collective).
#ifndef femp_front_wall_piston_h
#define femp_front_wall_piston_h

#include <femp/base/material.h>
#include <femp/base/piston_film.h>
#include <femp/base/recoil_law.h>
#include <femp/grid/background_grid.h>
#include <femp/heat/metal_surface.h>

#include <cstdint>
#include <functional>
#include <vector>

namespace femp
{
  using namespace dealii;

  template <int dim>
  class FrontWallPiston
  {
  public:
    /// @p recoil: the recoil pressure p_r(T) of the melt flow (RecoilLaw);
    /// @p spot_radius: r_b, m; @p T_far: the temperature of the solid far
    /// ahead of the front, K.
    FrontWallPiston(const BackgroundGrid<dim> &grid,
                    const Material            &material,
                    const RecoilLaw           &recoil,
                    const double               spot_radius,
                    const double               T_far);

    /// The film of a surface at @p T_s (K) over solid: thickness delta (m)
    /// and drilling speed v_d (m/s) of the balances above; both zero where
    /// T_s is not above the liquidus or the recoil p_r(T_s) is zero.
    void
    film(const double T_s, double &delta, double &v_d) const;

    /// Add the film's transfer of this step to the volumetric sources
    /// (W/m^3): -F/h in each piston cell i, +F/h in its melting-front cell
    /// j (added to @p source_cells, kept sorted, when not yet there; on
    /// another rank by its owner). @p T, @p alpha, @p gamma: the heat's
    /// cell fields (ghosts current); @p laser_density: the laser's
    /// volumetric source of the step, @p loss_weight: the surface-loss
    /// weight w |grad alpha| (1/m) of the owned surface cells; @p q_evap:
    /// the evaporation loss q_evap(T), W/m^2. Collective.
    void
    add_transfer(
      const std::vector<double>                                  &T,
      const std::vector<double>                                  &alpha,
      const std::vector<double>                                  &gamma,
      const std::vector<double>                                  &laser_density,
      const std::vector<double>                                  &loss_weight,
      const std::function<double(double)>                        &q_evap,
      const std::vector<typename MetalSurface<dim>::SurfaceCell> &surface,
      std::vector<double>                                        &source,
      std::vector<std::uint32_t>                                 &source_cells);

    /// Of the last add_transfer() on this rank: piston cells, the power
    /// moved (W, 2D: W/m), the thinnest film offered (m; 0 when none).
    std::size_t
    n_cells() const
    {
      return n_piston;
    }
    double
    power() const
    {
      return moved_power;
    }
    double
    thinnest_film() const
    {
      return delta_min;
    }

  private:
    const BackgroundGrid<dim> &grid;
    const Material            &mat;
    const PistonFilm           balance;
    std::size_t                n_piston    = 0;
    double                     moved_power = 0, delta_min = 0;
  };
} // namespace femp

#endif
