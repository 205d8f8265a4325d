// femp: the top-level problem: reads and checks parameters, builds the
// modules, and runs the macro time loop of the paper's sec. 2.6.
#include <deal.II/base/mpi.h>
#include <deal.II/base/utilities.h>

#include <femp/app/femp_problem.h>
#include <femp/app/run_checks.h>
#include <femp/base/collective_error.h>
#include <femp/base/input_checks.h>
#include <femp/heat/attached_metal.h>
#include <femp/solid/fe_zone_depth.h>

#include <chrono>
#include <iomanip>

namespace femp
{
  void
  declare_all_parameters(ParameterHandler &prm)
  {
    prm.declare_entry("Dimension",
                      "3",
                      Patterns::Integer(2, 3),
                      "Space dimension of the scene: 2 or 3.");
    prm.enter_subsection("Physics");
    prm.declare_entry("Heat transfer",
                      "true",
                      Patterns::Bool(),
                      "Solve the temperature equation (1). false: the "
                      "temperature stays frozen at 'Heat transfer/Initial "
                      "temperature' (a number or a function of x, y, z) and "
                      "nothing of the heat equation is computed; the flow "
                      "still takes its Marangoni stress, recoil and Darcy "
                      "damping from this field, and points still change "
                      "state with it. The step is then 'Time stepping/Time "
                      "step', or with melt flow and 0 the fluid step.");
    prm.declare_entry("Melt flow",
                      "false",
                      Patterns::Bool(),
                      "Solve the melt-pool flow (eqs. 3-4) of the fluid points "
                      "(subsection Melt flow): gravity, viscosity, Darcy "
                      "damping, surface tension, Marangoni stress and recoil "
                      "pressure.");
    prm.declare_entry("Solid stress",
                      "false",
                      Patterns::Bool(),
                      "Solve the thermal stress by MPM and FE (eqs. 5-17): "
                      "subsections 'Solid' and 'Solid FEM'. With 'Melt flow' "
                      "too, the flow moves the fluid points and the solid "
                      "the solid points, and the fluid pressure and viscous "
                      "forces on the faces to solid cells load the solid "
                      "(doc/solid.md, 'Flow and solid together').");
    prm.declare_entry("Gravity",
                      "9.81",
                      Patterns::Double(),
                      "Magnitude g of the gravitational acceleration, m/s^2, "
                      "acting along -y (2D) or -z (3D) on the melt flow and "
                      "on the solid (the one gravity of both); range [0, "
                      "inf).");
    prm.leave_subsection();
    SimulationControl::Parameters::declare_parameters(prm);
    Material::declare_parameters(prm);
    BackgroundGrid<3>::Parameters::declare_parameters(prm);
    MaterialPoints<3>::Parameters::declare_parameters(prm);
    HeatTransfer<3>::Parameters::declare_parameters(prm);
    IncompressibleFlow<3>::Parameters::declare_parameters(prm);
    Laser<3>::Parameters::declare_parameters(prm);
    RayTracedAbsorption<3>::Parameters::declare_parameters(prm);
    Output<3>::Parameters::declare_parameters(prm);
    ThermalHistory<3>::Parameters::declare_parameters(prm);
    TrackShape<3>::Parameters::declare_parameters(prm);
    SolidMaterial::declare_parameters(prm);
    SolidStress<3>::Parameters::declare_parameters(prm);
    SolidFEM<3>::Parameters::declare_parameters(prm);
    Checkpoint<3>::Parameters::declare_parameters(prm);
  }

  template <int dim>
  FempProblem<dim>::FempProblem(ParameterHandler &prm, MPI_Comm comm)
      : comm(comm)
      , pcout(std::cout, Utilities::MPI::this_mpi_process(comm) == 0)
      , timer(pcout, TimerOutput::never, TimerOutput::wall_times)
  {
    prm.enter_subsection("Physics");
    melt_flow      = prm.get_bool("Melt flow");
    heat_enabled   = prm.get_bool("Heat transfer");
    solid_enabled  = prm.get_bool("Solid stress");
    const double g = prm.get_double("Gravity");
    prm.leave_subsection();
    require(g >= 0,
            "Physics/Gravity",
            g,
            "it must be a magnitude >= 0 (m/s^2; it acts along -y in 2D, "
            "-z in 3D)");
    gravity[dim - 1] = -g;
    time_prm.parse_parameters(prm);
    material.parse_parameters(prm);
    grid_prm.parse_parameters(prm);
    points_prm.parse_parameters(prm);
    points_prm.check(grid_prm);
    heat_prm.parse_parameters(prm);
    heat_prm.check(grid_prm.lower_corner,
                   grid_prm.upper_corner,
                   grid_prm.cell_size);
    flow_prm.parse_parameters(prm);
    flow_prm.gravity = gravity;
    if (melt_flow)
      flow_prm.check_time_step(grid_prm.cell_size, material.density);
    laser_prm.parse_parameters(prm);
    absorption_prm.parse_parameters(prm);
    output_prm.parse_parameters(prm);
    history_prm.parse_parameters(prm);
    track_prm.parse_parameters(prm);
    // A bare plate without flow or solid carries no points (Material
    // points/Carry points = auto).
    points_prm.resolve_carry(melt_flow,
                             solid_enabled,
                             track_prm.enabled(melt_flow));
    output_prm.check(grid_prm.lower_corner, grid_prm.upper_corner);
    if (solid_enabled)
      {
        solid_material.parse_parameters(prm);
        solid_prm.parse_parameters(prm);
        solid_prm.gravity = gravity;
        solid_prm.check(solid_material, grid_prm);
        fem_prm.parse_parameters(prm);
        if (fem_prm.enabled && fem_prm.automatic_top)
          place_fe_zone_automatically();
        fem_prm.check(grid_prm);
      }

    check_across_modules();
    checkpoint_prm.parse_parameters(prm);
    checkpoint = std::make_unique<Checkpoint<dim>>(checkpoint_prm,
                                                   output_prm.directory,
                                                   checkpoint_scene(),
                                                   comm);
    if (checkpoint->resuming())
      checkpoint->read(); // refuses a corrupt or mismatched one here
    control = std::make_unique<SimulationControl>(
      time_prm,
      SimulationControl::Cadence{output_prm.output_interval,
                                 output_prm.output_steps,
                                 output_prm.series_interval,
                                 output_prm.progress_interval});
    control->set_step_chooser(
      [this](const unsigned int step, const double time) {
        return choose_time_step(step, time);
      });
    report = std::make_unique<RunReport<dim>>(comm, pcout);
    laser  = std::make_unique<Laser<dim>>(laser_prm);
    laser->check_path_inside(grid_prm.lower_corner, grid_prm.upper_corner);
  }

  template <int dim>
  void
  FempProblem<dim>::place_fe_zone_automatically()
  {
    // 'Zone upper corner = auto' (fe_zone_depth.h, doc/cases.md): the top
    // below the conservative melt depth of the laser's strongest moving
    // segment.
    require(dim == 3,
            "Solid FEM/Zone upper corner",
            "auto",
            "'auto' is for 3D scenes; give the corner's coordinates");
    double           d = 0;
    const Laser<dim> path(laser_prm);
    for (const auto &s : path.segments())
      if (s.power > 0 && s.speed > 0)
        d = std::max(d,
                     conservative_melt_depth(material,
                                             laser_prm.absorptivity * s.power,
                                             s.speed,
                                             heat_prm.initial_temperature));
    fem_prm.upper_corner = grid_prm.upper_corner;
    fem_prm.upper_corner[dim - 1] =
      automatic_fe_zone_top(d,
                            points_prm.substrate_top,
                            grid_prm.lower_corner[dim - 1],
                            grid_prm.cell_size);
    pcout << "Solid FEM: zone top 'auto' at z = "
          << fem_prm.upper_corner[dim - 1] << " m (conservative melt depth "
          << d << " m below the substrate top " << points_prm.substrate_top
          << " m, margin 1.1 d + 2 cells)" << std::endl;
  }

  template <int dim>
  void
  FempProblem<dim>::check_across_modules()
  {
    require(time_prm.stop_temperature == 0 ||
              (heat_enabled &&
               time_prm.stop_temperature > heat_prm.initial_temperature),
            "Time stepping/Stop when peak temperature below",
            time_prm.stop_temperature,
            "0 (off), or with Physics/Heat transfer a temperature above the "
            "initial temperature " +
              num(heat_prm.initial_temperature) + " K");
    require(heat_enabled || melt_flow || time_prm.time_step > 0,
            "Time stepping/Time step",
            time_prm.time_step,
            "with 'Physics/Heat transfer = false' and no melt flow nothing "
            "sets the step: prescribe it (s, > 0)");
    require(time_prm.time_step_solidified == 0 || heat_enabled,
            "Time stepping/Time step after solidification",
            time_prm.time_step_solidified,
            "0: with 'Physics/Heat transfer = false' nothing melts or "
            "solidifies");
    if (time_prm.time_step > 0 && heat_enabled)
      {
        // Upper bound of the stable diffusion step of any cell full of
        // metal; the exact limit is checked again at every step.
        const double h     = grid_prm.cell_size;
        const double bound = h * h * material.density *
                             material.specific_heat.max_value() /
                             (2 * dim * material.conductivity.min_value());
        std::ostringstream allowed;
        allowed << "it exceeds the stable limit of the explicit temperature "
                   "step for every metal cell (at most "
                << bound << " s for h = " << h
                << " m and these material tables); use 0 (automatic)";
        require(time_prm.time_step <= bound,
                "Time stepping/Time step",
                time_prm.time_step,
                allowed.str());
        require(time_prm.time_step_solidified <= bound,
                "Time stepping/Time step after solidification",
                time_prm.time_step_solidified,
                allowed.str());
      }
  }

  namespace
  {
    // Relative cost of a background cell, for the partition of the grid
    // over the ranks (doc/performance.md, "Balancing the ranks"), from the
    // scene's geometry at the start: 1 per cell (the heat and flow passes
    // over the box), 2 per material point expected in it (metal fraction,
    // temperatures to the points, relocation) and 40 more per point that
    // the solid steps by MPM (the substrate outside the FE zone: its point
    // loops run at every solid step, 7 to 17 times per temperature step).
    // Without points every cell costs the same: no function.
    template <int dim>
    std::function<unsigned int(const Point<dim> &)>
    partition_cost(const typename MaterialPoints<dim>::Parameters &points,
                   const typename SolidFEM<dim>::Parameters       &fem,
                   const Point<dim>                               &origin,
                   const double                                    h,
                   const bool                                      solid)
    {
      if (!points.carry_points)
        return {};
      const double      full       = std::pow(h / points.point_spacing, dim);
      const double      top        = points.substrate_top;
      const double      powder_top = top + std::max(0., points.layer_thickness);
      const double      packing    = points.packing_fraction;
      const FeZone<dim> fe_zone    = fem.zone(origin, h);
      return [=](const Point<dim> &c) {
        const double z     = c[dim - 1];
        const bool   in_fe = fe_zone.contains(c);
        double       n = 0, n_mpm = 0;
        if (z < top)
          n = full, n_mpm = solid && !in_fe ? full : 0.;
        else if (z < powder_top)
          n = packing * full;
        return static_cast<unsigned int>(std::lround(1 + 2 * n + 40 * n_mpm));
      };
    }
  } // namespace

  template <int dim>
  void
  FempProblem<dim>::setup()
  {
    {
      TimerOutput::Scope t(timer, "setup: grid");
      grid = std::make_unique<BackgroundGrid<dim>>(grid_prm, comm);
      grid->create(partition_cost<dim>(points_prm,
                                       fem_prm,
                                       grid_prm.lower_corner,
                                       grid_prm.cell_size,
                                       solid_enabled));
    }
    {
      TimerOutput::Scope t(timer, "setup: material points");
      // Points carry only the property blocks of the physics switched on.
      const bool affine =
        solid_enabled && solid_material.velocity_transfer ==
                           SolidMaterial::VelocityTransfer::apic;
      points = std::make_unique<MaterialPoints<dim>>(
        points_prm,
        material,
        *grid,
        MaterialPoints<dim>::PropertyIndex::n_used(solid_enabled, affine));
      points->create(heat_prm.initial_temperature);
    }
    heat =
      std::make_unique<HeatTransfer<dim>>(heat_prm, material, *laser, *grid);
    heat->initialize();
    heat->set_absorption_model(absorption_prm);
    if (!heat_enabled)
      heat->freeze();
    point_heat = std::make_unique<PointHeatExchange<dim>>(
      *points, *heat, heat_prm.advection_by_melt_flow == "points");
    point_heat->initial_temperatures(points_prm.bodies, heat_prm);
    {
      TimerOutput::Scope t(timer, "setup: metal fraction");
      heat->set_metal_fraction(points->metal_fraction());
    }
    if (melt_flow)
      setup_flow();
    output = std::make_unique<Output<dim>>(output_prm, *grid);
    if (track_prm.enabled(melt_flow))
      {
        // Centre line and default cross-section from the laser's first
        // segment (the middle of the domain without a path).
        Point<dim> a = grid->origin(), b = grid->origin();
        for (int d = 0; d < dim; ++d)
          a[d] = b[d] =
            0.5 * (grid_prm.lower_corner[d] + grid_prm.upper_corner[d]);
        if (!laser->segments().empty())
          a = laser->segments().front().start,
          b = laser->segments().front().end;
        track_shape =
          std::make_unique<TrackShape<dim>>(track_prm,
                                            *grid,
                                            dim == 3 ? a[1] : 0.,
                                            points_prm.substrate_top,
                                            0.5 * (a[0] + b[0]));
      }
    if (history_prm.enabled)
      history = std::make_unique<ThermalHistory<dim>>(*grid,
                                                      material.solidus,
                                                      material.liquidus,
                                                      heat->temperature(),
                                                      heat->metal_fraction(),
                                                      0.);
    {
      std::vector<std::string> names;
      for (const auto &f : output_fields())
        names.push_back(f.name);
      output->initialize(names, checkpoint->resuming());
    }
    if (solid_enabled)
      setup_solid();
    print_scene();
  }

  template <int dim>
  void
  FempProblem<dim>::setup_flow()
  {
    flow = std::make_unique<IncompressibleFlow<dim>>(
      flow_prm, material, *grid, *points, &timer);
    // The flow reads T and gamma, the heat (with 'Advection by melt flow =
    // upwind') the flow's cell velocity, from cell_fields() at each call.
  }

  template <int dim>
  void
  FempProblem<dim>::setup_solid()
  {
    TimerOutput::Scope t(timer, "setup: solid");
    solid = std::make_unique<SolidStress<dim>>(
      solid_prm, fem_prm, solid_material, *grid, *points);
    if (flow)
      {
        // Flow and solid together (doc/solid.md): the flow owns the
        // fluid points' velocities; its forces on the solid enter
        // through the solid's external nodal forces.
        solid->set_flow_owns_fluid_points(true);
        // Fragments that solidify where the flow left them: light nodes
        // accelerated as if they had the mass at which the step is
        // stable for them, or (`Solid/Light nodes = no force`) no force
        // on nodes with less than `Solid/Small mass cutoff` of a full
        // node's mass (stability estimate and choice: doc/solid.md).
        if (solid_prm.light_nodes == "mass floor")
          solid->set_mass_floor(true);
        else
          solid->set_small_mass_cutoff(solid_prm.small_mass_cutoff);
        fluid_solid = std::make_unique<FluidSolidForces<dim>>(*grid,
                                                              *points,
                                                              material.density,
                                                              fem_prm);
      }
    // On resume the solid's CSV files are cut back and reopened by its
    // load_state() instead.
    solid->initialize(heat->temperature(),
                      checkpoint->resuming() ? std::string() :
                                               output_prm.directory);
    // The FE zone's points never move nor melt (the solid stops the run
    // otherwise): the metal fraction bins them once.
    points->set_fixed_cells(solid->fe_zone_cells());
  }

  template <int dim>
  void
  FempProblem<dim>::print_scene() const
  {
    const std::string index = output_prm.format == "hdf5" ? ".xdmf" : ".pvd";
    pcout << "femp: " << dim << "D scene, "
          << Utilities::MPI::n_mpi_processes(comm) << " MPI rank(s)\n"
          << "  background grid: " << grid->n_global_cells() << " cells of "
          << grid->h() << " m (";
    for (int d = 0; d < dim; ++d)
      pcout << grid->n_cells()[d] << (d + 1 < dim ? " x " : ")\n");
    if (points->carried())
      pcout << "  material points: " << points->n_global_points() << " ("
            << points->n_powder_grains() << " powder grains, packing fraction "
            << std::setprecision(3) << points->achieved_packing_fraction()
            << ")\n";
    else
      pcout << "  material points: none (Material points/Carry points = auto: "
               "a bare plate without melt flow or solid; alpha from the "
               "substrate's lattice)"
            << (output_prm.write_points != "never" ?
                  "; 'Output/Write material points = " +
                    output_prm.write_points +
                    "' writes nothing (Carry points = always for point files)" :
                  std::string())
            << "\n";
    const unsigned int n_ranks = Utilities::MPI::n_mpi_processes(comm);
    std::string        solid_line;
    if (solid)
      {
        // With several ranks, the largest share of the MPM points on one
        // rank: what the partition leaves for the solid's point loops.
        const auto         n     = solid->sizes();
        const double       n_max = solid->largest_rank_points();
        std::ostringstream s;
        s << "  solid: " << int(n[0]) << " material points";
        if (n_ranks > 1 && n[0] > 0)
          s << " (at most " << std::fixed << std::setprecision(1)
            << 100 * n_max / n[0] << " % on one rank)" << std::defaultfloat;
        s << ", " << int(n[1]) << " finite elements, step "
          << num(solid->time_step()) << " s\n";
        solid_line = s.str();
      }
    pcout << std::setprecision(3) << solid_line
          << "  output: " << output_prm.directory << "/grid" << index << ", "
          << (points->carried() ?
                output_prm.directory + "/points" + index + ", " :
                std::string())
          << output_prm.directory << "/melt_pool.csv\n";
    if (dim == 3 && heat_enabled)
      print_melting_regime();
  }

  template <int dim>
  void
  FempProblem<dim>::print_melting_regime() const
  {
    // Regime by the normalized enthalpy of King et al. (2014),
    // eta P/(pi h_s sqrt(D v r_b^3)), h_s = rho c T_s, D = lambda/(rho c)
    // at the solidus, largest over the laser-on segments; keyhole-mode
    // melting above about 30 (doc/absorption.md).
    const double Ts    = material.solidus;
    const double rc    = material.density * material.specific_heat.value(Ts);
    const double D     = material.conductivity.value(Ts) / rc;
    const double rb    = laser_prm.beam_radius;
    double       ratio = 0;
    for (const auto &s : laser->segments())
      if (s.power > 0)
        ratio =
          std::max(ratio,
                   laser_prm.absorptivity * s.power /
                     (M_PI * rc * Ts * std::sqrt(D * s.speed * rb * rb * rb)));
    if (ratio > 0)
      pcout << "  regime: normalized enthalpy eta P/(pi h_s sqrt(D v r_b^3)) = "
            << std::setprecision(3) << ratio
            << (ratio >= 30 ?
                  " >= 30: keyhole mode likely; a fixed absorptivity on the "
                  "first surface underestimates the depth there" :
                  (ratio >= 20 ? " (near the keyhole transition at ~30)" :
                                 " < 30: conduction mode\n"));
    if (ratio >= 20)
      pcout << (heat->ray_traced() ?
                  "; ray-traced absorption on (doc/absorption.md)\n" :
                  "; use 'Laser/Absorption model = ray traced' "
                  "(doc/absorption.md)\n");
  }

  template <int dim>
  void
  FempProblem<dim>::run()
  {
    control->start_clock();
    setup();
    if (checkpoint->resuming())
      restore_checkpoint();
    else
      {
        // The exact stability limit and the projected number of steps are
        // checked before anything is written.
        choose_time_step(0, control->time());
        report->start(*heat);
        write_output(false);
      }

    while (control->running())
      {
        const double dt = control->next_time_step();
        workpiece_peak.reset();

        // 1. Tag cells, alpha, gamma, properties: alpha changes only when
        //    points move (the melt-flow and solid modules, step 3), so
        //    nothing to do here; gamma and the properties follow T inside
        //    HeatTransfer::advance().

        // 2. Temperature in fluid, solid and powder (eq. 1), then to the
        //    points (eq. 2).
        temperature_step(dt);
        cells_to_points();

        // 3. Melt-pool flow (eqs. 3-4), sub-cycled, with the heat carried
        //    by the points that changed cells; with the solid, the fluid
        //    forces on it (eq. 13), held over the solid sub-steps of 4.
        if (flow)
          flow_substeps(dt);
        if (fluid_solid)
          fluid_forces_on_solid();

        stop_if_cooled_down(dt);
        control->advance(dt);

        // 4. Solid stress (SolidMPM + SolidFEM coupled, eqs. 5-17),
        //    sub-cycled against the temperature step.
        if (solid)
          solid_step();

        // 5. Output.
        output_results();
        if (checkpoint->enabled() &&
            checkpoint->due(control->step(), control->time()))
          write_checkpoint();
      }

    points->flush_point_temperatures();
    report->finish(*control,
                   *heat,
                   *points,
                   flow.get(),
                   solid.get(),
                   point_heat->moved_points_energy(),
                   result);
    if (history)
      history->write(output_prm.directory);
    timer.print_summary();
    print_timer_statistics(timer, comm); // min/avg/max over the ranks
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
    if (!heat_enabled)
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
    if (history)
      history->observe(heat->temperature(),
                       heat->metal_fraction(),
                       control->time() + dt);
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
      solid->set_detached_cells(heat->detached_cells());
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
  FempProblem<dim>::flow_substeps(const double dt)
  {
    // Sub-cycle with the current limits (they change as the flow speeds
    // up), or with the prescribed step, in equal pieces that end with the
    // temperature step. The limits and which one governed are recorded for
    // the report at the end of the run.
    const unsigned int resorts = flow->statistics().resorts;
    auto              &r       = result.flow_limits;
    // Nothing to flow, and nothing can start to: the last flow step had no
    // fluid cell (its pressure, nodal velocities and forces on the solid
    // are zero) and no metal cell is above the solidus, so cells_to_points()
    // left no point fluid. A flow step would change nothing; skip it (in
    // the cooling after the laser's path, once the last drop has
    // solidified).
    if (heat_enabled && flow->statistics().steps > 0 &&
        flow->statistics().n_fluid_cells == 0 &&
        heat->max_temperature() < material.solidus)
      {
        ++r.idle_steps;
        return;
      }
    double       t     = 0;
    unsigned int n_sub = 0;
    while (t < dt * (1 - 1e-12))
      {
        const auto l = flow->stable_time_step();
        r.record(l, flow_prm.time_step > 0);
        const double wanted =
          flow_prm.time_step > 0 ? flow_prm.time_step : l.min();
        // Equal sub-steps over the rest of the temperature step, none above
        // the wanted step: no tiny last sub-step (uneven sub-steps shortened
        // the droplet period in prm/oscillating_droplet.prm).
        const double rest = dt - t;
        const double dt_f =
          rest / std::max(1., std::ceil(rest / wanted * (1 - 1e-12)));
        flow->step(dt_f, cell_fields());
        t += dt_f;
        // Collective: the limits are global, so is the count.
        if (++n_sub > run_limits().max_flow_substeps)
          throw CollectiveError(
            InputError("Run limits/Maximum flow sub-steps",
                       std::to_string(run_limits().max_flow_substeps),
                       "the flow needed more sub-steps in the temperature "
                       "step of " +
                         num(dt) + " s (sub-step now " + num(dt_f) +
                         " s: the flow may have blown up); raise "
                         "the bound if the flow is right")
              .what());
        // Feedback during a long sub-cycle (the progress line comes only
        // between temperature steps).
        const double wall = control->wall_time();
        if (wall > next_substep_report)
          {
            pcout << "  melt flow: sub-step " << n_sub << " of the temperature "
                  << "step at t = " << control->time() << " s, " << t / dt * 100
                  << " % done, sub-step " << dt_f << " s (wall " << wall
                  << " s)" << std::endl;
            next_substep_report = wall + 30;
          }
      }
    next_substep_report = control->wall_time() + 30;
    r.record_substeps(n_sub);
    if (flow->statistics().resorts == resorts)
      return;
    // Points changed cells: new alpha, and the heat they bring.
    TimerOutput::Scope scope(timer, "flow: alpha and new metal cells");
    point_heat->points_changed_cells();
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
    // With the melt flow, once the workpiece has solidified after the
    // laser's path (the metal attached to the substrate, attached_metal.h:
    // spatter drops in the gas may stay liquid): the larger cooling step
    // of the same accuracy.
    if (fluid_solid &&
        solid_prm.safety_factor_solidified > solid_prm.safety_factor &&
        !solid->uses_cooling_step() &&
        control->time() >= laser->end_time() * (1 - 1e-12) &&
        workpiece_peak_temperature() < material.solidus)
      {
        const std::string change = solid->use_cooling_step();
        if (!change.empty())
          pcout << "Solid: the melt has solidified after the laser's path "
                   "(t = "
                << control->time() << " s): " << change << std::endl;
      }
    // Loaded by the fluid forces of step 3, with the flow.
    solid->advance(control->time(),
                   heat->temperature(),
                   control->is_last(),
                   fluid_solid ? &fluid_solid->nodal_forces() : nullptr);
  }

  template <int dim>
  void
  FempProblem<dim>::stop_if_cooled_down(const double dt)
  {
    const bool cooled =
      time_prm.stop_temperature > 0 && heat_enabled &&
      control->time() + dt >= laser->end_time() * (1 - 1e-12) &&
      workpiece_peak_temperature() < time_prm.stop_temperature;
    if (!cooled)
      return;
    control->request_stop();
    std::ostringstream T_peak; // to 0.01 K: it lies just below
    T_peak << std::fixed << std::setprecision(2)
           << workpiece_peak_temperature();
    pcout << "Stopping at t = " << control->time() + dt
          << " s: the laser's path has ended and the peak "
             "temperature of the metal attached to the substrate "
          << T_peak.str() << " K is below " << time_prm.stop_temperature << " K"
          << std::endl;
  }

  template <int dim>
  double
  FempProblem<dim>::workpiece_peak_temperature()
  {
    if (!workpiece_peak)
      workpiece_peak = attached_metal_max_temperature(*grid,
                                                      heat->temperature(),
                                                      heat->metal_fraction());
    return *workpiece_peak;
  }

  template <int dim>
  void
  FempProblem<dim>::output_results()
  {
    if (control->series_due())
      write_series();
    if (control->output_due())
      write_output(control->is_last());
    if (control->progress_due())
      report->progress(*control, heat->max_temperature(), result.pool);
  }

  template <int dim>
  void
  FempProblem<dim>::write_series()
  {
    TimerOutput::Scope t(timer, "time series");
    result.pool = measure_melt_pool(*grid,
                                    heat->temperature(),
                                    heat->metal_fraction(),
                                    material.liquidus,
                                    points_prm.substrate_top,
                                    material.solidus);
    output->write_series(control->time(), output_fields(), result.pool);
    if (heat_enabled && heat->ray_traced())
      write_absorption_series();
    control->series_written();
  }

  template <int dim>
  void
  FempProblem<dim>::write_absorption_series()
  {
    if (Utilities::MPI::this_mpi_process(comm) != 0)
      return;
    const std::string name = output_prm.directory + "/absorption.csv";
    if (!absorption_csv)
      {
        absorption_csv = std::make_unique<std::ofstream>(name);
        *absorption_csv << "time,incident,absorbed,escaped,absorbed_fraction,"
                           "hits_per_ray\n";
      }
    // The last trace: of the step that ended at this time.
    const auto &r = heat->last_trace();
    *absorption_csv << std::setprecision(8) << control->time() << ','
                    << r.incident << ',' << r.absorbed << ',' << r.escaped
                    << ',' << (r.incident > 0 ? r.absorbed / r.incident : 0.)
                    << ',' << double(r.n_hits) / std::max(1u, r.n_rays) << '\n';
    absorption_csv->flush();
    require(bool(*absorption_csv),
            "Output/Directory",
            output_prm.directory,
            "absorption.csv cannot be written there");
  }

  template <int dim>
  double
  FempProblem<dim>::choose_time_step(const unsigned int step, const double time)
  {
    if (!heat_enabled)
      {
        // Frozen temperature: the prescribed step, else the fluid step.
        const double dt =
          time_prm.time_step > 0 ?
            time_prm.time_step :
            (flow_prm.time_step > 0 ? flow_prm.time_step :
                                      flow->stable_time_step().min());
        check_projected_steps(step, dt);
        return dt;
      }
    const double stable = step == 0 ? heat->stable_time_step(cell_fields()) :
                                      heat->last_stable_time_step();
    if (time_prm.time_step_solidified > 0)
      {
        // The cooling step, while the laser's path has ended and the
        // workpiece is below the solidus (checked at every step, the same
        // test as the solid's cooling switch), within the stable limit.
        const bool cooling = time >= laser->end_time() * (1 - 1e-12) &&
                             workpiece_peak_temperature() < material.solidus;
        const double dt_cooling =
          std::max(time_prm.time_step,
                   std::min(time_prm.time_step_solidified,
                            time_prm.safety_factor * stable));
        if (cooling != cooling_step)
          pcout << "Time stepping: at t = " << time << " s "
                << (cooling ? "the laser's path has ended and the workpiece "
                              "is below the solidus: temperature step " :
                              "metal attached to the workpiece is above the "
                              "solidus again: temperature step ")
                << (cooling ? dt_cooling : time_prm.time_step) << " s"
                << std::endl;
        cooling_step = cooling;
        // (Above the limit only if 'Time step' itself is: refused below.)
        if (cooling && dt_cooling <= stable)
          return dt_cooling;
      }
    const double dt = time_prm.time_step > 0 ? time_prm.time_step :
                                               time_prm.safety_factor * stable;
    if (time_prm.time_step > stable)
      {
        std::ostringstream s;
        s << "it exceeds the stable limit " << stable << " s of the explicit "
          << "temperature step"
          << (step > 0 ? " reached at step " + std::to_string(step) +
                           ", time " + num(time) + " s" :
                         std::string())
          << "; use 0 (automatic) or a step <= " << stable << " s";
        // Collective: the stable limit is a global minimum.
        throw CollectiveError(InputError("Time stepping/Time step",
                                         num(time_prm.time_step),
                                         s.str())
                                .what());
      }
    check_projected_steps(step, dt);
    return dt;
  }

  template <int dim>
  void
  FempProblem<dim>::check_projected_steps(const unsigned int step,
                                          const double       dt) const
  {
    // No run that silently stops short: refuse a projected step count
    // above the bound (collective: dt is the same on every rank).
    if (step > 0 || time_prm.end_time / dt <= time_prm.max_steps)
      return;
    throw CollectiveError(
      InputError("Time stepping/Maximum number of steps",
                 std::to_string(time_prm.max_steps),
                 "the first step of " + num(dt) + " s needs about " +
                   num(std::ceil(time_prm.end_time / dt)) +
                   " steps to reach 'End time'; raise the bound or shorten "
                   "the scene")
        .what());
  }

  template <int dim>
  std::vector<typename Output<dim>::Field>
  FempProblem<dim>::output_fields() const
  {
    std::vector<typename Output<dim>::Field> fields = {
      {"T", &heat->temperature()},
      {"gamma", &heat->liquid_fraction()},
      {"alpha", &heat->metal_fraction()}};
    if (flow)
      {
        // Melt flow: pressure (Pa) and cell-centred fluid velocity (m/s).
        static const char *u_names[3] = {"u_x", "u_y", "u_z"};
        fields.push_back({"p", &flow->pressure()});
        for (int d = 0; d < dim; ++d)
          fields.push_back({u_names[d], &flow->cell_velocity()[d]});
      }
    return fields;
  }

  template <int dim>
  void
  FempProblem<dim>::write_output(const bool last)
  {
    const unsigned int n    = control->output_number();
    const double       time = control->time();
    TimerOutput::Scope t(timer, "output");
    points->flush_point_temperatures();
    std::vector<double> phase(grid->n_local(), 0.);
    const auto         &a = heat->metal_fraction();
    const auto         &g = heat->liquid_fraction();
    for (std::size_t i = 0; i < phase.size(); ++i)
      phase[i] = a[i] <= 0 ? 0 : (g[i] <= 0 ? 1 : (g[i] < 1 ? 2 : 3));
    const std::vector<double> zone =
      points->zone_tags(heat->metal_fraction(), heat->temperature());
    auto fields = output_fields();
    // Solid: sigma_xx, sigma_yy, sigma_zz, von Mises, equivalent plastic
    // strain (FE element or mean over the cell's solid points); also on the
    // probe lines.
    std::vector<std::vector<double>> solid_fields;
    if (solid)
      {
        solid->cell_fields(solid_fields);
        const auto names = SolidStress<dim>::cell_field_names();
        for (std::size_t i = 0; i < names.size(); ++i)
          fields.push_back({names[i], &solid_fields[i]});
      }
    const auto line_fields = fields;
    fields.push_back({"laser_source", &heat->laser_source()});
    fields.push_back({"phase", &phase, false});
    fields.push_back({"zone", &zone, false});
    const bool with_points =
      points->carried() && (output_prm.write_points == "always" ||
                            (output_prm.write_points == "last" && last));
    output->write_fields(n,
                         time,
                         fields,
                         with_points ? &points->particle_handler() : nullptr,
                         points->used_property_names());
    output->write_probe_lines(n, time, line_fields);
    if (track_shape)
      write_track_shape(n, time);
    control->output_written();
  }

  template <int dim>
  void
  FempProblem<dim>::write_track_shape(const unsigned int n, const double time)
  {
    const auto sections =
      track_shape->measure(heat->metal_fraction(),
                           track_shape->resolidified_cells(*points,
                                                           material.liquidus));
    track_shape->write(output_prm.directory, n, time, sections);
  }

  template <int dim>
  typename Checkpoint<dim>::Scene
  FempProblem<dim>::checkpoint_scene() const
  {
    typename Checkpoint<dim>::Scene s;
    for (int d = 0; d < dim; ++d)
      {
        s.n_cells[d] = static_cast<unsigned int>(
          std::round((grid_prm.upper_corner[d] - grid_prm.lower_corner[d]) /
                     grid_prm.cell_size));
        s.lower_corner[d] = grid_prm.lower_corner[d];
      }
    s.cell_size = grid_prm.cell_size;
    s.heat      = heat_enabled;
    s.flow      = melt_flow;
    s.solid     = solid_enabled;
    s.fe_zone   = solid_enabled && fem_prm.enabled;
    if (s.fe_zone)
      for (int d = 0; d < dim; ++d)
        {
          s.fe_lower[d] = fem_prm.lower_corner[d];
          s.fe_upper[d] = fem_prm.upper_corner[d];
        }
    const bool affine =
      solid_enabled &&
      solid_material.velocity_transfer == SolidMaterial::VelocityTransfer::apic;
    // 0 without carried points: a checkpoint resumes only the same choice.
    s.n_point_properties =
      points_prm.carry_points ?
        MaterialPoints<dim>::PropertyIndex::n_used(solid_enabled, affine) :
        0;
    return s;
  }

  template <int dim>
  std::string
  FempProblem<dim>::write_checkpoint()
  {
    TimerOutput::Scope t(timer, "checkpoint");
    // One section per module that owns state; the problem's own section
    // holds the run's accounts that no module keeps.
    StateWriter c, h, p, o, th, run, trigger;
    control->save_state(c);
    heat->save_state(h);
    points->save_state(p);
    output->save_state(o);
    checkpoint->save_state(trigger);
    run.put(report->initial_enthalpy());
    run.put(point_heat->moved_points_energy());
    run.put(result.pool);
    run.put(result.flow_limits);
    std::vector<std::pair<std::string, const StateWriter *>> sections = {
      {"control", &c},
      {"heat", &h},
      {"points", &p},
      {"output", &o},
      {"trigger", &trigger},
      {"run", &run}};
    if (history)
      {
        history->save_state(th);
        sections.emplace_back("thermal history", &th);
      }
    StateWriter f;
    if (flow)
      {
        flow->save_state(f);
        sections.emplace_back("flow", &f);
      }
    StateWriter sol;
    if (solid)
      {
        solid->save_state(sol);
        sections.emplace_back("solid", &sol);
      }
    const std::string dir =
      checkpoint->write(control->step(), control->time(), sections);
    pcout << "Checkpoint: step " << control->step() << ", time "
          << control->time() << " s -> " << dir << " ("
          << checkpoint->bytes_written() << " bytes)" << std::endl;
    return dir;
  }

  template <int dim>
  void
  FempProblem<dim>::restore_checkpoint()
  {
    TimerOutput::Scope t(timer, "checkpoint");
    auto               load = [&](const std::string &name, auto &module) {
      auto parts = checkpoint->section(name);
      module.load_state(parts);
    };
    load("control", *control);
    load("points", *points);
    load("heat", *heat);
    load("output", *output);
    load("trigger", *checkpoint);
    if (flow)
      load("flow", *flow);
    if (solid)
      {
        auto parts = checkpoint->section("solid");
        solid->load_state(parts, output_prm.directory);
      }
    if (history)
      {
        require(checkpoint->has_section("thermal history"),
                "Checkpoint/Resume from",
                checkpoint->path_read(),
                "it was written without 'Thermal history/Enable' (the "
                "history before it is lost)");
        load("thermal history", *history);
      }
    {
      std::vector<StateReader> parts = checkpoint->section("run");
      StateReader             &in    = parts[0];
      report->set_initial_enthalpy(in.get<double>());
      point_heat->set_moved_points_energy(in.get<double>());
      result.pool        = in.get<MeltPoolSize>();
      result.flow_limits = in.get<typename Summary::FlowLimits>();
    }
    // Series written outside Output: drop their rows after the checkpoint.
    if (track_shape)
      track_shape->resume(output_prm.directory, control->time());
    if (heat_enabled && heat->ray_traced() &&
        Utilities::MPI::this_mpi_process(comm) == 0)
      {
        absorption_csv = std::make_unique<std::ofstream>();
        reopen_series_at(*absorption_csv,
                         output_prm.directory + "/absorption.csv",
                         control->time());
        if (!absorption_csv->is_open())
          absorption_csv.reset();
      }
    checkpoint->release();
    pcout << "Resumed from " << checkpoint->path_read() << " (written by "
          << checkpoint->saved_ranks() << " rank(s)) at step "
          << control->step() << ", time " << control->time() << " s"
          << std::endl;
  }

  template class FempProblem<2>;
  template class FempProblem<3>;
} // namespace femp
