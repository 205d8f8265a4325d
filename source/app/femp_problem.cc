// femp: the top-level problem: reads and checks parameters, builds the
// modules, and runs the macro time loop of the paper's sec. 2.6.
#include <deal.II/base/mpi.h>
#include <deal.II/base/utilities.h>

#include <femp/app/femp_problem.h>
#include <femp/base/input_checks.h>

#include <chrono>
#include <iomanip>

namespace femp
{
  void
  declare_all_parameters(ParameterHandler &prm)
  {
    prm.declare_entry("Dimension", "3", Patterns::Integer(2, 3),
                      "Space dimension of the scene: 2 or 3.");
    prm.enter_subsection("Physics");
    prm.declare_entry("Heat transfer", "true", Patterns::Bool(),
                      "Solve the temperature equation (1). false: the "
                      "temperature stays frozen at 'Heat transfer/Initial "
                      "temperature' (a number or a function of x, y, z) and "
                      "nothing of the heat equation is computed; the flow "
                      "still takes its Marangoni stress, recoil and Darcy "
                      "damping from this field, and points still change "
                      "state with it. The step is then 'Time stepping/Time "
                      "step', or with melt flow and 0 the fluid step.");
    prm.declare_entry("Melt flow", "false", Patterns::Bool(),
                      "Solve the melt-pool flow (eqs. 3-4) of the fluid points "
                      "(subsection Melt flow): gravity, viscosity, Darcy "
                      "damping, surface tension, Marangoni stress and recoil "
                      "pressure.");
    prm.declare_entry("Solid stress", "false", Patterns::Bool(),
                      "Solve the thermal stress by MPM and FE (eqs. 5-17): "
                      "subsections 'Solid' and 'Solid FEM'. With 'Melt flow' "
                      "too, the flow moves the fluid points and the solid "
                      "the solid points, and the fluid pressure and viscous "
                      "forces on the faces to solid cells load the solid "
                      "(doc/solid.md, 'Flow and solid together'); "
                      "'Solid/Gravity' must then be the flow's gravity.");
    prm.leave_subsection();
    FempProblem<3>::TimeParameters::declare_parameters(prm);
    Material::declare_parameters(prm);
    BackgroundGrid<3>::Parameters::declare_parameters(prm);
    MaterialPoints<3>::Parameters::declare_parameters(prm);
    HeatTransfer<3>::Parameters::declare_parameters(prm);
    IncompressibleFlow<3>::Parameters::declare_parameters(prm);
    Laser<3>::Parameters::declare_parameters(prm);
    Output<3>::Parameters::declare_parameters(prm);
    SolidMaterial::declare_parameters(prm);
    SolidStress<3>::Parameters::declare_parameters(prm);
    SolidFEM<3>::Parameters::declare_parameters(prm);
  }


  template <int dim>
  void
  FempProblem<dim>::TimeParameters::declare_parameters(ParameterHandler &prm)
  {
    prm.enter_subsection("Time stepping");
    prm.declare_entry("End time", "1e-3", Patterns::Double(0.),
                      "Simulated time at which the run ends, s; range (0, inf).");
    prm.declare_entry("Time step", "0", Patterns::Double(0.),
                      "Temperature step, s; 0 chooses it automatically as the "
                      "safety factor times the stable limit. A prescribed step "
                      "above the stable limit is refused. Range [0, inf).");
    prm.declare_entry("Safety factor", "0.5", Patterns::Double(0., 1.),
                      "Fraction C of the stable limit h^2 rho c / sum(lambda_f) "
                      "(diffusion) and h/|u| (convection) used as the "
                      "automatic step; range (0, 1].");
    prm.declare_entry("Maximum number of steps", "100000000", Patterns::Integer(1),
                      "Stop after this many steps even before the end time.");
    prm.leave_subsection();
  }


  template <int dim>
  void
  FempProblem<dim>::TimeParameters::parse_parameters(ParameterHandler &prm)
  {
    prm.enter_subsection("Time stepping");
    end_time      = prm.get_double("End time");
    time_step     = prm.get_double("Time step");
    safety_factor = prm.get_double("Safety factor");
    max_steps     = prm.get_integer("Maximum number of steps");
    prm.leave_subsection();
    require(end_time > 0, "Time stepping/End time", end_time,
            "it must be positive (s)");
    require(safety_factor > 0, "Time stepping/Safety factor", safety_factor,
            "it must lie in (0, 1]");
  }


  template <int dim>
  FempProblem<dim>::FempProblem(ParameterHandler &prm, MPI_Comm comm)
    : comm(comm)
    , pcout(std::cout, Utilities::MPI::this_mpi_process(comm) == 0)
    , timer(pcout, TimerOutput::never, TimerOutput::wall_times)
  {
    prm.enter_subsection("Physics");
    melt_flow     = prm.get_bool("Melt flow");
    heat_enabled  = prm.get_bool("Heat transfer");
    solid_enabled = prm.get_bool("Solid stress");
    prm.leave_subsection();
    time_prm.parse_parameters(prm);
    material.parse_parameters(prm);
    grid_prm.parse_parameters(prm);
    points_prm.parse_parameters(prm);
    points_prm.check(grid_prm);
    heat_prm.parse_parameters(prm);
    heat_prm.check(grid_prm.lower_corner, grid_prm.upper_corner,
                   grid_prm.cell_size);
    flow_prm.parse_parameters(prm);
    if (melt_flow)
      flow_prm.check_time_step(grid_prm.cell_size, material.density);
    laser_prm.parse_parameters(prm);
    output_prm.parse_parameters(prm);
    output_prm.check(grid_prm.lower_corner, grid_prm.upper_corner);
    melt_temperature = material.liquidus;
    if (solid_enabled)
      {
        solid_material.parse_parameters(prm);
        solid_material.density          = material.density;
        solid_material.melt_temperature = material.solidus;
        solid_prm.parse_parameters(prm);
        solid_prm.check(solid_material, grid_prm);
        fem_prm.parse_parameters(prm);
        fem_prm.check(grid_prm);
        if (melt_flow)
          {
            // One body under one gravity: the fluid's weight reaches the
            // solid through the fluid forces, the solid's own through
            // Solid/Gravity.
            bool same = true;
            for (int d = 0; d < dim; ++d)
              same = same && std::abs(solid_prm.gravity[d] -
                                      flow_prm.gravity[d]) <=
                               1e-12 * (1 + flow_prm.gravity.norm());
            std::ostringstream v, allowed;
            for (int d = 0; d < dim; ++d)
              v << (d ? ", " : "") << solid_prm.gravity[d];
            allowed << "with Physics/Melt flow = true it must be the flow's "
                       "gravity (Melt flow/Gravity "
                    << -flow_prm.gravity[dim - 1] << " m/s^2 downwards): ";
            for (int d = 0; d < dim; ++d)
              allowed << (d ? ", " : "") << flow_prm.gravity[d];
            require(same, "Solid/Gravity", v.str(), allowed.str());
          }
      }

    // Checks that need several modules, still before any work.
    require(heat_enabled || melt_flow || time_prm.time_step > 0,
            "Time stepping/Time step", time_prm.time_step,
            "with 'Physics/Heat transfer = false' and no melt flow nothing "
            "sets the step: prescribe it (s, > 0)");
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
        require(time_prm.time_step <= bound, "Time stepping/Time step",
                time_prm.time_step, allowed.str());
      }
    laser = std::make_unique<Laser<dim>>(laser_prm);
    laser->check_path_inside(grid_prm.lower_corner, grid_prm.upper_corner);
  }


  template <int dim>
  void
  FempProblem<dim>::setup()
  {
    {
      TimerOutput::Scope t(timer, "setup: grid");
      grid = std::make_unique<BackgroundGrid<dim>>(grid_prm, comm);
      grid->create();
    }
    {
      TimerOutput::Scope t(timer, "setup: material points");
      // Points carry only the property blocks of the physics switched on.
      const bool affine =
        solid_enabled && solid_material.velocity_transfer ==
                           SolidMaterial::VelocityTransfer::apic;
      points = std::make_unique<MaterialPoints<dim>>(
        points_prm, material, *grid,
        MaterialPoints<dim>::PropertyIndex::n_used(solid_enabled, affine));
      points->create(heat_prm.initial_temperature);
    }
    heat = std::make_unique<HeatTransfer<dim>>(heat_prm, material, *laser, *grid);
    heat->initialize();
    if (!heat_enabled)
      heat->freeze();
    if (!heat_prm.initial_temperature_expression.empty())
      {
        // Points outside the initial bodies take the initial temperature
        // at their position.
        using P = typename MaterialPoints<dim>::PropertyIndex;
        for (auto &particle : points->particle_handler())
          {
            const Point<dim> x = particle.get_location();
            bool             in_body = false;
            for (const auto &b : points_prm.bodies)
              in_body = in_body || b.inside(x);
            if (in_body)
              continue;
            auto         v         = particle.get_properties();
            const double T0        = heat_prm.initial_temperature_at(x);
            v[P::temperature]      = T0;
            v[P::peak_temperature] = T0;
          }
      }
    if (!points_prm.bodies.empty())
      {
        // Cells of initial bodies take the mean temperature of their points
        // (and the liquid fraction of that temperature).
        using P = typename MaterialPoints<dim>::PropertyIndex;
        for (const auto &[idx, cell] : points->occupied_cells())
          {
            double sum = 0, n = 0;
            for (const auto &particle :
                 points->particle_handler().particles_in_cell(cell))
              sum += particle.get_properties()[P::temperature], ++n;
            if (n > 0)
              heat->set_cell_temperature(idx, sum / n);
          }
        heat->update_ghosts();
      }
    {
      TimerOutput::Scope t(timer, "setup: metal fraction");
      heat->set_metal_fraction(points->metal_fraction());
    }
    if (melt_flow)
      {
        flow_prm.latent_heat_evaporation = heat_prm.latent_heat_evaporation;
        flow_prm.evaporation_temperature = heat_prm.evaporation_temperature;
        flow_prm.molar_mass              = heat_prm.molar_mass;
        flow_prm.ambient_pressure        = heat_prm.ambient_pressure;
        flow = std::make_unique<IncompressibleFlow<dim>>(flow_prm, material,
                                                         *grid, *points, &timer);
        flow->set_liquid_fraction(&heat->liquid_fraction());
        flow->set_temperature(&heat->temperature());
        // Heat moves with the flow either on the points (taken when they
        // change cells, flow_substeps()) or by upwind convection of T.
        if (heat_prm.advection_by_melt_flow == "upwind")
          heat->set_velocity(&flow->cell_velocity());
      }
    output = std::make_unique<Output<dim>>(output_prm, *grid);
    {
      std::vector<std::string> names;
      for (const auto &f : output_fields())
        names.push_back(f.name);
      output->initialize(names);
    }
    if (solid_enabled)
      {
        TimerOutput::Scope t(timer, "setup: solid");
        solid = std::make_unique<SolidStress<dim>>(solid_prm, fem_prm,
                                                   solid_material, *grid,
                                                   *points);
        if (flow)
          {
            // Flow and solid together (doc/solid.md): the flow owns the
            // fluid points' velocities; its forces on the solid enter
            // through the solid's external nodal forces.
            solid->set_flow_owns_fluid_points(true);
            // Fragments that solidify where the flow left them: no force
            // on nodes with less than `Solid/Small mass cutoff` (default
            // 5 %) of a full node's mass (stability estimate and choice:
            // doc/solid.md).
            solid->set_small_mass_cutoff(solid_prm.small_mass_cutoff);
            for (int d = 0; d < dim; ++d)
              fluid_force[d] = grid->make_node_field();
            solid->set_external_nodal_forces(&fluid_force);
          }
        solid->initialize(heat->temperature(), output_prm.directory);
      }

    pcout << "femp: " << dim << "D scene, "
          << Utilities::MPI::n_mpi_processes(comm) << " MPI rank(s)\n"
          << "  background grid: " << grid->n_global_cells() << " cells of "
          << grid->h() << " m (";
    for (int d = 0; d < dim; ++d)
      pcout << grid->n_cells()[d] << (d + 1 < dim ? " x " : ")\n");
    pcout << "  material points: " << points->n_global_points() << " ("
          << points->n_powder_grains() << " powder grains, packing fraction "
          << std::setprecision(3) << points->achieved_packing_fraction() << ")\n"
          << (solid ? "  solid: " + std::to_string(int(solid->sizes()[0])) +
                        " material points, " +
                        std::to_string(int(solid->sizes()[1])) +
                        " finite elements, step " +
                        std::to_string(solid->time_step()) + " s\n" :
                      std::string())
          << "  output: " << output_prm.directory << "/grid.pvd, "
          << output_prm.directory << "/points.pvd, "
          << output_prm.directory << "/melt_pool.csv\n";
    if (dim == 3 && heat_enabled)
      {
        // Regime by the normalized enthalpy of King et al. (2014),
        // eta P/(pi h_s sqrt(D v r_b^3)), h_s = rho c T_s, D = lambda/(rho c)
        // at the solidus, largest over the laser-on segments; keyhole-mode
        // melting above about 30 (doc/absorption.md).
        const double Ts = material.solidus;
        const double rc = material.density * material.specific_heat.value(Ts);
        const double D  = material.conductivity.value(Ts) / rc;
        const double rb = laser_prm.beam_radius;
        double       ratio = 0;
        for (const auto &s : laser->segments())
          if (s.power > 0)
            ratio = std::max(ratio, laser_prm.absorptivity * s.power /
                                      (M_PI * rc * Ts *
                                       std::sqrt(D * s.speed * rb * rb * rb)));
        if (ratio > 0)
          pcout << "  regime: normalized enthalpy eta P/(pi h_s sqrt(D v r_b^3)) = "
                << std::setprecision(3) << ratio
                << (ratio >= 30 ?
                      " >= 30: keyhole mode likely; a fixed absorptivity on the "
                      "first surface underestimates the depth there (ray-traced "
                      "absorption: doc/absorption.md)\n" :
                      (ratio >= 20 ? " (near the keyhole transition at ~30, "
                                     "doc/absorption.md)\n" :
                                     " < 30: conduction mode\n"));
      }
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
        return std::min(dt, time_prm.end_time - time);
      }
    const double stable =
      step == 0 ? heat->stable_time_step() : heat->last_stable_time_step();
    double dt = time_prm.time_step > 0 ? time_prm.time_step :
                                         time_prm.safety_factor * stable;
    if (time_prm.time_step > stable)
      {
        std::ostringstream s;
        s << "it exceeds the stable limit " << stable << " s of the explicit "
          << "temperature step" << (step > 0 ? " reached at step " + std::to_string(step) +
                                                 ", time " + num(time) + " s" :
                                               std::string())
          << "; use 0 (automatic) or a step <= " << stable << " s";
        throw InputError("Time stepping/Time step",
                         std::to_string(time_prm.time_step), s.str());
      }
    return std::min(dt, time_prm.end_time - time);
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
  FempProblem<dim>::write_output(const unsigned int n,
                                 const double       time,
                                 const bool         last)
  {
    TimerOutput::Scope t(timer, "output");
    std::vector<double> phase(grid->n_local(), 0.);
    const auto &        a = heat->metal_fraction();
    const auto &        g = heat->liquid_fraction();
    for (std::size_t i = 0; i < phase.size(); ++i)
      phase[i] = a[i] <= 0 ? 0 : (g[i] <= 0 ? 1 : (g[i] < 1 ? 2 : 3));
    const std::vector<double> zone = points->zone_tags();
    auto fields = output_fields();
    std::vector<double> sigma_xx, von_mises;
    if (solid)
      {
        solid->cell_stress_fields(sigma_xx, von_mises);
        fields.push_back({"sigma_xx", &sigma_xx});
        fields.push_back({"von_mises", &von_mises});
      }
    fields.push_back({"laser_source", &heat->laser_source()});
    fields.push_back({"phase", &phase});
    fields.push_back({"zone", &zone});
    const bool with_points = output_prm.write_points == "always" ||
                             (output_prm.write_points == "last" && last);
    output->write_fields(n, time, fields,
                         with_points ? &points->particle_handler() : nullptr,
                         points->used_property_names());
    output->write_probe_lines(n, time, output_fields());
  }


  template <int dim>
  void
  FempProblem<dim>::run()
  {
    const auto wall_start = std::chrono::steady_clock::now();
    setup();

    const double H0   = heat->stored_enthalpy();
    double       time = 0;
    unsigned int step = 0, n_output = 0;
    double       next_output = output_prm.output_interval;
    double       next_series = 0;
    write_output(n_output++, time, false);

    while (time < time_prm.end_time * (1 - 1e-12) && step < time_prm.max_steps)
      {
        const double dt = choose_time_step(step, time);

        // 1. Tag cells, alpha, gamma, properties: alpha changes only when
        //    points move (the melt-flow and solid modules), so nothing to do
        //    in a thermal-only scene; gamma and the properties follow T
        //    inside HeatTransfer::advance().

        // 2. Temperature in fluid, solid and powder (eq. 1).
        if (heat_enabled)
          {
            TimerOutput::Scope t(timer, "temperature step");
            heat->advance(dt, time);
          }
        {
          TimerOutput::Scope t(timer, "cells to points");
          points->cells_to_points(heat->temperature());
        }
        if (melt_flow && solid)
          {
            // Points that melted leave the solid with the velocity they had
            // in it (booked before the flow changes it).
            TimerOutput::Scope t(timer, "solid");
            solid->find_state_changes();
          }

        // 3. Melt-pool flow (IncompressibleFlow, eqs. 3-4), sub-cycled;
        //    with the solid, the fluid forces on it (eq. 13), held over
        //    the solid sub-steps of step 4.
        if (melt_flow)
          flow_substeps(dt);
        if (melt_flow && solid)
          {
            TimerOutput::Scope t(timer, "flow: forces on the solid");
            fluid_forces_to_solid_nodes();
          }

        time += dt;
        ++step;
        const bool last = time >= time_prm.end_time * (1 - 1e-12) ||
                          step >= time_prm.max_steps;

        // 4. Solid stress (SolidMPM + SolidFEM coupled, eqs. 5-17),
        //    sub-cycled against the temperature step.
        if (solid)
          {
            TimerOutput::Scope t(timer, "solid");
            solid->advance(time, heat->temperature(), last);
          }

        // 5. Output.
        if (time >= next_series * (1 - 1e-12) || last)
          {
            TimerOutput::Scope t(timer, "time series");
            result.pool = measure_melt_pool(*grid, heat->temperature(),
                                            heat->metal_fraction(),
                                            melt_temperature,
                                            points_prm.substrate_top,
                                            heat->material().solidus);
            output->write_series(time, output_fields(), result.pool);
            next_series = time + output_prm.series_interval;
          }
        if ((output_prm.output_interval > 0 &&
             time >= next_output * (1 - 1e-9)) ||
            (output_prm.output_steps > 0 && step % output_prm.output_steps == 0) ||
            last)
          {
            write_output(n_output++, time, last);
            while (next_output <= time * (1 + 1e-9) &&
                   output_prm.output_interval > 0)
              next_output += output_prm.output_interval;
          }
        if (step % output_prm.progress_interval == 0 || last)
          {
            const double wall = std::chrono::duration<double>(
                                  std::chrono::steady_clock::now() - wall_start)
                                  .count();
            const double left = wall / time * (time_prm.end_time - time);
            pcout << std::setprecision(4) << "t = " << std::setw(10) << time
                  << " s  step " << std::setw(7) << step << "  dt = "
                  << std::setw(10) << dt << " s  T_max = " << std::setw(8)
                  << heat->max_temperature() << " K  pool L x W x D = "
                  << result.pool.length * 1e6 << " x "
                  << result.pool.width * 1e6 << " x "
                  << result.pool.depth * 1e6 << " um  wall "
                  << std::setprecision(3) << wall << " s, left ~" << left
                  << " s" << std::endl;
          }
      }
    result.steps = step;
    result.time  = time;
    result.T_max = heat->max_temperature();

    const auto e    = heat->energy_budget();
    result.laser    = e.laser;
    result.losses   = heat->total_losses();
    result.boundary = e.boundary;
    result.advection = e.advection;
    result.stored   = heat->stored_enthalpy() - H0;
    result.n_points = points->n_global_points();
    {
      double sum = 0;
      for (const auto &p : points->particle_handler())
        sum += p.get_properties()[MaterialPoints<dim>::PropertyIndex::temperature];
      result.point_T_mean =
        Utilities::MPI::sum(sum, comm) / std::max<double>(1, result.n_points);
    }
    if (solid)
      {
        result.solid_steps  = solid->n_steps();
        result.solid_energy = solid->energies();
        const auto &e       = result.solid_energy;
        pcout << std::setprecision(6) << "Solid: " << result.solid_steps
              << " steps of " << solid->time_step()
              << " s; energies (J" << (dim == 2 ? "/m" : "")
              << "): external work " << e.external << ", stress work "
              << e.internal << ", kinetic " << e.kinetic << ", hourglass "
              << e.hourglass << ", balance " << e.balance()
              << "; kinetic/internal " << e.kinetic / std::max(1e-300, std::abs(e.internal))
              << std::endl;
      }
    if (!heat_enabled)
      pcout << "Energy: heat transfer off (Physics/Heat transfer = false), "
               "temperature frozen at its initial field"
            << std::endl;
    else
      pcout << std::setprecision(6) << "Energy (J" << (dim == 2 ? "/m" : "")
            << "): laser " << result.laser << ", surface losses "
            << result.losses << " (evaporation " << e.evaporation
            << ", convection " << e.convection << ", radiation " << e.radiation
            << " at the end of each step), fixed faces " << result.boundary
            << ", stored " << result.stored << "; balance error "
            << std::abs(result.laser + result.boundary - result.losses -
                        result.stored) /
                 std::max(1e-300, std::max(result.laser + std::abs(result.boundary),
                                           result.losses))
            << std::endl;
    if (heat_enabled && flow)
      pcout << std::setprecision(6)
            << "  with melt flow, energy created (J" << (dim == 2 ? "/m" : "")
            << ") by the upwind convection of T " << result.advection
            << " and by points moving between cells " << result.moved_points
            << "; balance error with these counted as sources "
            << std::abs(result.laser + result.boundary + result.advection +
                        result.moved_points - result.losses - result.stored) /
                 std::max(1e-300, std::max(result.laser + std::abs(result.boundary),
                                           result.losses))
            << std::endl;
    if (flow)
      {
        const auto &st                = flow->statistics();
        result.flow_steps             = st.steps;
        result.pressure_matrix_builds = st.matrix_rebuilds;
        result.pressure_cg_iterations = st.cg_iterations;
        result.max_fluid_speed        = st.max_point_speed;
        pcout << "Melt flow: " << st.steps << " fluid steps, pressure matrix "
              << "graph built " << st.matrix_rebuilds << " times, AMG "
              << "hierarchy " << st.amg_setups << " times, CG iterations " << st.cg_iterations << " in total ("
              << std::setprecision(3)
              << double(st.cg_iterations) / std::max(1u, st.steps)
              << " per solve, at most " << st.max_iterations
              << "), " << st.halvings << " steps redone as halves, points "
              << "re-sorted in " << st.resorts << " steps (" << st.global_sorts
              << " with deal.II's global sort), "
              << st.n_fluid_cells << " fluid cells and max speed "
              << st.max_point_speed << " m/s at the end" << std::endl;
        if (st.volume_iterations > 0 || st.volume_skipped > 0)
          pcout << "Melt flow volume correction: " << st.volume_iterations
                << " CG iterations in total, " << st.volume_skipped
                << " solves not converged (no correction in those steps)"
                << std::endl;
        const auto &r = result.flow_limits;
        pcout << std::setprecision(4)
              << "Melt flow time step limits (smallest over the run): "
              << "convective " << r.convective << " s, viscous " << r.viscous
              << " s, capillary " << r.capillary << " s (used x "
              << r.capillary_fraction << ")\n"
              << "  sub-steps governed by: convective " << r.governed[0]
              << ", viscous " << r.governed[1] << ", capillary "
              << r.governed[2] << ", prescribed (Melt flow/Time step) "
              << r.governed[3] << "; sub-steps per temperature step "
              << (r.max_substeps > 0 ? r.min_substeps : 0) << " to "
              << r.max_substeps << std::endl;
      }
    timer.print_summary();
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
    auto &             r       = result.flow_limits;
    double             t       = 0;
    unsigned int       n_sub   = 0;
    while (t < dt * (1 - 1e-12))
      {
        const auto l = flow->stable_time_step();
        r.convective = std::min(r.convective, l.convective);
        r.viscous    = std::min(r.viscous, l.viscous);
        r.capillary  = std::min(r.capillary, l.capillary);
        r.capillary_fraction = l.capillary_fraction;
        const double wanted  = flow_prm.time_step > 0 ? flow_prm.time_step : l.min();
        ++r.governed[flow_prm.time_step > 0 ? 3 : l.governing()];
        // Equal sub-steps over the rest of the temperature step, none above
        // the wanted step: no tiny last sub-step (uneven sub-steps shortened
        // the droplet period in prm/oscillating_droplet.prm).
        const double rest = dt - t;
        const double dt_f =
          rest / std::max(1., std::ceil(rest / wanted * (1 - 1e-12)));
        flow->step(dt_f);
        t += dt_f;
        ++n_sub;
      }
    r.min_substeps = std::min(r.min_substeps, n_sub);
    r.max_substeps = std::max(r.max_substeps, n_sub);
    if (flow->statistics().resorts == resorts)
      return;
    // Points changed cells: new alpha; cells that gained metal take the
    // mean temperature of their points (METHOD sec. 2).
    TimerOutput::Scope  scope(timer, "flow: alpha and new metal cells");
    // Energy bookkeeping: the stored enthalpy before and after (collective).
    const double        H_before = heat_enabled ? heat->stored_enthalpy() : 0.;
    std::vector<double> alpha = points->metal_fraction();
    const auto &        old   = heat->metal_fraction();
    using P                   = typename MaterialPoints<dim>::PropertyIndex;
    if (heat_enabled && heat_prm.advection_by_melt_flow == "points")
      {
        // The points carry the heat: every cell whose points came from
        // cells at other temperatures takes their mean specific enthalpy
        // (cells that gained metal included).
        const auto mean_e = points->volume_mean_over_points(
          heat->temperature(),
          [this](const double T) { return heat->specific_enthalpy(T); });
        heat->set_metal_fraction(alpha);
        heat->take_point_enthalpy(mean_e);
        result.moved_points += heat->stored_enthalpy() - H_before;
        return;
      }
    // (With a frozen temperature the field keeps its initial values.)
    if (heat_enabled)
      {
      for (const auto &[idx, cell] : points->occupied_cells())
        if (old[idx] <= 0 && alpha[idx] > 0)
          {
            double sum = 0, n = 0;
            for (const auto &particle : points->particle_handler().particles_in_cell(cell))
              sum += particle.get_properties()[P::temperature], ++n;
            // gamma from T: a stale gamma (0 in a former gas cell) would
            // take the latent heat of a hot arrival from its sensible heat
            // at the next step (cooling it by up to L_m/c_m ~ 350 K).
            if (n > 0)
              heat->set_cell_temperature(idx, sum / n);
          }
      }
    heat->update_ghosts();
    heat->set_metal_fraction(alpha);
    if (heat_enabled)
      result.moved_points += heat->stored_enthalpy() - H_before;
  }

  template <int dim>
  void
  FempProblem<dim>::fluid_forces_to_solid_nodes()
  {
    // Flow and solid together (doc/solid.md): the fluid force through each
    // face of an owned solid cell to a fluid cell goes to the face's
    // 2^(dim-1) grid nodes, to node I the share
    //   F_face / 2^(dim-1) * min(1, m_I / (m_ref / 2)),
    // m_I = sum_p N_I(x_p) m_p over the cell's solid points, m_ref = rho
    // h^dim / 2^dim the share of a full cell. A full cell gets the face
    // force exactly (equal shares: the traction on the face), also when
    // its points have moved by up to a quarter cell; a node that holds
    // only a small part of a point's mass gets a force in proportion, so
    // its acceleration is at most twice that of a node of a full cell (a
    // whole face force on such a node made the 3D track scene blow up). Spreading over the points with their tents instead was stable
    // but put half of the face force on the far nodes of the cell (the
    // stress under the interface 0.47 short in coupled_pool_on_solid).
    // Cells of the FE zone: equal shares. Cells with no solid point
    // (powder only): no force; the unmelted powder carries no stress.
    using P = typename MaterialPoints<dim>::PropertyIndex;
    flow->fluid_forces_on_solid(fluid_face_force);
    for (int d = 0; d < dim; ++d)
      std::fill(fluid_force[d].begin(), fluid_force[d].end(), 0.);
    constexpr unsigned int n_corners = 1u << dim;
    const double           h = grid->h(), ih = 1. / h;
    const double           m_ref = material.density * std::pow(h, dim) / n_corners;
    const auto &           x0    = grid->origin();
    const auto &           ns    = grid->node_strides();
    std::array<std::size_t, n_corners> offset;
    for (unsigned int k = 0; k < n_corners; ++k)
      {
        offset[k] = 0;
        for (int d = 0; d < dim; ++d)
          if ((k >> d) & 1)
            offset[k] += ns[d];
      }
    auto &handler = points->particle_handler();
    for (const auto c : grid->owned_cells())
      {
        bool any = false;
        for (const auto &f : fluid_face_force)
          any = any || f[c] != 0;
        if (!any)
          continue;
        const auto        ijk = grid->global_index(c);
        const std::size_t n0  = grid->first_node_of_cell(c);
        // Share of each corner: 1 in the FE zone, else min(1, 2 m_I / m_ref).
        std::array<double, n_corners> share;
        bool fe = fem_prm.enabled;
        for (int d = 0; d < dim; ++d)
          {
            const double xc = x0[d] + (ijk[d] + 0.5) * h;
            fe = fe && xc > fem_prm.lower_corner[d] && xc < fem_prm.upper_corner[d];
          }
        if (fe)
          share.fill(1.);
        else
          {
            share.fill(0.);
            for (const auto &particle :
                 handler.particles_in_cell(grid->cell_iterator(c)))
              {
                const auto v = particle.get_properties();
                if (v[P::state] != MaterialPoints<dim>::solid)
                  continue;
                const Point<dim> &x = particle.get_location();
                double            w[n_corners];
                tent_weights<dim>(x, x0, ih, ijk, v[P::mass] / (0.5 * m_ref), w);
                for (unsigned int k = 0; k < n_corners; ++k)
                  share[k] += w[k];
              }
            for (auto &s : share)
              s = std::min(1., s);
          }
        for (int d = 0; d < dim; ++d)
          for (unsigned int side = 0; side < 2; ++side)
            {
              const unsigned int f = dim * (2 * d + side);
              for (unsigned int k = 0; k < n_corners; ++k)
                if (((k >> d) & 1) == side)
                  for (int e = 0; e < dim; ++e)
                    fluid_force[e][n0 + offset[k]] +=
                      fluid_face_force[f + e][c] * share[k] / (n_corners / 2);
            }
      }
  }

  template class FempProblem<2>;
  template class FempProblem<3>;
} // namespace femp
