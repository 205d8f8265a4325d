// femp: sub-cell expulsion of the melt from a boiling surface (Melt
// flow/Front wall expulsion; doc/flow.md, "Front wall expulsion").
//
// On the front wall of a vapour depression the recoil pressure p_r drives
// the melt that the absorbed flux makes out of the beam's spot at the
// Bernoulli speed u = sqrt(2 p_r / rho) (Semak and Matsunawa, J. Phys. D 30
// (1997) 2541, eq. for the melt velocity at the spot's rim); only a film of
// thickness delta stays between the boiling surface and the melting front
// (the piston's film, PistonFilm::film(), a few micrometres). With
// cells of several micrometres the grid's pressure gradient across the spot
// is smeared over cells, and the grid's melt moves at a fraction of u.
// This model lets the melt that a boiling surface cell holds beyond the
// film leave at the Bernoulli speed of its recoil: on the nodes of an
// *expelling* cell the velocity component along the surface, away from the
// hot spot, is raised to at least u (after the pressure correction, before
// the points take the nodal velocity). An expelling cell is a recoil-driven
// surface cell (FreeSurface::mark_recoil_driven(): it boils and its recoil
// exceeds its capillary pressure) whose melt, alpha~ h (alpha~ its smoothed
// metal fraction), is thicker than the piston's film delta at its
// temperature. The direction is t = -grad_s T / |grad_s T|, the surface
// gradient of the cell temperature (grad T - (n . grad T) n, n = -grad
// alpha~ / |grad alpha~|, central differences over metal neighbours): the
// recoil's own gradient, since p_r grows monotonically with T. Nodes fixed
// in every direction (corners of solid cells: the film under the surface
// stays) are left alone; on nodes fixed in some directions (domain
// boundary, film slip) only the free components count.
//
// The points move, none is added or deleted: mass is kept; the points carry
// their enthalpy, so the heat's energy ledger is unchanged. The momentum
// and kinetic energy given to the melt are those the recoil pressure gives
// a film accelerated through the pressure drop p_r (Bernoulli), which the
// grid's pressure solve does not resolve under a cell.
#ifndef femp_front_wall_expulsion_h
#define femp_front_wall_expulsion_h

#include <femp/base/material.h>
#include <femp/base/piston_film.h>
#include <femp/base/recoil_law.h>
#include <femp/grid/background_grid.h>

#include <array>
#include <cstdint>
#include <vector>

namespace femp
{
  using namespace dealii;

  template <int dim>
  class FrontWallExpulsion
  {
  public:
    /// @p recoil: the recoil pressure p_r(T) of the free surface
    /// (RecoilLaw); @p spot_radius: the beam radius r_b, m; @p T_far: the
    /// temperature of the solid far ahead, K (the three for the piston's
    /// film thickness).
    FrontWallExpulsion(const BackgroundGrid<dim> &grid,
                       const Material            &material,
                       const RecoilLaw           &recoil,
                       const double               spot_radius,
                       const double               T_far);

    /// The expelling cells of this fluid step among the owned
    /// @p fluid_cells, from @p driven (FreeSurface::mark_recoil_driven(),
    /// ghosts exchanged), the cell classes @p type, the recoil pressure
    /// @p p_surface - @p p_capillary (Pa, surface cells; FreeSurface), the
    /// smoothed metal fraction
    /// @p alpha (near-fluid cells, ghosts exchanged) and the cell
    /// temperature @p T (K, ghosts current): their Bernoulli speed and
    /// direction, ghosts exchanged. Collective.
    void
    select(const std::vector<std::uint32_t> &fluid_cells,
           const std::vector<double>        &driven,
           const std::vector<double>        &type,
           const std::vector<double>        &p_surface,
           const std::vector<double>        &p_capillary,
           const std::vector<double>        &alpha,
           const std::vector<double>        &T);

    /// Raise the component of @p u along the expulsion direction to the
    /// Bernoulli speed on the @p active nodes (@p active_cell: the cell
    /// whose corner 0 each is) that are corners of an expelling cell (the
    /// fastest one where several meet), leaving the directions fixed by
    /// @p node_fix alone.
    void
    apply(const std::vector<std::uint32_t>     &active,
          const std::vector<std::uint32_t>     &active_cell,
          const std::vector<std::uint8_t>      &node_fix,
          std::array<std::vector<double>, dim> &u) const;

    /// Expelling cells of the last select() on this rank, and their
    /// largest Bernoulli speed (m/s; 0 when none).
    std::size_t
    n_cells() const
    {
      return expelling.size();
    }
    double
    max_speed() const
    {
      return fastest;
    }
    /// The Bernoulli speed sqrt(2 p_r / rho) of a recoil pressure @p p_r,
    /// m/s.
    double
    bernoulli_speed(const double p_r) const;
    /// The piston's film thickness at a surface temperature @p T_s, m (0
    /// where there is none: T_s not above the liquidus or no recoil).
    double
    film_thickness(const double T_s) const;

  private:
    static constexpr unsigned int         n_corners = 1u << dim;
    const BackgroundGrid<dim>            &grid;
    const double                          rho;
    const PistonFilm                      piston;
    std::array<std::ptrdiff_t, n_corners> around_offset; // cells round a node
    std::vector<double>                   speed;         // m/s, 0: none
    std::array<std::vector<double>, dim>  direction;     // unit
    std::vector<std::uint32_t>            expelling;     // owned
    double                                fastest = 0;
  };
} // namespace femp

#endif
