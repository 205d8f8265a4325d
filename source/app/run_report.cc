// femp: RunReport, the progress line and the end-of-run report of a scene
// (see the header): the energy balance of the temperature equation (1),
// the solid energies of eqs. 5-17 and the melt-flow statistics.
#include <deal.II/base/mpi.h>

#include <femp/app/run_report.h>
#include <femp/base/progress_watchdog.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>

namespace femp
{
  template <int dim>
  RunReport<dim>::RunReport(MPI_Comm comm, ConditionalOStream &out)
      : comm(comm)
      , out(out)
  {
  }

  template <int dim>
  void
  RunReport<dim>::start(const HeatTransfer<dim> &heat)
  {
    H0 = heat.stored_enthalpy();
  }

  template <int dim>
  void
  RunReport<dim>::watch_laser(const Laser<dim> &laser)
  {
    with_laser = std::any_of(laser.segments().begin(),
                             laser.segments().end(),
                             [](const auto &seg) { return seg.power > 0; });
  }

  template <int dim>
  void
  RunReport<dim>::add_state(ModuleStates<dim>       &states,
                            PointHeatExchange<dim>  &point_heat,
                            IncompressibleFlow<dim> *flow)
  {
    states.add(
      "run",
      [this, &point_heat, flow](StateWriter &out) {
        out.put(H0);
        out.put(point_heat.moved_points_energy());
        out.put(point_heat.evaporated_mass_account());
        out.put(s.pool);
        out.put(flow ? flow->subcycle_record() : s.flow_limits);
        out.put(point_heat.swept_account());
      },
      [this, &point_heat, flow](std::vector<StateReader> &parts) {
        StateReader &in = parts[0];
        H0              = in.get<double>();
        point_heat.set_moved_points_energy(in.get<double>());
        point_heat.set_evaporated_mass_account(
          in.get<typename PointHeatExchange<dim>::EvaporatedMassAccount>());
        s.pool        = in.get<MeltPoolSize>();
        s.flow_limits = in.get<typename RunSummary<dim>::FlowLimits>();
        if (flow)
          flow->set_subcycle_record(s.flow_limits);
        // Not in checkpoints written before the blade swept: none.
        point_heat.set_swept_account(
          in.at_end() ?
            typename PointHeatExchange<dim>::SweptAccount() :
            in.get<typename PointHeatExchange<dim>::SweptAccount>());
      });
  }

  template <int dim>
  void
  RunReport<dim>::progress_when_due(
    const SimulationControl                      &control,
    const std::function<MetalPeakTemperatures()> &T_max,
    const std::function<MeltPoolSize()>          &pool) const
  {
    if (!control.progress_due())
      return;
    const MetalPeakTemperatures T = T_max();
    progress(control, T, pool());
  }

  template <int dim>
  void
  RunReport<dim>::progress(const SimulationControl     &control,
                           const MetalPeakTemperatures &T_max,
                           const MeltPoolSize          &pool) const
  {
    const double time = control.time();
    const double wall = control.wall_time();
    // (The estimate at the last step is round-off: shown as 0.)
    const double left =
      control.wall_time_left() < 0.01 ? 0. : control.wall_time_left();
    progress::reported();
    out << std::setprecision(4) << "t = " << std::setw(10) << time
        << " s  step " << std::setw(7) << control.step()
        << "  dt = " << std::setw(10) << control.time_step()
        << " s  T_max(attached metal) = ";
    // (No metal attached, or none detached: 'none'.)
    const auto temperature = [this](const std::optional<double> &T) {
      if (T)
        out << std::setw(8) << *T << " K";
      else
        out << std::setw(10) << "none";
    };
    temperature(T_max.attached);
    out << "  T_max(detached metal) = ";
    temperature(T_max.detached);
    // The pool of a scene with a laser (a thermal shock or a flow check
    // without one shows none).
    if (with_laser && pool.length <= 0 && pool.width <= 0 && pool.depth <= 0)
      out << "  melt pool none (no metal of the workpiece above the liquidus)";
    else if (with_laser)
      {
        out << "  melt pool L";
        if (dim == 3) // in 2D the pool has a length and a depth only
          out << " x W";
        out << " = " << pool.length * 1e6;
        if (dim == 3)
          out << " x " << pool.width * 1e6;
        out << " um, depth into the substrate " << pool.depth * 1e6 << " um";
      }
    out << "  wall " << std::setprecision(4) << wall << " s, ~"
        << std::setprecision(3) << left << " s left" << std::endl;
  }

  template <int dim>
  void
  RunReport<dim>::finish(const SimulationControl       &control,
                         const HeatTransfer<dim>       &heat,
                         const MaterialPoints<dim>     &points,
                         const IncompressibleFlow<dim> *flow,
                         const SolidSubCycle<dim>      *solid,
                         const PointHeatExchange<dim>  &point_heat)
  {
    const bool heat_enabled = !heat.is_frozen();
    s.steps                 = control.step();
    s.time                  = control.time();
    s.T_max                 = heat.max_temperature();
    s.moved_points          = point_heat.moved_points_energy();
    if (flow)
      s.flow_limits = flow->subcycle_record();

    const auto e = heat.energy_budget();
    s.laser      = e.laser;
    s.losses     = heat.total_losses();
    s.boundary   = e.boundary;
    s.advection  = e.advection;
    s.stored     = heat.stored_enthalpy() - H0;
    if (heat.lists_evaporated_mass() && points.carried())
      {
        const auto &a = point_heat.evaporated_mass_account();
        s.evaporated_mass =
          e.evaporation / heat.material().latent_heat_evaporation;
        s.removed_mass     = a.removed;
        s.removed_enthalpy = a.enthalpy;
        removal            = true;
        removal_account    = a;
      }
    {
      const auto &a    = point_heat.swept_account();
      s.swept_mass     = a.mass;
      s.swept_enthalpy = a.enthalpy;
      s.swept_points   = a.points;
      s.swept_bodies   = a.bodies;
    }
    s.n_points = points.n_global_points();
    {
      using P = typename MaterialPoints<dim>::PropertyIndex;
      // Cell by cell in the order of the owned cells (not the handler's,
      // which depends on the history of insertions: a resumed run sums in
      // the same order).
      double sum = 0;
      for (std::size_t c = 0; c < points.occupied_cells().size(); ++c)
        for (const double *p : points.cell_point_properties(c))
          sum += p[P::temperature];
      s.point_T_mean =
        Utilities::MPI::sum(sum, comm) / std::max<double>(1, s.n_points);
    }
    if (solid)
      {
        s.solid_steps  = solid->n_steps();
        s.solid_energy = solid->energies();
        const auto &se = s.solid_energy;
        out << std::setprecision(6) << "Solid: " << s.solid_steps
            << " steps of " << solid->time_step() << " s; energies (J"
            << (dim == 2 ? "/m" : "") << "): external work " << se.external
            << ", stress work " << se.internal << ", kinetic " << se.kinetic
            << ", hourglass " << se.hourglass;
        if (se.withheld != 0) // light nodes with the melt flow
          out << ", withheld at light nodes " << se.withheld;
        out << ", balance " << se.balance() << "; kinetic / |stress work| "
            << se.kinetic / std::max(1e-300, std::abs(se.internal))
            << std::endl;
        const auto hd = solid->largest_hourglass_distortion(); // collective
        if (hd[0] >= 0)
          out << "Solid: largest hourglass distortion of a finite element's "
                 "corners "
              << std::setprecision(3) << hd[0] << " (limit " << hd[1] << ")"
              << std::setprecision(6) << std::endl;
        const unsigned long held = solid->n_points_held(); // collective
        if (held > 0)
          out << "Solid: " << held
              << " time(s) a material point (spatter moving with the melt's "
                 "velocity) reached a face of the domain and was held there"
              << std::endl;
        const unsigned long held_top =
          solid->n_points_held_at_zone_top(); // collective
        const unsigned long held_lateral =
          solid->n_points_held_at_zone_lateral();                  // collective
        const double held_kinetic = solid->kinetic_held_at_zone(); // collective
        if (held_top + held_lateral > 0)
          out << "Solid: a material point crossed a face of the "
                 "finite-element zone (less than half a point spacing into "
                 "the zone) and was held on it: "
              << held_top << " time(s) on its top face, " << held_lateral
              << " time(s) on a lateral face; the velocities into the zone "
                 "removed carried "
              << std::setprecision(3) << held_kinetic << std::setprecision(6)
              << (dim == 2 ? " J/m" : " J")
              << " of kinetic energy (booked by the next transfer)"
              << std::endl;
        if (solid->n_points_set_aside() > 0)
          out << "Solid: " << solid->n_points_set_aside()
              << " time(s) a solid point in a detached drop (Heat "
                 "transfer/Detached drops) was set aside, out of the solid"
              << std::endl;
        if (solid->n_points_removed() > 0)
          out << "Solid: " << solid->n_points_removed()
              << " of its points were swept by the recoater's blade (their "
                 "kinetic energy booked with the melted points')"
              << std::endl;
      }
    print_energy(e, heat_enabled, flow != nullptr);
    if (flow)
      {
        const auto &st           = flow->statistics();
        s.flow_steps             = st.steps;
        s.pressure_matrix_builds = st.matrix_rebuilds;
        s.pressure_cg_iterations = st.cg_iterations;
        s.max_fluid_speed        = st.max_point_speed;
        print_flow(*flow);
      }
  }

  template <int dim>
  void
  RunReport<dim>::print_energy(
    const typename HeatTransfer<dim>::EnergyBudget &e,
    const bool                                      heat_enabled,
    const bool                                      with_flow) const
  {
    if (!heat_enabled)
      {
        out << "Energy: heat transfer off (Physics/Heat transfer = false), "
               "temperature frozen at its initial field"
            << std::endl;
        return;
      }
    // The balance error relative to the energy that came in or went out;
    // in a scene where none did (a frozen or closed scene), the absolute
    // error in J.
    const std::string unit = dim == 2 ? "J/m" : "J";
    const double scale     = std::max(s.laser + std::abs(s.boundary), s.losses);
    const auto   error = [&](const std::string &what, const double imbalance) {
      std::ostringstream o;
      o << std::setprecision(6);
      if (scale > 0)
        o << "relative balance error " << what
          << " / max(laser + |fixed faces|, losses) " << imbalance / scale;
      else
        o << "balance error " << what << " " << imbalance << " " << unit
          << " (no energy in or out)";
      return o.str();
    };
    out << std::setprecision(6) << "Energy (" << unit << "): laser " << s.laser
        << ", surface losses " << s.losses << " (evaporation " << e.evaporation
        << ", convection " << e.convection << ", radiation " << e.radiation
        << " at the end of each step), fixed faces " << s.boundary
        << ", stored " << s.stored << "; ";
    // Carried away: by the evaporated mass, by the recoater's blade.
    const bool swept   = s.swept_points > 0;
    const bool carried = removal || swept;
    if (carried)
      {
        out << "carried away";
        if (removal)
          out << " by the evaporated mass " << s.removed_enthalpy;
        if (swept)
          out << (removal ? "," : "") << " by the recoater's blade "
              << s.swept_enthalpy;
        out << "; "
            << error("|laser + fixed faces - losses - carried - stored|",
                     std::abs(s.laser + s.boundary - s.losses -
                              s.removed_enthalpy - s.swept_enthalpy - s.stored))
            << std::endl;
      }
    else
      out << error("|laser + fixed faces - losses - stored|",
                   std::abs(s.laser + s.boundary - s.losses - s.stored))
          << std::endl;
    if (removal)
      out << std::setprecision(6) << "  evaporated mass ("
          << (dim == 2 ? "kg/m" : "kg") << "): " << s.evaporated_mass
          << " (its latent heat L_v m is the evaporation loss), taken from "
             "the points "
          << s.removed_mass << " (" << removal_account.deleted
          << " points deleted), where no melt held it "
          << removal_account.not_removed
          << "; carried away: its sensible and melting heat (above)"
          << std::endl;
    if (swept)
      out << std::setprecision(6) << "  swept by the recoater's blade ("
          << (dim == 2 ? "kg/m" : "kg") << "): " << s.swept_mass << " in "
          << s.swept_points << " points of " << s.swept_bodies
          << " detached bodies above the layers' tops; carried away: their "
             "sensible and melting heat (above)"
          << std::endl;
    if (e.laser_incident > 0)
      out << std::setprecision(6) << "  ray-traced laser (" << unit
          << "): incident " << e.laser_incident << ", absorbed " << e.laser
          << " (fraction " << e.laser / e.laser_incident << "), escaping "
          << e.laser_escaped
          << "; relative error |absorbed + escaping - incident| / incident "
          << std::abs(e.laser + e.laser_escaped - e.laser_incident) /
               e.laser_incident
          << std::endl;
    if (with_flow)
      out << std::setprecision(6) << "  with melt flow, energy created ("
          << unit << "): by the upwind convection of T " << s.advection
          << ", by points moving between cells " << s.moved_points
          << "; with these counted as sources, "
          << error(carried ?
                     "|laser + fixed faces + created - losses - carried - "
                     "stored|" :
                     "|laser + fixed faces + created - losses - stored|",
                   std::abs(s.laser + s.boundary + s.advection +
                            s.moved_points - s.losses - s.removed_enthalpy -
                            s.swept_enthalpy - s.stored))
          << std::endl;
  }

  template <int dim>
  void
  RunReport<dim>::print_flow(const IncompressibleFlow<dim> &flow) const
  {
    const auto &st = flow.statistics();
    out << "Melt flow: " << st.steps << " fluid steps (" << st.halvings
        << " redone as two halves), pressure CG " << std::setprecision(3)
        << double(st.cg_iterations) / std::max(1u, st.steps)
        << " iterations per solve (at most " << st.max_iterations << "), "
        << st.n_fluid_cells << " fluid cells and largest point speed "
        << st.max_point_speed << " m/s at the end" << std::endl;
    if (flow.expels())
      out << "Melt flow front wall expulsion: " << st.expelling_cell_steps
          << " expelling cells over " << st.expelling_steps
          << " fluid steps, fastest Bernoulli speed " << st.max_expulsion_speed
          << " m/s" << std::endl;
    if (st.volume_skipped > 0)
      out << "Melt flow volume correction: " << st.volume_skipped
          << " solves not converged (no correction in those steps)"
          << std::endl;
    const auto &r = s.flow_limits;
    out << std::setprecision(4)
        << "Melt flow time step limits (smallest over the run): "
        << "convective " << r.convective << " s, viscous " << r.viscous
        << " s, capillary ";
    if (std::isfinite(r.capillary))
      out << r.capillary << " s (used x " << r.capillary_fraction << ")\n";
    else
      out << "none (no surface tension)\n";
    out << "  sub-steps governed by: convective " << r.governed[0]
        << ", viscous " << r.governed[1] << ", capillary " << r.governed[2]
        << ", prescribed (Melt flow/Time step) " << r.governed[3]
        << "; sub-steps per temperature step "
        << (r.max_substeps > 0 ? r.min_substeps : 0) << " to " << r.max_substeps
        << std::endl;
    if (r.idle_steps > 0)
      out << "  melt flow idle (no fluid, no metal above the solidus) in "
          << r.idle_steps << " temperature steps" << std::endl;
  }

  template class RunReport<2>;
  template class RunReport<3>;
} // namespace femp
