// femp: the scene of a run: every module's parameters, read and checked
// before any work (the cross-module checks, the automatic FE-zone depth),
// the partition cost, the checkpoint's scene and the scene printout.
#include <deal.II/base/mpi.h>
#include <deal.II/base/utilities.h>

#include <femp/app/physics_switches.h>
#include <femp/app/scene.h>
#include <femp/base/input_checks.h>
#include <femp/grid/saved_points.h>
#include <femp/solid/fe_zone_depth.h>
#include <femp/solid/saved_fe_zone.h>

#include <algorithm>
#include <iomanip>
#include <sstream>

namespace femp
{
  void
  declare_all_parameters(ParameterHandler &prm)
  {
    {
      ParameterTable table(prm, ParameterTable::Mode::declare);
      unsigned int   dimension = 3;
      table.add("Dimension",
                dimension,
                Patterns::Integer(2, 3),
                "Space dimension of the scene: 2 or 3.");
    }
    PhysicsSwitches::declare_parameters(prm);
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
    SolidSubCycle<3>::Parameters::declare_parameters(prm);
    SolidFEM<3>::Parameters::declare_parameters(prm);
    Checkpoint<3>::Parameters::declare_parameters(prm);
    LayerSchedule<3>::Parameters::declare_parameters(prm);
    PoreDetector<3>::Parameters::declare_parameters(prm);
    TrackRecord<3>::Parameters::declare_parameters(prm);
    FeZoneHandover<3>::Parameters::declare_parameters(prm);
  }

  template <int dim>
  Scene<dim>::Scene(ParameterHandler &prm, ConditionalOStream &out)
  {
    PhysicsSwitches physics;
    physics.parse_parameters(prm);
    melt_flow      = physics.melt_flow;
    heat_enabled   = physics.heat_transfer;
    solid          = physics.solid_stress;
    const double g = physics.gravity;
    require(g >= 0,
            "Physics/Gravity",
            g,
            "it must be a magnitude >= 0 (m/s^2; it acts along -y in 2D, "
            "-z in 3D)");
    gravity[dim - 1] = -g;
    time.parse_parameters(prm);
    material.parse_parameters(prm);
    grid.parse_parameters(prm);
    points.parse_parameters(prm);
    points.check(grid);
    heat.parse_parameters(prm);
    heat.check(grid.lower_corner, grid.upper_corner, grid.cell_size);
    flow.parse_parameters(prm);
    flow.gravity = gravity;
    if (melt_flow)
      flow.check_time_step(grid.cell_size, material.density);
    laser.parse_parameters(prm);
    absorption.parse_parameters(prm);
    output.parse_parameters(prm);
    history.parse_parameters(prm);
    track.parse_parameters(prm);
    build.parse_parameters(prm);
    porosity.parse_parameters(prm);
    track_record.parse_parameters(prm);
    handover.parse_parameters(prm);
    // A bare plate without flow or solid carries no points (Material
    // points/Carry points = auto); a layer schedule needs them (the
    // recoated powder).
    points.resolve_carry(melt_flow,
                         solid,
                         track.enabled(melt_flow) || build.enabled());
    output.check(grid.lower_corner, grid.upper_corner);
    if (solid)
      {
        solid_material.parse_parameters(prm);
        solid_stress.parse_parameters(prm);
        solid_stress.gravity = gravity;
        solid_stress.check(solid_material, grid);
        fem.parse_parameters(prm);
        if (fem.enabled && fem.automatic_top)
          place_fe_zone_automatically(out);
        fem.check(grid);
      }
    check_across_modules();
    checkpoint.parse_parameters(prm);
    handover.check(material.solidus,
                   heat_enabled,
                   solid,
                   solid && fem.enabled,
                   build.enabled());
  }

  template <int dim>
  void
  Scene<dim>::place_fe_zone_automatically(ConditionalOStream &pcout)
  {
    // 'Zone upper corner = auto' (fe_zone_depth.h, doc/cases.md): the top
    // below the conservative melt depth of the laser's strongest moving
    // segment.
    require(dim == 3,
            "Solid FEM/Zone upper corner",
            "auto",
            "'auto' is for 3D scenes; give the corner's coordinates");
    double           d = 0;
    const Laser<dim> path(laser);
    for (const auto &s : path.segments())
      if (s.power > 0 && s.speed > 0)
        d = std::max(d,
                     conservative_melt_depth(material,
                                             laser.absorptivity * s.power,
                                             s.speed,
                                             heat.initial_temperature));
    fem.upper_corner          = grid.upper_corner;
    fem.upper_corner[dim - 1] = automatic_fe_zone_top(
      d, points.substrate_top, grid.lower_corner[dim - 1], grid.cell_size);
    pcout << "Solid FEM: zone top 'auto' at z = " << fem.upper_corner[dim - 1]
          << " m (conservative melt depth " << d
          << " m below the substrate top " << points.substrate_top
          << " m, margin 1.1 d + 2 cells)" << std::endl;
  }

  template <int dim>
  void
  Scene<dim>::check_across_modules() const
  {
    require(time.stop_temperature == 0 ||
              (heat_enabled &&
               time.stop_temperature > heat.initial_temperature),
            "Time stepping/Stop when peak temperature below",
            time.stop_temperature,
            "0 (off), or with Physics/Heat transfer a temperature above the "
            "initial temperature " +
              num(heat.initial_temperature) + " K");
    require(heat_enabled || melt_flow || time.time_step > 0,
            "Time stepping/Time step",
            time.time_step,
            "with 'Physics/Heat transfer = false' and no melt flow nothing "
            "sets the step: prescribe it (s, > 0)");
    require(!solid || !solid_stress.adaptive_after_solidification ||
              (melt_flow && heat_enabled),
            "Solid/Mass scaling after solidification",
            "adaptive",
            "it switches when the melt has solidified after the laser's "
            "path: it needs 'Physics/Melt flow = true' and 'Physics/Heat "
            "transfer = true' (without the melt flow set 'Solid/Mass "
            "scaling = adaptive')");
    require(build.rebalance_above == 0 || grid.partition_by_cost,
            "Build/Rebalance above imbalance",
            build.rebalance_above,
            "with 'Background grid/Partition = cells' it cannot act: a "
            "rebalance re-cuts the grid by the run's cost, which only "
            "'Background grid/Partition = cost' does; allowed: 0 (never) "
            "with 'Partition = cells', or 'Partition = cost' with 0 or a "
            "ratio in [1, inf)");
    require(time.time_step_solidified == 0 || heat_enabled,
            "Time stepping/Time step after solidification",
            time.time_step_solidified,
            "0: with 'Physics/Heat transfer = false' nothing melts or "
            "solidifies");
    if (time.time_step > 0 && heat_enabled)
      {
        // Upper bound of the stable diffusion step of any cell full of
        // metal; the exact limit is checked again at every step.
        const double h     = grid.cell_size;
        const double bound = h * h * material.density *
                             material.specific_heat.max_value() /
                             (2 * dim * material.conductivity.min_value());
        std::ostringstream allowed;
        allowed << "it exceeds the stable limit of the explicit temperature "
                   "step for every metal cell (at most "
                << bound << " s for h = " << h
                << " m and these material tables); use 0 (automatic)";
        require(time.time_step <= bound,
                "Time stepping/Time step",
                time.time_step,
                allowed.str());
        require(time.time_step_solidified <= bound,
                "Time stepping/Time step after solidification",
                time.time_step_solidified,
                allowed.str());
      }
  }

  template <int dim>
  SimulationControl::Cadence
  Scene<dim>::cadence() const
  {
    // Without laser power (or without the heat) and without probe points
    // the time series is melt_pool.csv alone, and no pool forms but from
    // a start above the liquidus: a row at each field output (at the
    // first and the last step when the fields are written only at the
    // end) instead of at every step, where the measurement and the row
    // cost as much as a step of a small scene.
    double series_interval = output.series_interval;
    if (output.probe_points.empty())
      {
        const Laser<dim> scan(laser);
        const auto      &segments = scan.segments();
        const bool       powered =
          heat_enabled &&
          std::any_of(segments.begin(), segments.end(), [](const auto &s) {
            return s.power > 0;
          });
        if (!powered)
          series_interval =
            std::max(series_interval,
                     output.output_interval > 0 ? output.output_interval :
                                                  time.end_time);
      }
    return {output.output_interval,
            output.output_steps,
            series_interval,
            output.progress_interval};
  }

  template <int dim>
  bool
  Scene<dim>::affine_points() const
  {
    return (solid && solid_material.velocity_transfer ==
                       SolidMaterial::VelocityTransfer::apic) ||
           (melt_flow && flow.affine());
  }

  template <int dim>
  unsigned int
  Scene<dim>::n_point_properties() const
  {
    return MaterialPoints<dim>::PropertyIndex::n_used(solid, affine_points());
  }

  namespace
  {
    /// Relative cost of a cell holding @p n material points, @p n_mpm of
    /// them stepped by the solid's MPM (doc/performance.md, "Balancing the
    /// ranks"): 1 per cell (the heat and flow passes over the box), 2 per
    /// point (metal fraction, temperatures to the points, relocation) and
    /// 40 more per MPM point (its loops run at every solid step, 7 to 17
    /// times per temperature step).
    unsigned int
    cell_cost(const double n, const double n_mpm)
    {
      return static_cast<unsigned int>(std::lround(1 + 2 * n + 40 * n_mpm));
    }
  } // namespace

  template <int dim>
  std::function<unsigned int(const Point<dim> &)>
  Scene<dim>::partition_cost(const Checkpoint<dim> *resumed) const
  {
    // Without points every cell costs the same: no function.
    if (!points.carry_points)
      return {};
    const double     h  = grid.cell_size;
    const Point<dim> x0 = grid.lower_corner;
    if (resumed && checkpoint.partition_by_state &&
        resumed->has_section("points"))
      {
        // The checkpoint's state: its points per cell, and of these the
        // solid ones outside the FE zone it holds (raised by the
        // hand-overs before it) as MPM points.
        std::array<unsigned int, dim> n_cells;
        std::uint64_t                 n_all = 1;
        for (int d = 0; d < dim; ++d)
          {
            n_cells[d] = static_cast<unsigned int>(
              std::round((grid.upper_corner[d] - x0[d]) / h));
            n_all *= n_cells[d];
          }
        std::vector<std::uint32_t> n, n_solid;
        auto                       point_parts = resumed->section("points");
        count_saved_points<dim>(point_parts, n_all, n, n_solid);
        FeZone<dim> zone;
        if (solid && resumed->has_section("fe zone"))
          {
            auto       zone_parts = resumed->section("fe zone");
            const auto saved      = read_saved_fe_zone<dim>(zone_parts);
            if (saved.has_cells)
              zone = FeZone<dim>(saved.first, saved.n, saved.mask, x0, h);
            else if (fem.enabled)
              {
                Point<dim> upper = fem.upper_corner;
                upper[dim - 1]   = saved.top;
                zone = FeZone<dim>(true, fem.lower_corner, upper, x0, h);
              }
          }
        else
          zone = fem.zone(x0, h);
        auto cost = std::make_shared<std::vector<unsigned int>>(n_all, 1u);
        std::array<int, dim> ijk;
        for (std::uint64_t g = 0; g < n_all; ++g)
          {
            std::uint64_t r = g;
            for (int d = 0; d < dim; ++d)
              ijk[d] = static_cast<int>(r % n_cells[d]), r /= n_cells[d];
            const bool mpm = solid && !zone.contains_cell(ijk);
            (*cost)[g]     = cell_cost(n[g], mpm ? n_solid[g] : 0.);
          }
        return [cost, n_cells, x0, h](const Point<dim> &c) {
          // Padding cells of the triangulation lie outside the grid.
          std::uint64_t g = 0;
          for (int d = dim - 1; d >= 0; --d)
            {
              const int i = static_cast<int>(std::floor((c[d] - x0[d]) / h));
              if (i < 0 || i >= static_cast<int>(n_cells[d]))
                return 1u;
              g = g * n_cells[d] + i;
            }
          return (*cost)[g];
        };
      }
    // The scene's geometry at the start: the substrate below 'Substrate
    // top' at the full point density, the powder layer at its packing
    // fraction, the substrate's points outside the FE zone the user set
    // (asked cell by cell through its mask) stepped by MPM.
    const double      full       = std::pow(h / points.point_spacing, dim);
    const double      top        = points.substrate_top;
    const double      powder_top = top + std::max(0., points.layer_thickness);
    const double      packing    = points.packing_fraction;
    const FeZone<dim> fe_zone    = fem.zone(x0, h);
    const bool        with_solid = solid;
    return [=](const Point<dim> &c) {
      const double         z = c[dim - 1];
      std::array<int, dim> ijk;
      for (int d = 0; d < dim; ++d)
        ijk[d] = static_cast<int>(std::floor((c[d] - x0[d]) / h));
      const bool in_fe = fe_zone.contains_cell(ijk);
      double     n = 0, n_mpm = 0;
      if (z < top)
        n = full, n_mpm = with_solid && !in_fe ? full : 0.;
      else if (z < powder_top)
        n = packing * full;
      return cell_cost(n, n_mpm);
    };
  }

  template <int dim>
  typename Checkpoint<dim>::Scene
  Scene<dim>::checkpoint_scene() const
  {
    typename Checkpoint<dim>::Scene s;
    for (int d = 0; d < dim; ++d)
      {
        s.n_cells[d]      = static_cast<unsigned int>(std::round(
          (grid.upper_corner[d] - grid.lower_corner[d]) / grid.cell_size));
        s.lower_corner[d] = grid.lower_corner[d];
      }
    s.cell_size = grid.cell_size;
    s.heat      = heat_enabled;
    s.flow      = melt_flow;
    s.solid     = solid;
    s.fe_zone   = solid && fem.enabled;
    if (s.fe_zone)
      for (int d = 0; d < dim; ++d)
        {
          s.fe_lower[d] = fem.lower_corner[d];
          s.fe_upper[d] = fem.upper_corner[d];
        }
    // 0 without carried points: a checkpoint resumes only the same choice.
    s.n_point_properties = points.carry_points ? n_point_properties() : 0;
    return s;
  }

  template <int dim>
  void
  Scene<dim>::print(ConditionalOStream        &pcout,
                    const MPI_Comm             comm,
                    const BackgroundGrid<dim> &bg,
                    const MaterialPoints<dim> &mp,
                    const HeatTransfer<dim>   &heat_module,
                    const Laser<dim>          &laser_module,
                    const SolidSubCycle<dim>  *solid_module) const
  {
    const std::string index =
      output.format == Output<dim>::Parameters::Format::hdf5 ? ".xdmf" : ".pvd";
    pcout << "femp: " << dim << "D scene, "
          << Utilities::MPI::n_mpi_processes(comm) << " MPI rank(s)\n"
          << "  background grid: " << bg.n_global_cells() << " cells of "
          << bg.h() << " m (";
    for (int d = 0; d < dim; ++d)
      pcout << bg.n_cells()[d] << (d + 1 < dim ? " x " : ")\n");
    if (mp.carried())
      {
        pcout << "  material points: " << mp.n_global_points();
        if (mp.n_powder_grains() > 0)
          pcout << " (" << mp.n_powder_grains()
                << " powder grains, packing fraction " << std::setprecision(3)
                << mp.achieved_packing_fraction() << ")\n";
        else
          pcout << " (no powder layer)\n";
      }
    else
      pcout << "  material points: none (Material points/Carry points = auto: "
               "a bare plate without melt flow or solid; alpha from the "
               "substrate's lattice)"
            << (output.write_points !=
                    Output<dim>::Parameters::WritePoints::never ?
                  "; 'Output/Write material points = " +
                    choice_name(output.write_points,
                                Output<dim>::Parameters::write_points_names()) +
                    "' writes nothing (Carry points = always for point files)" :
                  std::string())
            << "\n";
    const unsigned int n_ranks = Utilities::MPI::n_mpi_processes(comm);
    std::string        solid_line;
    if (solid_module)
      {
        // With several ranks, the largest share of the MPM points on one
        // rank: what the partition leaves for the solid's point loops.
        const auto         n     = solid_module->sizes();
        const double       n_max = solid_module->largest_rank_points();
        std::ostringstream s;
        s << "  solid: " << int(n[0]) << " material points";
        if (n_ranks > 1 && n[0] > 0)
          s << " (at most " << std::fixed << std::setprecision(1)
            << 100 * n_max / n[0] << " % on one rank)" << std::defaultfloat;
        s << ", " << int(n[1]) << " finite elements, step "
          << num(solid_module->time_step()) << " s\n";
        solid_line = s.str();
      }
    pcout << std::setprecision(3) << solid_line
          << "  output: " << output.directory << "/grid" << index << ", "
          << (mp.carried() && output.write_points !=
                                Output<dim>::Parameters::WritePoints::never ?
                output.directory + "/points" + index + ", " :
                std::string())
          << output.directory << "/melt_pool.csv\n";
    if (dim == 3 && heat_enabled)
      print_melting_regime(pcout, heat_module, laser_module);
  }

  template <int dim>
  void
  Scene<dim>::print_melting_regime(ConditionalOStream      &pcout,
                                   const HeatTransfer<dim> &heat_module,
                                   const Laser<dim>        &laser_module) const
  {
    // Regime by the normalized enthalpy of King et al. (2014),
    // eta P/(pi h_s sqrt(D v r_b^3)), h_s = rho c T_s, D = lambda/(rho c)
    // at the solidus, largest over the laser-on segments. The thresholds
    // are those of the measured single tracks in this definition
    // (doc/validation.md, "Which regime"): conduction below about 2.5,
    // transition or keyhole from about 3 (depth/width 0.7 and more).
    const double Ts    = material.solidus;
    const double rc    = material.density * material.specific_heat.value(Ts);
    const double D     = material.conductivity.value(Ts) / rc;
    const double rb    = laser.beam_radius;
    double       ratio = 0;
    for (const auto &s : laser_module.segments())
      if (s.power > 0)
        ratio =
          std::max(ratio,
                   laser.absorptivity * s.power /
                     (M_PI * rc * Ts * std::sqrt(D * s.speed * rb * rb * rb)));
    if (ratio > 0)
      pcout << "  regime: normalized enthalpy eta P/(pi h_s sqrt(D v r_b^3)) = "
            << std::setprecision(3) << ratio
            << (ratio >= 3 ?
                  " >= 3: transition or keyhole mode likely; a fixed "
                  "absorptivity on the first surface underestimates the "
                  "depth there" :
                  (ratio >= 2.5 ?
                     " (near the conduction-to-keyhole transition at ~3)" :
                     " < 2.5: conduction mode\n"));
    if (ratio >= 2.5)
      pcout << (heat_module.ray_traced() ?
                  "; ray-traced absorption on (doc/absorption.md)\n" :
                  "; use 'Laser/Absorption model = ray traced' "
                  "(doc/absorption.md)\n");
  }

  template class Scene<2>;
  template class Scene<3>;
} // namespace femp
