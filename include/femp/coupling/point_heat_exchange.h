// femp: PointHeatExchange, the heat that passes between the material points
// and the cells of the background grid beyond the plain cells-to-points
// copy of eq. 2:
//  - at the start, points outside the initial bodies take the initial
//    temperature at their position, and the cells of initial bodies the
//    mean temperature of their points;
//  - after the points changed cells (whoever moved them: the flow, the
//    solid, the recoater; MaterialPoints::point_moves() tells), the new
//    metal fraction alpha, and either each cell takes the mean specific
//    enthalpy C(T) + L_m gamma(T) of the points now in it (Heat
//    transfer/Advection by melt flow = points: the points carry the heat), or
//    only cells that gained metal take the mean temperature of their points
//    ('upwind': the heat moves by upwind convection of T in the heat equation).
// It is the one keeper of alpha: the only caller of
// HeatTransfer::set_metal_fraction() in a run, which stores alpha for the
// heat equation and its readers (cell_fields.h), and the owner of the
// MetalBodies, which find the bodies of metal of the same alpha once for
// the heat, the solid, the stop test and the melt pool, and of the
// MetalSurface, which finds the free surface of the same alpha once for
// the heat (its laser and surface losses).
// With 'Heat transfer/Metal of melt cells = points' it gives the heat its
// metal per cell besides alpha: in cells holding melt the volume of their
// own points (alpha there counts the excess volume of over-full neighbours,
// whose points carry it), so that the grid holds the heat the points carry.
// It keeps the energy account of these exchanges ('moved_points': the
// change of the stored enthalpy of the grid they caused, zero for a
// conservative exchange; with 'alpha' it holds the heat the temperature
// step gave or took from the excess volume, with 'points' only the gas's).
// With 'Heat transfer/Remove evaporated mass' it takes the mass that
// evaporated in the temperature step from the points of the surface cells
// (MaterialPoints::remove_mass()) and keeps the account of
// that mass and of the sensible and melting heat it took out of the grid
// (the change of the stored enthalpy; its latent heat of evaporation is the
// heat's evaporation loss). It books in the same way the points that the
// recoater's blade sweeps (builds/recoater.h).
#ifndef femp_point_heat_exchange_h
#define femp_point_heat_exchange_h

#include <femp/grid/material_points.h>
#include <femp/grid/metal_bodies.h>
#include <femp/heat/heat_transfer.h>
#include <femp/heat/metal_surface.h>

#include <memory>

namespace femp
{
  template <int dim>
  class PointHeatExchange
  {
  public:
    /// The exchange of a run on @p grid, alpha's keeper with the bodies of
    /// metal (MetalBodies) and, with @p heat_enabled, the free surface
    /// (MetalSurface) it builds: detached drops are looked for with
    /// @p heat_enabled and @p prm's 'Detached drops = sphere'; @p prm's
    /// 'Advection by melt flow = points' makes the points carry the heat.
    PointHeatExchange(MaterialPoints<dim>                          &points,
                      HeatTransfer<dim>                            &heat,
                      const BackgroundGrid<dim>                    &grid,
                      const Material                               &material,
                      const typename HeatTransfer<dim>::Parameters &prm,
                      const bool heat_enabled);
    /// An exchange without bodies of metal and surface (the heat finds
    /// the surface itself); @p carried_by_points: 'Advection by melt flow
    /// = points'; @p metal_from_points (with it): 'Metal of melt cells =
    /// points'.
    PointHeatExchange(MaterialPoints<dim>       &points,
                      HeatTransfer<dim>         &heat,
                      const BackgroundGrid<dim> &grid,
                      const bool                 carried_by_points,
                      const bool                 metal_from_points = false);

    /// The start of a run: the initial temperatures, then the metal
    /// fraction of the points as they were created (no heat exchange),
    /// its bodies and its surface. Points outside the initial @p bodies
    /// take heat_prm's initial temperature at their position (when it is
    /// a function), then the occupied cells of the bodies take the mean
    /// temperature of their points (and the liquid fraction of that
    /// temperature). Collective.
    void
    start(
      const std::vector<typename MaterialPoints<dim>::Parameters::Body> &bodies,
      const typename HeatTransfer<dim>::Parameters &heat_prm);

    /// If points changed cells since alpha was last computed (the count
    /// MaterialPoints::point_moves() moved on, whoever moved them):
    /// points_changed_cells(), and true; else nothing, and false. Call
    /// after each module that may move points across cells, before the
    /// readers of alpha. Collective.
    bool
    follow_points();

    /// The points changed cells: new alpha for the heat module and the heat
    /// the points bring (see the header comment); with a frozen
    /// temperature only alpha. Collective.
    void
    points_changed_cells();

    /// After a checkpoint restored the heat's alpha: the bodies of metal
    /// and the free surface of it, and with 'Metal of melt cells = points'
    /// the heat's metal mass: @p metal_mass, the parts of what
    /// save_metal_mass() wrote, or, when null (a checkpoint written with
    /// 'alpha'), the volume of the restored points (metal_mass()).
    /// Collective.
    void
    metal_fraction_restored(std::vector<StateReader> *metal_mass = nullptr);

    /// 'Metal of melt cells = points' (with the points carrying the heat).
    bool
    metal_of_points() const
    {
      return metal_from_points;
    }

    /// Checkpoint: the heat's metal mass per owned cell. It is renewed
    /// only when points change cells, while the points' volume (the
    /// solid's deformation) and their melt marks (each temperature step)
    /// change in between: a resume cannot find it again from the points.
    void
    save_metal_mass(StateWriter &out) const;

    /// The bodies of metal of alpha (detached drops, workpiece) that the
    /// heat, the solid, the stop test and the melt pool read (run
    /// constructor only).
    MetalBodies<dim> &
    bodies()
    {
      return *metal_bodies;
    }

    /// Change of the stored enthalpy caused by points_changed_cells() over
    /// the run, J (2D: J/m).
    double
    moved_points_energy() const
    {
      return moved_points;
    }

    /// Resume: the account at the checkpoint.
    void
    set_moved_points_energy(const double e)
    {
      moved_points = e;
    }

    /// After the temperature step and the transfer of its temperatures to
    /// the points: take the mass that evaporated in the step
    /// (HeatTransfer::evaporated_mass()) from the fluid points of the cells
    /// (MaterialPoints::remove_mass()) and book it with the stored heat it
    /// carries, m [e(T) - e(T_ref) - (rho_g c_g/rho_m)(T - T_ref)] per
    /// piece at the point's temperature (the change of the stored enthalpy
    /// of a cell whose alpha is its points' volume). alpha is stale then:
    /// the next follow_points() renews it (the flow's, or the caller's
    /// without the flow). Nothing unless the heat lists the evaporated mass
    /// and the scene carries points. Collective.
    void
    remove_evaporated_mass();

    /// The evaporated mass over the run (sums over the ranks).
    struct EvaporatedMassAccount
    {
      double        removed     = 0; ///< taken from the points, kg (2D: kg/m)
      double        not_removed = 0; ///< evaporated where no fluid point had it
      unsigned long deleted     = 0; ///< points deleted
      /// The stored enthalpy (relative to T_ref) that left the grid with
      /// the removed mass: its sensible and melting heat, J (2D: J/m).
      double enthalpy = 0;
    };
    /// The accounts so far (the same on every rank).
    const EvaporatedMassAccount &
    evaporated_mass_account() const
    {
      return evaporated;
    }
    /// Resume: the accounts at the checkpoint.
    void
    set_evaporated_mass_account(const EvaporatedMassAccount &a)
    {
      evaporated = a;
    }

    /// The stored enthalpy (relative to T_ref) that a kilogram of metal
    /// at @p T (K) takes out of a cell whose alpha is its points' volume:
    /// e(T) - e(T_ref) - (rho_g c_g/rho_m)(T - T_ref), J/kg.
    double
    removed_enthalpy_per_mass(const double T) const;

    /// What the recoater's blade swept over the run (builds/recoater.h),
    /// sums over the ranks.
    struct SweptAccount
    {
      double        mass   = 0; ///< kg (2D: kg/m)
      unsigned long points = 0; ///< points deleted
      unsigned long bodies = 0; ///< detached bodies swept
      /// Their stored heat (relative to T_ref): the sum over their points
      /// of m removed_enthalpy_per_mass(T), J (2D: J/m).
      double enthalpy = 0;
    };
    /// The recoater deleted the points of @p a (alpha is stale: the next
    /// follow_points() renews it): book them. As with the evaporated mass,
    /// the stored heat they took is booked here, not as moved points.
    void
    book_swept(const SweptAccount &a);
    /// The account so far (the same on every rank).
    const SweptAccount &
    swept_account() const
    {
      return swept;
    }
    /// Resume: the account at the checkpoint.
    void
    set_swept_account(const SweptAccount &a)
    {
      swept = a;
    }

  private:
    MaterialPoints<dim>       &points;
    HeatTransfer<dim>         &heat;
    const BackgroundGrid<dim> &grid;
    const bool                 carried_by_points;
    // 'Metal of melt cells = points' (with carried_by_points).
    const bool                         metal_from_points;
    std::unique_ptr<MetalBodies<dim>>  metal_bodies;
    std::unique_ptr<MetalSurface<dim>> surface; ///< null with the heat off
    double                             moved_points = 0;
    EvaporatedMassAccount              evaporated;
    SweptAccount                       swept;
    // MaterialPoints::point_moves() when alpha was last computed.
    std::uint64_t alpha_moves = 0;
    // 'Metal of melt cells = points': the metal mass last handed to the
    // heat (owned cells and ghosts), for save_metal_mass().
    std::vector<double> given_mass;

    /// 'Metal of melt cells = points': @p alpha, except in the cells of its
    /// volume rule (a point that is or has been fluid,
    /// MaterialPoints::metal_fraction()), which take the volume of their own
    /// points over the cell volume, neither spread to neighbours nor
    /// capped at 1 (ghosts exchanged). Collective.
    std::vector<double>
    metal_mass(const std::vector<double> &alpha) const;

    void
    initial_temperatures(
      const std::vector<typename MaterialPoints<dim>::Parameters::Body> &bodies,
      const typename HeatTransfer<dim>::Parameters &heat_prm);

    /// alpha changed: the bodies, the surface, then the heat; with
    /// 'Metal of melt cells = points' the metal mass @p given, or when
    /// null metal_mass(alpha).
    void
    new_metal_fraction(const std::vector<double> &alpha,
                       const std::vector<double> *given = nullptr);
  };
} // namespace femp

#endif
