// femp: PointHeatExchange, heat between the material points and the grid
// cells when points enter the grid or change cells (see the header; the
// enthalpy relation of eq. 1, the point-cell transfer of eq. 2).
#include <femp/coupling/point_heat_exchange.h>
#include <femp/grid/cell_state.h>

#include <cmath>

namespace femp
{
  template <int dim>
  PointHeatExchange<dim>::PointHeatExchange(
    MaterialPoints<dim>                          &points,
    HeatTransfer<dim>                            &heat,
    const BackgroundGrid<dim>                    &grid,
    const Material                               &material,
    const typename HeatTransfer<dim>::Parameters &prm,
    const bool                                    heat_enabled)
      : points(points)
      , heat(heat)
      , grid(grid)
      , carried_by_points(prm.advection_by_melt_flow ==
                          HeatTransfer<dim>::Parameters::Advection::points)
      , metal_from_points(carried_by_points &&
                          prm.metal_of_melt_cells ==
                            HeatTransfer<dim>::Parameters::MeltMetal::points)
      // Detached drops are looked for only for the heat equation's losses.
      , metal_bodies(std::make_unique<MetalBodies<dim>>(
          grid,
          heat_enabled && prm.detached_drops ? prm.detached_drop_cells : 0))
  {
    // The free surface of the metal only for the heat equation.
    if (heat_enabled)
      surface = std::make_unique<MetalSurface<dim>>(grid,
                                                    material,
                                                    prm.reference_temperature,
                                                    prm.detached_drops);
  }

  template <int dim>
  PointHeatExchange<dim>::PointHeatExchange(MaterialPoints<dim>       &points,
                                            HeatTransfer<dim>         &heat,
                                            const BackgroundGrid<dim> &grid,
                                            const bool carried_by_points,
                                            const bool metal_from_points)
      : points(points)
      , heat(heat)
      , grid(grid)
      , carried_by_points(carried_by_points)
      , metal_from_points(carried_by_points && metal_from_points)
  {
  }

  template <int dim>
  void
  PointHeatExchange<dim>::new_metal_fraction(const std::vector<double> &alpha,
                                             const std::vector<double> *given)
  {
    if (metal_bodies)
      metal_bodies->update(alpha);
    const bool by_points = metal_from_points && points.carried();
    if (by_points)
      given_mass = given ? *given : metal_mass(alpha);
    const std::vector<double> *mass = by_points ? &given_mass : nullptr;
    if (!surface)
      {
        heat.set_metal_fraction(alpha, metal_bodies.get(), mass);
        return;
      }
    surface->update(alpha, metal_bodies.get());
    heat.set_metal_fraction(alpha, *surface, mass);
  }

  template <int dim>
  std::vector<double>
  PointHeatExchange<dim>::metal_mass(const std::vector<double> &alpha) const
  {
    // alpha, except in the cells of the volume rule (a point that is or
    // has been fluid, MaterialPoints::metal_fraction()): there the volume
    // of the points, not spread to neighbours nor capped.
    using P                      = typename MaterialPoints<dim>::PropertyIndex;
    const double        Ts       = heat.material().solidus;
    const double        inv_V    = 1. / std::pow(grid.h(), dim);
    std::vector<double> m        = alpha;
    const auto         &occupied = points.occupied_cells();
    for (std::size_t c = 0; c < occupied.size(); ++c)
      {
        double v    = 0;
        bool   melt = false;
        for (const double *p : points.cell_point_properties(c))
          {
            v += p[P::volume];
            melt = melt || p[P::state] == MaterialPoints<dim>::fluid ||
                   p[P::peak_temperature] > Ts;
          }
        const auto idx = occupied[c].first;
        if (melt && v > 0 && alpha[idx] > 0)
          m[idx] = v * inv_V;
      }
    grid.update_ghosts(m);
    return m;
  }

  template <int dim>
  void
  PointHeatExchange<dim>::save_metal_mass(StateWriter &out) const
  {
    // The heat's: alpha where no metal mass was handed to it.
    save_cell_fields(
      out, grid, {given_mass.empty() ? &heat.metal_fraction() : &given_mass});
  }

  template <int dim>
  void
  PointHeatExchange<dim>::metal_fraction_restored(
    std::vector<StateReader> *metal_mass)
  {
    if (!metal_bodies && !surface)
      return;
    // The heat restored alpha and the surface lists it found itself; the
    // bodies and the surface follow, and the heat takes them (the rest of
    // its state is the same after a second set_metal_fraction()), with the
    // metal mass of the checkpoint where it holds one. Every rank makes
    // the call: the drops are per rank, the updates and
    // set_metal_fraction() are collective.
    const std::vector<double> alpha = heat.metal_fraction();
    std::vector<double>       saved;
    if (metal_mass)
      {
        saved = grid.make_field(0.);
        load_cell_fields(*metal_mass, grid, {&saved});
      }
    new_metal_fraction(alpha, metal_mass ? &saved : nullptr);
  }

  template <int dim>
  void
  PointHeatExchange<dim>::initial_temperatures(
    const std::vector<typename MaterialPoints<dim>::Parameters::Body> &bodies,
    const typename HeatTransfer<dim>::Parameters                      &heat_prm)
  {
    using P = typename MaterialPoints<dim>::PropertyIndex;
    if (!heat_prm.initial_temperature_expression.empty())
      {
        // Points outside the initial bodies take the initial temperature
        // at their position.
        for (auto &particle : points.particle_handler_for_update())
          {
            const Point<dim> x       = particle.get_location();
            bool             in_body = false;
            for (const auto &b : bodies)
              in_body = in_body || b.inside(x);
            if (in_body)
              continue;
            auto         v         = particle.get_properties();
            const double T0        = heat_prm.initial_temperature_at(x);
            v[P::temperature]      = T0;
            v[P::peak_temperature] = T0;
          }
      }
    if (!bodies.empty())
      {
        // Cells of initial bodies take the mean temperature of their points
        // (and the liquid fraction of that temperature).
        for (const auto &[idx, cell] : points.occupied_cells())
          {
            double sum = 0, n = 0;
            for (const auto &particle :
                 points.particle_handler().particles_in_cell(cell))
              sum += particle.get_properties()[P::temperature], ++n;
            if (n > 0)
              heat.set_cell_temperature(idx, sum / n);
          }
        heat.update_ghosts();
      }
  }

  template <int dim>
  void
  PointHeatExchange<dim>::start(
    const std::vector<typename MaterialPoints<dim>::Parameters::Body> &bodies,
    const typename HeatTransfer<dim>::Parameters                      &heat_prm)
  {
    initial_temperatures(bodies, heat_prm);
    new_metal_fraction(points.metal_fraction());
    alpha_moves = points.point_moves();
  }

  template <int dim>
  bool
  PointHeatExchange<dim>::follow_points()
  {
    if (points.point_moves() == alpha_moves)
      return false;
    points_changed_cells();
    return true;
  }

  template <int dim>
  void
  PointHeatExchange<dim>::points_changed_cells()
  {
    alpha_moves             = points.point_moves();
    const bool heat_enabled = !heat.is_frozen();
    // Energy bookkeeping: the stored enthalpy before and after (collective).
    const double        H_before = heat_enabled ? heat.stored_enthalpy() : 0.;
    std::vector<double> alpha    = points.metal_fraction();
    const auto         &old      = heat.metal_fraction();
    using P                      = typename MaterialPoints<dim>::PropertyIndex;
    if (heat_enabled && carried_by_points)
      {
        // The points carry the heat: every cell whose points came from
        // cells at other temperatures takes their mean specific enthalpy
        // (cells that gained metal included).
        const auto mean_e =
          points.volume_mean_over_points(heat.temperature(),
                                         [this](const double T) {
                                           return heat.specific_enthalpy(T);
                                         });
        new_metal_fraction(alpha);
        heat.take_point_enthalpy(mean_e);
        moved_points += heat.stored_enthalpy() - H_before;
        return;
      }
    // (With a frozen temperature the field keeps its initial values.)
    if (heat_enabled)
      for (const auto &[idx, cell] : points.occupied_cells())
        if (old[idx] <= 0 && alpha[idx] > 0)
          {
            double sum = 0, n = 0;
            for (const auto &particle :
                 points.particle_handler().particles_in_cell(cell))
              sum += particle.get_properties()[P::temperature], ++n;
            // gamma from T: a stale gamma (0 in a former gas cell) would
            // take the latent heat of a hot arrival from its sensible heat
            // at the next step (cooling it by up to L_m/c_m ~ 350 K).
            if (n > 0)
              heat.set_cell_temperature(idx, sum / n);
          }
    heat.update_ghosts();
    new_metal_fraction(alpha);
    if (heat_enabled)
      moved_points += heat.stored_enthalpy() - H_before;
  }

  template <int dim>
  void
  PointHeatExchange<dim>::remove_evaporated_mass()
  {
    if (heat.is_frozen() || !heat.lists_evaporated_mass() || !points.carried())
      return;
    const auto &list = heat.evaporated_mass();
    std::vector<typename MaterialPoints<dim>::MassToRemove> cells;
    cells.reserve(list.size());
    for (const auto &e : list)
      cells.push_back({e.index, e.mass, e.outward});
    const auto r = points.remove_mass(cells, [this](const double T) {
      return removed_enthalpy_per_mass(T);
    });
    evaporated.removed += r.mass;
    evaporated.not_removed += r.not_removed;
    evaporated.deleted += r.deleted;
    evaporated.enthalpy += r.weighted;
    // alpha follows at the next follow_points(), which books the change of
    // the stored enthalpy as that of moved points; the part the removed
    // metal took is booked here instead (so moved_points keeps only what
    // the exchange itself created: alpha capped in over-full cells).
    moved_points += r.weighted;
  }

  template <int dim>
  double
  PointHeatExchange<dim>::removed_enthalpy_per_mass(const double T) const
  {
    // Its own, less that of the gas that takes its place.
    const Material &mat  = heat.material();
    const double    Tref = heat.reference_temperature();
    const double    gas = mat.gas_density * mat.gas_specific_heat / mat.density;
    return heat.specific_enthalpy(T) - heat.specific_enthalpy(Tref) -
           gas * (T - Tref);
  }

  template <int dim>
  void
  PointHeatExchange<dim>::book_swept(const SweptAccount &a)
  {
    swept.mass += a.mass;
    swept.points += a.points;
    swept.bodies += a.bodies;
    swept.enthalpy += a.enthalpy;
    // The next follow_points() books the change of the stored enthalpy as
    // that of moved points; the part the swept metal took is booked here.
    moved_points += a.enthalpy;
  }

  template class PointHeatExchange<2>;
  template class PointHeatExchange<3>;
} // namespace femp
