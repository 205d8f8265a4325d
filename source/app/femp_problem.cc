// femp: the top-level problem, a sequencer: builds the modules of the scene,
// registers their output and state, and runs the macro time loop of the
// paper's sec. 2.6.
#include <deal.II/base/mpi.h>
#include <deal.II/base/utilities.h>

#include <femp/app/femp_problem.h>
#include <femp/app/run_checks.h>
#include <femp/base/free_heap.h>
#include <femp/base/input_checks.h>
#include <femp/base/recoil_law.h>

#include <iomanip>

namespace femp
{
  namespace
  {
    /// One line of the scene's printout when a rebalance ratio
    /// @p ratio > 0 cannot act in this run: on one rank, without the solid
    /// or without a later layer to start.
    void
    say_if_rebalance_inert(ConditionalOStream &out,
                           const MPI_Comm      comm,
                           const double        ratio,
                           const bool          has_solid,
                           const bool          has_layer_starts)
    {
      if (ratio <= 0)
        return;
      std::string why;
      if (Utilities::MPI::n_mpi_processes(comm) < 2)
        why = "one MPI rank";
      else if (!has_solid)
        why = "no solid (Physics/Solid stress = false)";
      else if (!has_layer_starts)
        why = "one layer (no layer starts: Build/Layer schedule)";
      if (!why.empty())
        out << "  rebalance: inert, " << why
            << " (Build/Rebalance above imbalance = " << ratio
            << " acts at a layer start, on several ranks, with the solid)"
            << std::endl;
    }
  } // namespace

  template <int dim>
  FempProblem<dim>::FempProblem(ParameterHandler &prm, MPI_Comm comm)
      : comm(comm)
      , pcout(std::cout, Utilities::MPI::this_mpi_process(comm) == 0)
      , scene(prm, pcout)
      , states(scene.checkpoint,
               scene.output.directory,
               scene.checkpoint_scene(),
               comm)
      , timer(pcout, TimerOutput::never, TimerOutput::wall_times)
  {
    control = std::make_unique<SimulationControl>(scene.time, scene.cadence());
    report  = std::make_unique<RunReport<dim>>(comm, pcout);
    laser   = std::make_unique<Laser<dim>>(scene.laser);
    report->watch_laser(*laser);
    laser->check_path_inside(scene.grid.lower_corner, scene.grid.upper_corner);
    builds = std::make_unique<BuildSteps<dim>>(scene, *laser);
  }

  template <int dim>
  void
  FempProblem<dim>::setup()
  {
    {
      TimerOutput::Scope t(timer, "setup: grid");
      grid = std::make_unique<BackgroundGrid<dim>>(scene.grid, comm);
      // A resumed run weighs the cells by the checkpoint it read (a
      // build's zone and points as they are then).
      grid->create(scene.partition_cost(
        states.resuming() ? &states.checkpoint_file() : nullptr));
    }
    {
      TimerOutput::Scope t(timer, "setup: material points");
      // Points carry only the property blocks of the physics switched on.
      points = std::make_unique<MaterialPoints<dim>>(
        scene.points, scene.material, *grid, scene.n_point_properties());
      points->create(scene.heat.initial_temperature);
    }
    heat = std::make_unique<HeatTransfer<dim>>(scene.heat,
                                               scene.material,
                                               *laser,
                                               *grid);
    heat->initialize();
    heat->set_absorption_model(scene.absorption);
    if (scene.heat_enabled)
      heat->enable_front_wall_piston(
        RecoilLaw(scene.material,
                  scene.melt_flow ? scene.flow.recoil_coefficient : 0.,
                  scene.flow.recoil_above_ambient));
    if (!scene.heat_enabled)
      heat->freeze();
    // alpha's keeper, with the bodies of metal and the free surface of
    // alpha: the initial temperatures and alpha.
    point_heat = std::make_unique<PointHeatExchange<dim>>(
      *points, *heat, *grid, scene.material, scene.heat, scene.heat_enabled);
    {
      TimerOutput::Scope t(timer, "setup: metal fraction");
      point_heat->start(scene.points.bodies, scene.heat);
    }
    results =
      std::make_unique<ResultsOutput<dim>>(scene.output, *grid, *points);
    add_heat_output(*results, scene, *heat, *points, comm);
    if (scene.melt_flow)
      setup_flow();
    builds->setup(*grid, *points, *heat, *control, *results);
    builds->watch_flow(flow.get());
    add_track_shape(*results, scene, *grid, *laser, *points, *heat);
    results->initialize(states.resuming());
    if (scene.solid)
      setup_solid();
    register_states();
    time_steps = std::make_unique<TimeStepPolicy<dim>>(
      scene, *laser, *heat, point_heat->bodies(), flow.get(), pcout);
    control->set_step_chooser(
      [this](const unsigned int step, const double time) {
        return time_steps->choose(step, time, cell_fields());
      });
  }

  template <int dim>
  void
  FempProblem<dim>::setup_flow()
  {
    flow = std::make_unique<IncompressibleFlow<dim>>(
      scene.flow, scene.material, *grid, *points, &timer);
    flow->enable_front_wall_expulsion(laser->beam_radius(),
                                      scene.heat.initial_temperature);
    // The flow reads T and gamma, the heat (with 'Advection by melt flow =
    // upwind') the flow's cell velocity, from cell_fields() at each call.
    add_flow_output(*results, *flow);
  }

  template <int dim>
  void
  FempProblem<dim>::setup_solid()
  {
    TimerOutput::Scope t(timer, "setup: solid");
    solid = std::make_unique<SolidSubCycle<dim>>(
      scene.solid_stress, scene.fem, scene.solid_material, *grid, *points);
    if (flow)
      {
        // Flow and solid together (doc/solid.md): the fluid forces on the
        // solid enter through the solid's external nodal forces.
        solid->share_points_with_flow(scene.flow.affine());
        fluid_solid = std::make_unique<FluidSolidForces<dim>>(
          *grid, *points, scene.material.density, scene.fem);
      }
    // The FE zone of a checkpoint, which a hand-over may have raised: built
    // at its top from the start (checkpoints without the section hold the
    // scene's zone).
    if (states.resuming() && states.checkpoint_file().has_section("fe zone"))
      {
        auto parts = states.checkpoint_file().section("fe zone");
        solid->resume_fe_zone(parts);
      }
    // The fluid's forces take the FE zone as it is at each step.
    if (fluid_solid && solid->fe_zone())
      fluid_solid->follow_zone(*solid->fe_zone());
    // On resume the solid's CSV files are cut back and reopened by its
    // load_state() instead.
    solid->initialize(heat->temperature(),
                      states.resuming() ? std::string() :
                                          scene.output.directory);
    // The FE zone's points never move nor melt (the solid stops the run
    // otherwise): the metal fraction bins them once.
    points->set_fixed_cells(solid->fe_zone_cells());
    add_solid_output(*results, *solid);
  }

  template <int dim>
  void
  FempProblem<dim>::register_states()
  {
    // One section per module that owns state, in checkpoint order; "run"
    // holds the run's accounts that no module keeps.
    states.add("control", *control);
    states.add("heat", *heat);
    states.add("points", *points);
    states.add("output", results->output());
    states.add("trigger", states.checkpoint_file());
    report->add_state(states, *point_heat, flow.get());
    // 'Metal of melt cells = points': the heat's metal mass (read after
    // the restore, with alpha's bodies and surface).
    if (point_heat->metal_of_points())
      states.add(
        "metal mass",
        [this](StateWriter &out) { point_heat->save_metal_mass(out); },
        typename ModuleStates<dim>::Load());
    // The thermal history, when asked for, starts here: its state and its
    // files (written at the end of the run).
    add_thermal_history(*results, states, scene, *grid, *heat);
    builds->add_state(states);
    if (flow)
      states.add("flow", *flow);
    // Read before the restore, by setup_solid().
    if (solid)
      states.add(
        "fe zone",
        [this](StateWriter &out) { solid->save_fe_zone(out); },
        typename ModuleStates<dim>::Load());
    if (solid)
      states.add(
        "solid",
        [this](StateWriter &out) { solid->save_state(out); },
        [this](std::vector<StateReader> &in) {
          solid->load_state(in, scene.output.directory);
        });
    // Once all is loaded: alpha's bodies and surface, and the series
    // written outside Output cut back to the checkpoint.
    states.after_restore([this] {
      // A checkpoint written with 'Metal of melt cells = alpha' holds no
      // metal mass: the restored points' volume.
      auto &file = states.checkpoint_file();
      if (point_heat->metal_of_points() && file.has_section("metal mass"))
        {
          auto parts = file.section("metal mass");
          point_heat->metal_fraction_restored(&parts);
        }
      else
        point_heat->metal_fraction_restored();
      results->resume(control->time());
    });
  }

  template <int dim>
  typename FempProblem<dim>::End
  FempProblem<dim>::run()
  {
    control->start_clock();
    // After a rebalance the progress line goes on with the run's clock.
    if (rebalance)
      control->continue_clock(rebalance->clock);
    setup();
    // The setup's temporary lists (points, powder, the FE zone) are freed.
    release_free_heap();
    // The scene's printout counts the points the run goes on with: a
    // resumed run's after the restore.
    if (states.resuming())
      states.restore(pcout, timer);
    scene.print(pcout, comm, *grid, *points, *heat, *laser, solid.get());
    // 'Build/Rebalance above imbalance' that cannot act says why (the same
    // scene may run on one rank or without the solid).
    say_if_rebalance_inert(pcout,
                           comm,
                           scene.build.rebalance_above,
                           solid != nullptr,
                           builds->layers() &&
                             !builds->layers()->layers().empty());
    if (!states.resuming())
      {
        // The exact stability limit and the projected number of steps are
        // checked before anything is written.
        time_steps->choose(0, control->time(), cell_fields());
        report->start(*heat);
        results->write_fields(*control, timer, false);
      }
    // After a rebalance: the layer's row of layer_cost.csv goes on, with
    // the rebalance's wall (the checkpoint, the set-up and the restore).
    if (rebalance)
      {
        rebalance->cost.rebalance_wall =
          std::chrono::duration<double>(std::chrono::steady_clock::now() -
                                        rebalance->since)
            .count();
        const double ratio = mpm_imbalance();
        pcout << "Rebalance: the checkpoint, the set-up and the restore took "
              << rebalance->cost.rebalance_wall
              << " s; after it the busiest rank holds " << std::setprecision(3)
              << ratio << " times the mean of the MPM points"
              << std::setprecision(6) << std::endl;
      }
    builds->start_cost(control->time(),
                       control->step(),
                       states.resuming(),
                       timer,
                       solid.get(),
                       rebalance ? &rebalance->cost : nullptr);

    End end;
    while (control->running())
      {
        const double t0 = control->time();
        const double dt = control->next_time_step();
        time_steps->begin_step();

        // 0. The cost of the layer that ends when one starts in this step
        //    (layer_cost.csv), the record of a track that ended, then the
        //    recoat: the powder of a layer starting in this step.
        builds->record_cost(control->time(),
                            dt,
                            false,
                            control->step(),
                            timer,
                            *points,
                            solid.get());
        builds->record_tracks(
          control->time(), dt, false, *points, timer, pcout);
        //    With 'Build/Hand over cooled metal' the cooled rows below the
        //    new layer's melt pass to the solid's finite elements.
        builds->recoat(
          control->time(), dt, *points, *point_heat, timer, pcout, solid.get());

        // 1. Tag cells, alpha, gamma, properties: alpha changes only when
        //    points change cells, and PointHeatExchange::follow_points()
        //    renews it right after each module that moves them (recoat,
        //    flow, solid); gamma and the properties follow T inside
        //    HeatTransfer::advance().

        // 2. Temperature in fluid, solid and powder (eq. 1), then to the
        //    points (eq. 2).
        temperature_step(dt);
        cells_to_points();
        //    The mass that evaporated in the step leaves the points of the
        //    surface cells (Heat transfer/Remove evaporated mass).
        remove_evaporated_mass();

        // 3. Melt-pool flow (eqs. 3-4), sub-cycled, with the heat carried
        //    by the points that changed cells; with the solid, the fluid
        //    forces on it (eq. 13), held over the solid sub-steps of 4.
        if (flow)
          flow_step(dt);
        if (fluid_solid)
          fluid_forces_on_solid();
        builds->observe_tracks();

        if (time_steps->cooled_down(control->time() + dt))
          control->request_stop();
        control->advance(dt);

        // 4. Solid stress (SolidMPM + SolidFEM coupled, eqs. 5-17),
        //    sub-cycled against the temperature step.
        if (solid)
          solid_step();

        // 5. Output and checkpoint when due.
        output_results();
        if (states.due(control->step(), control->time()))
          end.checkpoint = write_checkpoint();
        //    A layer started in this step and the ranks' MPM points are
        //    uneven: a checkpoint (the trigger's, if it fired; else one
        //    kept only while it is the newest), and the run goes on from
        //    it on a grid cut by its state (run_to_end()).
        if (rebalance_due(t0, dt))
          {
            end.rebalance = true;
            end.since     = std::chrono::steady_clock::now();
            end.clock     = control->clock();
            end.cost = builds->carry_cost(control->step(), timer, solid.get());
            if (end.checkpoint.empty())
              end.checkpoint = write_checkpoint(CheckpointKind::rebalance);
            if (rebalance)
              end.timer_sums = rebalance->timer_sums;
            add_timer_sums(timer, end.timer_sums);
            pcout << "Rebalance: the run goes on from " << end.checkpoint
                  << " on a grid cut by its state" << std::endl;
            return end;
          }
        end.checkpoint.clear();
      }

    builds->record_tracks(control->time(), 0., true, *points, timer, pcout);
    builds->record_cost(
      control->time(), 0., true, control->step(), timer, *points, solid.get());
    points->flush_point_temperatures();
    report->finish(
      *control, *heat, *points, flow.get(), solid.get(), *point_heat);
    results->finish();
    // The timer's sections over the whole run, every part before a
    // rebalance included.
    print_cost_report(timer,
                      scene.output.directory,
                      comm,
                      rebalance ? rebalance->timer_sums : TimerSums());
    return end;
  }

  template <int dim>
  double
  FempProblem<dim>::mpm_imbalance() const
  {
    if (!solid)
      return 0.;
    const double n     = solid->sizes()[0];
    const double n_max = solid->largest_rank_points();
    return n > 0 ? n_max * Utilities::MPI::n_mpi_processes(comm) / n : 0.;
  }

  template <int dim>
  bool
  FempProblem<dim>::rebalance_due(const double t, const double dt) const
  {
    const double limit = scene.build.rebalance_above;
    if (limit <= 0 || !solid || !scene.grid.partition_by_cost ||
        Utilities::MPI::n_mpi_processes(comm) < 2 || !control->running())
      return false;
    const unsigned int layer = builds->layer_starting(t, dt);
    if (layer == 0)
      return false;
    // The same on every rank (a global count).
    const double ratio = mpm_imbalance();
    if (ratio <= limit)
      return false;
    pcout << "Rebalance at the start of layer " << layer
          << " (the step from t = " << t << " s): the busiest rank holds "
          << std::setprecision(3) << ratio
          << " times the mean of the MPM points (Build/Rebalance above "
             "imbalance = "
          << limit << ")" << std::setprecision(6) << std::endl;
    return true;
  }

  template <int dim>
  unsigned int
  run_to_end(std::unique_ptr<FempProblem<dim>> &problem,
             ParameterHandler                  &prm,
             MPI_Comm                           comm)
  {
    unsigned int n = 0;
    for (auto end = problem->run(); end.rebalance; end = problem->run())
      {
        // The same as 'femp --resume DIR' with the checkpoint's weights.
        prm.enter_subsection("Checkpoint");
        prm.set("Resume from", end.checkpoint);
        prm.set("Partition on resume", "checkpoint");
        prm.leave_subsection();
        problem.reset();
        problem = std::make_unique<FempProblem<dim>>(prm, comm);
        problem->continue_rebalance(end);
        ++n;
      }
    return n;
  }

  template <int dim>
  CellFields<dim>
  FempProblem<dim>::cell_fields() const
  {
    CellFields<dim> f;
    f.temperature     = &heat->temperature();
    f.liquid_fraction = &heat->liquid_fraction();
    f.metal_fraction  = &heat->metal_fraction();
    if (flow)
      f.velocity = &flow->cell_velocity();
    return f;
  }

  template <int dim>
  void
  FempProblem<dim>::temperature_step(const double dt)
  {
    if (!scene.heat_enabled)
      return;
    if (heat->ray_traced())
      {
        TimerOutput::Scope t(timer, "laser ray tracing");
        heat->trace_laser(control->time());
      }
    {
      TimerOutput::Scope t(timer, "temperature step");
      heat->advance(dt, control->time(), cell_fields());
    }
    results->after_temperature_step(control->time() + dt);
  }

  template <int dim>
  void
  FempProblem<dim>::cells_to_points()
  {
    {
      TimerOutput::Scope t(timer, "cells to points");
      points->cells_to_points(heat->temperature(), &heat->metal_fraction());
    }
    // Solid points in detached drops stay out of the solid (they may
    // change with alpha in each flow sub-cycle; read once per temperature
    // step, before the state changes are looked for).
    if (solid)
      solid->set_detached_cells(point_heat->bodies().detached_cells());
    if (flow && solid)
      {
        // Points that melted leave the solid with the velocity they had
        // in it (booked before the flow changes it).
        TimerOutput::Scope t(timer, "solid");
        solid->find_state_changes();
      }
  }

  template <int dim>
  void
  FempProblem<dim>::remove_evaporated_mass()
  {
    if (!scene.heat_enabled || !heat->lists_evaporated_mass() ||
        !points->carried())
      return;
    TimerOutput::Scope t(timer, "evaporated mass");
    point_heat->remove_evaporated_mass();
    // alpha follows: with the flow after its sub-steps (one renewal for
    // both), else here.
    if (!flow)
      point_heat->follow_points();
  }

  template <int dim>
  void
  FempProblem<dim>::flow_step(const double dt)
  {
    flow->advance_over(control->time(),
                       dt,
                       cell_fields(),
                       time_steps->flow_may_melt(),
                       time_steps->flow_subcycle(*control));
    // Points changed cells: new alpha, and the heat they bring.
    TimerOutput::Scope scope(timer, "flow: alpha and new metal cells");
    point_heat->follow_points();
  }

  template <int dim>
  void
  FempProblem<dim>::fluid_forces_on_solid()
  {
    TimerOutput::Scope t(timer, "flow: forces on the solid");
    fluid_solid->update(*flow);
  }

  template <int dim>
  void
  FempProblem<dim>::solid_step()
  {
    TimerOutput::Scope t(timer, "solid");
    time_steps->cool_solid_when_due(*solid, control->time());
    // Loaded by the fluid forces of step 3, with the flow.
    solid->advance(control->time(),
                   heat->temperature(),
                   control->is_last(),
                   fluid_solid ? &fluid_solid->nodal_forces() : nullptr);
    // Points the solid carried into other cells: new alpha, and the heat
    // they bring, before the output and the next step read alpha.
    point_heat->follow_points();
  }

  template <int dim>
  void
  FempProblem<dim>::output_results()
  {
    const auto pool = [this] {
      return workpiece_melt_pool(scene, *grid, *heat, point_heat->bodies());
    };
    results->write_when_due(*control, timer, pool, report->series_pool());
    // The hottest metal of the workpiece and, apart, of the detached
    // metal, and the pool now (the series' pool may lie up to a 'Time
    // series interval' back).
    report->progress_when_due(
      *control, [this] { return time_steps->metal_peak_temperatures(); }, pool);
  }

  template <int dim>
  std::string
  FempProblem<dim>::write_checkpoint(const CheckpointKind kind)
  {
    return states.write(control->step(), control->time(), pcout, timer, kind);
  }

  template class FempProblem<2>;
  template class FempProblem<3>;
  template unsigned int
  run_to_end(std::unique_ptr<FempProblem<2>> &, ParameterHandler &, MPI_Comm);
  template unsigned int
  run_to_end(std::unique_ptr<FempProblem<3>> &, ParameterHandler &, MPI_Comm);
} // namespace femp
