// femp: BuildSteps (see the header): the layer schedule, the recoat in the
// step where a layer starts, the hand-over of cooled rows to the FE zone
// after it, the pore detector's output and the record of each track.
#include <deal.II/base/mpi.h>

#include <femp/app/build_steps.h>
#include <femp/app/run_checks.h>

#include <algorithm>
#include <boost/serialization/map.hpp>
#include <boost/serialization/string.hpp>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <limits>
#include <set>
#include <sstream>

namespace femp
{
  namespace
  {
    /// Whether @p layer starts in the step [t, t + dt): the one step that
    /// recoats it and closes the cost row of the layer before it.
    template <typename Layer>
    bool
    starts_in_step(const Layer &layer, const double t, const double dt)
    {
      return layer.start_time >= t && layer.start_time < t + dt;
    }

    /// @p a less @p b member by member: the fluid cells of a window, from
    /// two sums of IncompressibleFlow::FluidLoad.
    template <typename Load>
    Load
    load_difference(const Load &a, const Load &b)
    {
      Load d;
      d.all     = a.all - b.all;
      d.busiest = a.busiest - b.busiest;
      d.own     = a.own - b.own;
      return d;
    }
  } // namespace

  template <int dim>
  BuildSteps<dim>::BuildSteps(const Scene<dim> &scene, const Laser<dim> &laser)
      : scene(scene)
      , laser(laser)
  {
    if (scene.build.enabled())
      schedule = std::make_unique<LayerSchedule<dim>>(
        scene.build,
        laser.segments(),
        scene.points.substrate_top + std::max(0., scene.points.layer_thickness),
        scene.grid.upper_corner[dim - 1],
        scene.grid.cell_size);
  }

  template <int dim>
  void
  BuildSteps<dim>::setup(const BackgroundGrid<dim> &grid,
                         const MaterialPoints<dim> &points,
                         const HeatTransfer<dim>   &heat,
                         const SimulationControl   &control,
                         ResultsOutput<dim>        &results)
  {
    grid_ptr    = &grid;
    heat_ptr    = &heat;
    results_ptr = &results;
    if (schedule)
      recoater = std::make_unique<Recoater<dim>>(scene.points,
                                                 scene.material.density,
                                                 grid);
    if (schedule && scene.handover.enabled)
      handover = std::make_unique<FeZoneHandover<dim>>(
        scene.handover,
        grid,
        scene.material.solidus,
        scene.points.substrate_top + std::max(0., scene.points.layer_thickness),
        scene.points.substrate_top);
    // Tracks and layers: tracks.csv, layers.csv, probe lines per track.
    std::vector<double> starts;
    if (schedule)
      for (const auto &l : schedule->layers())
        starts.push_back(l.start_time);
    const auto list = TrackRecord<dim>::find_tracks(laser.segments(), starts);
    if (scene.track_record.enabled(list.size(), schedule != nullptr) &&
        scene.heat_enabled && !list.empty())
      tracks = std::make_unique<TrackRecord<dim>>(grid,
                                                  list,
                                                  scene.material.solidus,
                                                  scene.output.directory);
    if (!(scene.porosity.enabled(schedule != nullptr) && points.carried()))
      return;
    pores = std::make_unique<PoreDetector<dim>>(scene.porosity,
                                                grid,
                                                scene.points.substrate_top);
    // Pores and unfused powder with every field output: rows of
    // porosity.csv and pores.csv, and three cell fields.
    results.add_fields(
      {"pore", "unfused_powder", "partially_molten"},
      [this, &grid, &points, &heat, &control](
        std::vector<std::vector<double>> &v) {
        auto shares = PoreDetector<dim>::powder_shares(grid,
                                                       points,
                                                       scene.material.solidus,
                                                       scene.material.liquidus);
        auto r      = pores->find(heat.metal_fraction(), &shares.first);
        pores->write(scene.output.directory,
                     control.output_number(),
                     control.time(),
                     r);
        v.resize(3);
        v[0] = std::move(r.pore_number);
        v[1] = std::move(shares.first);
        v[2] = std::move(shares.second);
      },
      ResultsOutput<dim>::Reach::files,
      false);
    typename ResultsOutput<dim>::Writer w;
    w.resume = [this](const double time) {
      pores->resume(scene.output.directory, time);
    };
    results.add_writer(w);
  }

  template <int dim>
  void
  BuildSteps<dim>::recoat(const double              t,
                          const double              dt,
                          MaterialPoints<dim>      &points,
                          PointHeatExchange<dim>   &point_heat,
                          TimerOutput              &timer,
                          const ConditionalOStream &pcout,
                          SolidSubCycle<dim>       *solid)
  {
    if (!recoater)
      return;
    for (const auto &layer : schedule->layers())
      {
        // Each layer in the one step whose [t, t + dt) holds its start
        // (the same steps after a resume: no state to save).
        if (!starts_in_step(layer, t, dt))
          continue;
        TimerOutput::Scope scope(timer, "recoat");
        const double       T = scene.build.powder_temperature > 0 ?
                                 scene.build.powder_temperature :
                                 scene.heat.reference_temperature;
        // The surface: the metal attached to the build (the workpiece of
        // the current alpha); the blade sweeps the detached metal above
        // the layer's top, and the stored heat it takes is booked. (alpha
        // follows every module that moves points: renewed here only if
        // one did not.)
        point_heat.follow_points();
        const auto &alpha    = heat_ptr->metal_fraction();
        const auto &attached = point_heat.bodies().workpiece_cells();
        // The solid counts its points: it learns of the swept ones before
        // they go and checks its count after (their kinetic energy leaves
        // it as melted points' does).
        typename Recoater<dim>::RemovalHook tell_solid;
        if (solid)
          tell_solid = [&](const std::vector<types::particle_index> &ids) {
            solid->before_points_removed(ids);
          };
        const auto r = recoater->recoat(
          points,
          layer,
          T,
          alpha,
          attached,
          [&](const double T_point) {
            return point_heat.removed_enthalpy_per_mass(T_point);
          },
          tell_solid);
        const double swept_solid = solid ? solid->points_removed() : 0.;
        if (r.swept_points > 0)
          point_heat.book_swept(
            {r.swept_mass, r.swept_points, r.swept_bodies, r.swept_enthalpy});
        // The new points: alpha and the heat of the cells they entered.
        point_heat.follow_points();
        pcout << "Recoat: layer " << r.layer << " at t = " << t
              << " s: the blade swept " << r.swept_bodies
              << " detached bodies above the top (" << r.swept_points
              << " points";
        if (solid)
          pcout << ", " << swept_solid << " of them in the solid";
        pcout << ", " << std::setprecision(4) << r.swept_mass
              << (dim == 3 ? " kg" : " kg/m") << "); " << r.grains
              << " grains, packing fraction " << std::setprecision(3)
              << r.packing << " of the " << r.fill_volume
              << (dim == 3 ? " m^3" : " m^2")
              << " between the surface (attached metal, z " << r.surface_min
              << " to " << r.surface_max << " m";
        if (r.columns_on_drops > 0)
          pcout << "; " << r.columns_on_drops
                << " columns rest on detached drops below the top";
        pcout << ") and the top " << layer.top << " m; " << r.points
              << " points at " << T << " K" << std::setprecision(6)
              << std::endl;
        // The hand-over is a section of its own, not inside the recoat's.
        scope.stop();
        if (handover && solid)
          hand_over(t, layer.top, points, *solid, timer, pcout, true);
      }
    // With 'Hand-over checks per layer' n > 1: the choices within each
    // layer from the second on, at its start + j/n of its window (a
    // function of the time: the same steps after a resume).
    const int n = scene.handover.checks;
    if (!(handover && solid && n > 1))
      return;
    const auto &layers = schedule->layers();
    for (std::size_t i = 0; i < layers.size(); ++i)
      {
        const double a = layers[i].start_time;
        const double b = i + 1 < layers.size() ? layers[i + 1].start_time :
                                                 scene.time.end_time;
        for (int j = 1; j < n; ++j)
          if (const double tc = a + j * (b - a) / n; tc >= t && tc < t + dt)
            hand_over(t, layers[i].top, points, *solid, timer, pcout, false);
      }
  }

  template <int dim>
  void
  BuildSteps<dim>::hand_over(const double              t,
                             const double              top,
                             MaterialPoints<dim>      &points,
                             SolidSubCycle<dim>       &solid,
                             TimerOutput              &timer,
                             const ConditionalOStream &pcout,
                             const bool                layer_start)
  {
    TimerOutput::Scope scope(timer, "FE zone hand-over");
    // The zone's top face has moved since it was set; the fill of the row
    // above reads it (fe_zone_handover.h). The pores of the metal as the
    // detector finds them (its parameters; with or without its output).
    const std::vector<double> lift   = solid.zone_top_lift();
    const auto               &alpha  = heat_ptr->metal_fraction();
    const auto                shares = PoreDetector<dim>::powder_shares(
      *grid_ptr, points, scene.material.solidus, scene.material.liquidus);
    const PoreDetector<dim> detector(scene.porosity,
                                     *grid_ptr,
                                     scene.points.substrate_top);
    const auto              found = detector.find(alpha, &shares.first);
    const double            new_top =
      layer_start ?
                   handover->choose_top(
          top, points, solid.fe_zone_cells(), lift, alpha, found.pore_number) :
                   handover->choose_in_layer(
          points, solid.fe_zone_cells(), lift, alpha, found.pore_number);
    // The top of the zone's bounding box before the cells chosen.
    const double old_top = handover->zone_top();
    pcout << "FE zone hand-over at t = " << t << " s"
          << (layer_start ? "" : " (within the layer)") << ": deepest fusion "
          << handover->kept_depth() << " m (the layer "
          << (layer_start ? "before" : "so far") << " melted down to "
          << handover->last_lowest_molten() << " m), rows up to "
          << handover->limit() << " m";
    if (scene.handover.surface_limit)
      pcout << " and, per column, up to the lowest metal surface near it "
               "less the penetration depth "
            << handover->kept_penetration() << " m and the margin (down to "
            << handover->surface_limit() << " m)";
    if (!handover->stop_reason().empty())
      pcout << " (" << handover->stop_reason() << ")";
    if (scene.handover.rule == FeZoneHandover<dim>::Parameters::Rule::reheating)
      {
        // The rise at the limit's depth below the top: the envelope's and
        // the layer before's (the log).
        const auto       &env = handover->rise_envelope();
        const std::size_t k   = std::size_t(
          std::clamp(std::floor((top - handover->limit()) / grid_ptr->h()),
                     0.,
                     double(env.size() - 1)));
        pcout << std::setprecision(6)
              << "; the predicted peaks of the new layer reach "
              << handover->handed_peak_prediction() << " K in the cells taken, "
              << handover->hottest_prediction()
              << " K in those kept for it (the rise at the limit's depth "
              << env[k] << " K";
        if (!handover->layer_rises().empty())
          pcout << ", in the layer before " << handover->layer_rises().back()[k]
                << " K";
        pcout << ")";
      }
    if (!handover->least_fill().empty())
      {
        const auto [lo, hi] = std::minmax_element(lift.begin(), lift.end());
        pcout << "; the row at the zone's top reads a fill down to "
              << std::setprecision(3) << handover->least_fill()[0]
              << " (the top face moved by " << (lift.empty() ? 0. : *lo)
              << " to " << (lift.empty() ? 0. : *hi) << " m)"
              << std::setprecision(6);
      }
    const auto &cells = handover->chosen_cells();
    // Why the solid points of the zone's columns stay points (the classes
    // of FeZoneHandover::Kept), against the solid's MPM points.
    auto print_kept = [&]() {
      double n = 0;
      for (const double p : handover->kept_points())
        n += p;
      const double n_mpm = solid.sizes()[0];
      pcout << "FE zone hand-over at t = " << t
            << " s, cells (solid points) kept as points in the zone's "
               "columns:";
      for (unsigned int k = 0; k < FeZoneHandover<dim>::n_kept; ++k)
        pcout << (k ? ", " : " ") << FeZoneHandover<dim>::kept_name(k) << " "
              << handover->kept_cells()[k] << " (" << handover->kept_points()[k]
              << ")";
      pcout << "; " << n << " of the solid's " << n_mpm << " MPM points"
            << std::endl;
    };
    if (cells.empty())
      {
        pcout << "; the zone's top stays at " << old_top << " m" << std::endl;
        print_kept();
        return;
      }
    const double K0 = solid.energies(false).melted;
    // The cell fields before and after: in the handed cells the element's
    // stress and plastic strain are the means the fields showed for the
    // points, so sigma_ii and eps_p change by round-off; von Mises by the
    // averaging (the mean of the points' against that of the mean stress).
    std::vector<std::vector<double>> before, after;
    solid.cell_fields(before);
    const std::vector<std::uint8_t> zone_before = solid.fe_zone_cells();
    const double                    m_zone      = solid.fe_zone_mass();
    const auto                      n           = solid.hand_over_cells(cells);
    solid.cell_fields(after);
    // sigma_ii, von Mises, eps_p: the largest change and value.
    double      change[3] = {0, 0, 0}, largest[3] = {0, 0, 0};
    const auto &zone_after = solid.fe_zone_cells();
    for (const auto c : grid_ptr->owned_cells())
      if (zone_after[c] && !zone_before[c])
        for (unsigned int k = 0; k < 5; ++k)
          {
            const unsigned int j = k < 3 ? 0 : k - 2;
            change[j] =
              std::max(change[j], std::abs(after[k][c] - before[k][c]));
            largest[j] = std::max(largest[j], std::abs(before[k][c]));
          }
    Utilities::MPI::max(ArrayView<const double>(change, 3),
                        grid_ptr->communicator(),
                        ArrayView<double>(change, 3));
    Utilities::MPI::max(ArrayView<const double>(largest, 3),
                        grid_ptr->communicator(),
                        ArrayView<double>(largest, 3));
    auto ratio = [&](const unsigned int j) {
      return largest[j] > 0 ? change[j] / largest[j] : 0.;
    };
    // The zone's points carry temperatures only: alpha bins them once.
    points.set_fixed_cells(solid.fe_zone_cells());
    n_handed[0] += n[0], n_handed[1] += n[1];
    // The points' mass of the handed cells against the elements' (the
    // zone's mass added), which carry the full density over their cells.
    const double m_el = solid.fe_zone_mass() - m_zone;
    pcout << "; the zone's top rises from " << old_top << " to " << new_top
          << " m: " << n[0] << " elements, " << n[1]
          << " points handed over (their mass " << std::setprecision(4)
          << (m_el > 0 ? handover->chosen_point_mass() / m_el : 0.)
          << " of the elements' at the full density)" << std::setprecision(6)
          << ", their kinetic energy " << solid.energies(false).melted - K0
          << (dim == 2 ? " J/m" : " J")
          << " removed; in the handed cells sigma_ii changed by "
          << std::setprecision(2) << ratio(0) << " of the largest |sigma_ii| ("
          << largest[0] << " Pa), plastic strain by " << ratio(2)
          << " of the largest (" << largest[2] << "), von Mises by " << ratio(1)
          << " of the largest (" << largest[1] << " Pa, the averaging)"
          << std::setprecision(6) << std::endl;
    print_kept();
  }

  template <int dim>
  void
  BuildSteps<dim>::record_tracks(const double               t,
                                 const double               dt,
                                 const bool                 last,
                                 const MaterialPoints<dim> &points,
                                 TimerOutput               &timer,
                                 const ConditionalOStream  &pcout)
  {
    if (!tracks || (!last && !tracks->due(t + dt)))
      return;
    TimerOutput::Scope scope(timer, "track record");
    // The fused metal fraction alpha (1 - s_p): unfused powder is no bead.
    std::vector<double> fused = heat_ptr->metal_fraction();
    if (points.carried())
      {
        const auto shares = PoreDetector<dim>::powder_shares(
          *grid_ptr, points, scene.material.solidus, scene.material.liquidus);
        for (std::size_t i = 0; i < fused.size(); ++i)
          fused[i] *= 1. - shares.first[i];
      }
    const auto rows =
      last ? tracks->finish(t, fused, heat_ptr->temperature()) :
             tracks->update(t, t + dt, fused, heat_ptr->temperature());
    for (const auto &r : rows)
      {
        results_ptr->write_probe_lines("track_" +
                                         Utilities::int_to_string(r.track, 3),
                                       t);
        pcout << "Track " << r.track << " (layer " << r.layer
              << ") measured at t = " << t << " s: bead height "
              << r.bead_height << " m, width " << r.width
              << " m, re-melt depth " << r.remelt_depth << " m, overlap "
              << r.overlap_ratio << std::endl;
      }
    if (last)
      results_ptr->write_probe_lines("end", t);
  }

  namespace
  {
    /// The column of a part of the step: wall_<part>, lower case, every
    /// run of other characters than letters and digits as one '_'.
    std::string
    cost_column(const std::string &part)
    {
      std::string c = "wall_";
      for (const char x : part)
        if (std::isalnum(static_cast<unsigned char>(x)))
          c += static_cast<char>(std::tolower(static_cast<unsigned char>(x)));
        else if (c.back() != '_')
          c += '_';
      while (c.back() == '_')
        c.pop_back();
      return c;
    }

    /// The timer's wall time so far per column (part of the step), s.
    std::map<std::string, double>
    cost_parts(const TimerOutput &timer)
    {
      std::map<std::string, double> p;
      for (const auto &[name, t] :
           timer.get_summary_data(TimerOutput::total_wall_time))
        p[cost_column(part_of(name))] += t;
      return p;
    }
  } // namespace

  template <int dim>
  void
  BuildSteps<dim>::open_cost(const unsigned int        layer,
                             const double              t,
                             const unsigned int        step,
                             const TimerOutput        &timer,
                             const SolidSubCycle<dim> *solid)
  {
    cost_open         = CostRow();
    cost_open.layer   = layer;
    cost_open.t_start = t;
    // The counts after the layer's recoat and hand-over: at the next step.
    cost_counted    = false;
    cost_step       = step;
    cost_solid_step = solid ? solid->n_steps() : 0;
    cost_flow_step  = flow_substeps();
    cost_fluid      = fluid_load();
    cost_sections   = cost_parts(timer);
    cost_carried.clear();
    cost_clock = std::chrono::steady_clock::now();
  }

  template <int dim>
  void
  BuildSteps<dim>::start_cost(const double              t,
                              const unsigned int        step,
                              const bool                resuming,
                              const TimerOutput        &timer,
                              const SolidSubCycle<dim> *solid,
                              const CostCarry          *carried)
  {
    if (!schedule)
      return;
    // The layer in progress: 1 + the layers that started before t (a
    // layer starting at t itself closes this row in the next step).
    unsigned int layer = 1;
    for (const auto &l : schedule->layers())
      if (l.start_time < t)
        layer = std::max(layer, l.number);
    cost_rows.clear();
    if (resuming &&
        Utilities::MPI::this_mpi_process(grid_ptr->communicator()) == 0)
      {
        // The rows of the layers that ended before the checkpoint, as the
        // run that wrote it left them.
        std::ifstream            f(scene.output.directory + "/layer_cost.csv");
        std::string              line;
        std::vector<std::string> names;
        if (std::getline(f, line))
          {
            std::istringstream h(line);
            for (std::string c; std::getline(h, c, ',');)
              names.push_back(c);
          }
        while (std::getline(f, line))
          {
            std::istringstream in(line);
            CostRow            r;
            std::size_t        k = 0;
            for (std::string c; std::getline(in, c, ',') && k < names.size();
                 ++k)
              {
                // A cell that is no number (a file cut short): 0.
                const double v = std::strtod(c.c_str(), nullptr);
                const auto  &n = names[k];
                if (n == "layer")
                  r.layer = static_cast<unsigned int>(v);
                else if (n == "t_start")
                  r.t_start = v;
                else if (n == "t_end")
                  r.t_end = v;
                else if (n == "wall_total")
                  r.wall = v;
                else if (n == "temperature_steps")
                  r.steps = v;
                else if (n == "solid_steps")
                  r.solid_steps = v;
                else if (n == "flow_steps")
                  r.flow_steps = v;
                else if (n == "max_wall_total")
                  r.max_wall = v;
                else if (n.rfind("max_wall_", 0) == 0)
                  r.max_parts[n.substr(4)] = v;
                else if (n == "points")
                  r.points = v;
                else if (n == "mpm_points")
                  r.mpm_points = v;
                else if (n == "fe_elements")
                  r.elements = v;
                else if (n == "mpm_share_max")
                  r.mpm_share_max = v;
                else if (n == "fluid_cells")
                  r.fluid_cells = v;
                else if (n == "fluid_share_max")
                  r.fluid_share_max = v;
                else if (n == "fluid_step_share_max")
                  r.fluid_step_share_max = v;
                else if (n.rfind("kept_", 0) == 0)
                  r.kept[n] = v;
                else if (v > 0)
                  r.parts[n] = v;
              }
            if (r.layer < layer)
              cost_rows.push_back(r);
          }
      }
    open_cost(layer, t, step, timer, solid);
    if (carried && carried->layer == layer)
      {
        // After a rebalance in this process: the window goes on from the
        // layer's start, its wall and parts so far and the rebalance's
        // wall added at its close.
        cost_open.t_start = carried->t_start;
        cost_step -= static_cast<unsigned int>(carried->steps);
        cost_solid_step -= static_cast<unsigned int>(carried->solid_steps);
        cost_flow_step -= carried->flow_steps;
        cost_fluid   = load_difference(cost_fluid, carried->fluid);
        cost_carried = carried->parts;
        if (carried->rebalance_wall > 0)
          cost_carried["wall_rebalance"] += carried->rebalance_wall;
        cost_clock -=
          std::chrono::duration_cast<std::chrono::steady_clock::duration>(
            std::chrono::duration<double>(carried->wall +
                                          carried->rebalance_wall));
      }
    cost_started = true;
  }

  template <int dim>
  typename BuildSteps<dim>::CostCarry
  BuildSteps<dim>::carry_cost(const unsigned int        step,
                              const TimerOutput        &timer,
                              const SolidSubCycle<dim> *solid) const
  {
    CostCarry c;
    if (!cost_started)
      return c;
    c.layer   = cost_open.layer;
    c.t_start = cost_open.t_start;
    c.wall    = std::chrono::duration<double>(std::chrono::steady_clock::now() -
                                           cost_clock)
               .count();
    c.steps       = step - cost_step;
    c.solid_steps = solid ? solid->n_steps() - cost_solid_step : 0;
    c.flow_steps  = flow_substeps() - cost_flow_step;
    c.fluid       = load_difference(fluid_load(), cost_fluid);
    c.parts       = cost_carried;
    for (const auto &[col, w] : cost_parts(timer))
      {
        const auto   it = cost_sections.find(col);
        const double d  = w - (it == cost_sections.end() ? 0. : it->second);
        if (d > 0)
          c.parts[col] += d;
      }
    return c;
  }

  template <int dim>
  unsigned int
  BuildSteps<dim>::layer_starting(const double t, const double dt) const
  {
    if (schedule)
      for (const auto &l : schedule->layers())
        if (starts_in_step(l, t, dt))
          return l.number;
    return 0;
  }

  template <int dim>
  void
  BuildSteps<dim>::record_cost(const double               t,
                               const double               dt,
                               const bool                 last,
                               const unsigned int         step,
                               const TimerOutput         &timer,
                               const MaterialPoints<dim> &points,
                               const SolidSubCycle<dim>  *solid)
  {
    if (!cost_started)
      return;
    if (!cost_counted)
      {
        cost_open.points = points.n_global_points();
        if (solid)
          {
            const auto n         = solid->sizes();
            cost_open.mpm_points = n[0];
            cost_open.elements   = n[1];
            // The partition's balance of the solid's point loops.
            const double n_max      = solid->largest_rank_points();
            cost_open.mpm_share_max = n[0] > 0 ? n_max / n[0] : 0.;
          }
        if (handover)
          for (unsigned int k = 0; k < FeZoneHandover<dim>::n_kept; ++k)
            {
              const std::string c = FeZoneHandover<dim>::kept_name(k);
              cost_open.kept["kept_cells_" + c]  = handover->kept_cells()[k];
              cost_open.kept["kept_points_" + c] = handover->kept_points()[k];
            }
        cost_counted = true;
      }
    const typename LayerSchedule<dim>::Layer *next = nullptr;
    if (!last)
      for (const auto &l : schedule->layers())
        if (starts_in_step(l, t, dt))
          next = &l;
    if (!last && !next)
      return;
    CostRow r = cost_open;
    r.t_end   = t;
    r.wall    = std::chrono::duration<double>(std::chrono::steady_clock::now() -
                                           cost_clock)
               .count();
    for (const auto &[c, w] : cost_parts(timer))
      {
        const auto   it = cost_sections.find(c);
        const double d  = w - (it == cost_sections.end() ? 0. : it->second);
        if (d > 0)
          r.parts[c] = d;
      }
    for (const auto &[c, w] : cost_carried)
      r.parts[c] += w;
    r.steps       = step - cost_step;
    r.solid_steps = solid ? solid->n_steps() - cost_solid_step : 0;
    r.flow_steps  = flow_substeps() - cost_flow_step;
    // The largest wall over the ranks, in total and per part (the parts of
    // every rank).
    const MPI_Comm comm = grid_ptr->communicator();
    // The flow's balance: fluid cells (global) and this rank's own.
    const auto f  = load_difference(fluid_load(), cost_fluid);
    r.fluid_cells = f.all;
    if (r.fluid_cells > 0)
      {
        r.fluid_share_max = Utilities::MPI::max(f.own, comm) / r.fluid_cells;
        r.fluid_step_share_max = f.busiest / r.fluid_cells;
      }
    r.max_wall = Utilities::MPI::max(r.wall, comm);
    for (const auto &parts : Utilities::MPI::all_gather(comm, r.parts))
      for (const auto &[c, w] : parts)
        r.max_parts[c] = std::max(r.max_parts[c], w);
    cost_rows.push_back(r);
    write_cost();
    if (next)
      open_cost(next->number, t, step, timer, solid);
  }

  template <int dim>
  void
  BuildSteps<dim>::write_cost() const
  {
    if (Utilities::MPI::this_mpi_process(grid_ptr->communicator()) != 0)
      return;
    std::set<std::string> parts, max_parts;
    for (const auto &r : cost_rows)
      {
        for (const auto &[c, w] : r.parts)
          parts.insert(c);
        for (const auto &[c, w] : r.max_parts)
          max_parts.insert(c);
      }
    // With the hand-over: its classes, cells then points.
    std::vector<std::string> kept;
    if (handover)
      for (const char *what : {"kept_cells_", "kept_points_"})
        for (unsigned int k = 0; k < FeZoneHandover<dim>::n_kept; ++k)
          kept.push_back(what + std::string(FeZoneHandover<dim>::kept_name(k)));
    std::ofstream f(scene.output.directory + "/layer_cost.csv");
    f << "layer,t_start,t_end,temperature_steps,solid_steps,flow_steps,"
         "points,mpm_points,fe_elements,mpm_share_max,fluid_cells,"
         "fluid_share_max,fluid_step_share_max";
    for (const auto &c : kept)
      f << "," << c;
    f << ",wall_total";
    for (const auto &c : parts)
      f << "," << c;
    f << ",max_wall_total";
    for (const auto &c : max_parts)
      f << ",max_" << c;
    f << "\n";
    for (const auto &r : cost_rows)
      {
        f << r.layer << "," << std::setprecision(10) << r.t_start << ","
          << r.t_end << "," << std::setprecision(15) << r.steps << ","
          << r.solid_steps << "," << r.flow_steps << "," << r.points << ","
          << r.mpm_points << "," << r.elements << "," << std::setprecision(4)
          << r.mpm_share_max << std::setprecision(15) << "," << r.fluid_cells
          << "," << std::setprecision(4) << r.fluid_share_max << ","
          << r.fluid_step_share_max << std::setprecision(15);
        for (const auto &c : kept)
          {
            const auto it = r.kept.find(c);
            f << "," << (it == r.kept.end() ? 0. : it->second);
          }
        f << std::fixed << std::setprecision(6) << "," << r.wall;
        for (const auto &c : parts)
          {
            const auto it = r.parts.find(c);
            f << "," << (it == r.parts.end() ? 0. : it->second);
          }
        f << "," << r.max_wall;
        for (const auto &c : max_parts)
          {
            const auto it = r.max_parts.find(c);
            f << "," << (it == r.max_parts.end() ? 0. : it->second);
          }
        f << std::defaultfloat << "\n";
      }
  }

  template <int dim>
  double
  BuildSteps<dim>::flow_substeps() const
  {
    return flow_ptr ? flow_ptr->statistics().steps : 0.;
  }

  template <int dim>
  typename IncompressibleFlow<dim>::FluidLoad
  BuildSteps<dim>::fluid_load() const
  {
    return flow_ptr ? flow_ptr->fluid_load() :
                      typename IncompressibleFlow<dim>::FluidLoad();
  }

  template <int dim>
  void
  BuildSteps<dim>::observe_tracks() const
  {
    if (tracks)
      tracks->observe(heat_ptr->temperature(), heat_ptr->metal_fraction());
    if (handover)
      handover->observe(heat_ptr->temperature(), heat_ptr->metal_fraction());
  }

  template <int dim>
  void
  BuildSteps<dim>::add_state(ModuleStates<dim> &states)
  {
    if (tracks)
      {
        TrackRecord<dim> *t = tracks.get();
        states.add(
          "tracks",
          [t](StateWriter &out) { t->save_state(out); },
          [t](std::vector<StateReader> &in) { t->load_state(in[0]); },
          "it was written without the track record (Build/Track report)");
      }
    if (handover)
      {
        // The fusion depths and the counts of the hand-overs so far (the
        // raised zone itself is the solid's: section "fe zone").
        FeZoneHandover<dim> *h = handover.get();
        states.add(
          "handover",
          [this, h](StateWriter &out) {
            h->save_state(out);
            out.put(n_handed);
          },
          [this, h](std::vector<StateReader> &in) {
            h->load_state(in);
            for (std::size_t f = 0; f < in.size(); ++f)
              {
                const auto n = in[f].get<std::array<double, 2>>();
                if (f == 0)
                  n_handed = n;
              }
          },
          "it was written without the hand-over of cooled metal (Build/Hand "
          "over cooled metal = false): the fusion depths of its layers are "
          "unknown; resume it with 'Hand over cooled metal = false' or start "
          "the run anew");
        // The layer-start temperatures: the re-heating rule alone keeps
        // them.
        if (scene.handover.rule ==
            FeZoneHandover<dim>::Parameters::Rule::reheating)
          states.add(
            "handover layer start",
            [h](StateWriter &out) { h->save_layer_start(out); },
            [h](std::vector<StateReader> &in) { h->load_layer_start(in); },
            "it was written without the re-heating rule's layer-start "
            "temperatures (Build/Hand-over rule = temperature): the rises of "
            "the layer it was written in are unknown; resume it with "
            "'Hand-over rule = temperature' or start the run anew");
      }
  }

  template class BuildSteps<2>;
  template class BuildSteps<3>;
} // namespace femp
