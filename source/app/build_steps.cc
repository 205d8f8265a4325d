// femp: BuildSteps (see the header): the layer schedule, the recoat in the
// step where a layer starts, and the pore detector's output.
#include <femp/app/build_steps.h>

#include <iomanip>

namespace femp
{
  template <int dim>
  BuildSteps<dim>::BuildSteps(const Scene<dim> &scene, const Laser<dim> &laser)
      : scene(scene)
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
    if (schedule)
      recoater = std::make_unique<Recoater<dim>>(scene.points,
                                                 scene.material.density,
                                                 grid);
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
                          const ConditionalOStream &pcout)
  {
    if (!recoater)
      return;
    for (const auto &layer : schedule->layers())
      {
        // Each layer in the one step whose [t, t + dt) holds its start
        // (the same steps after a resume: no state to save).
        if (!(layer.start_time >= t && layer.start_time < t + dt))
          continue;
        TimerOutput::Scope scope(timer, "recoat");
        const double       T = scene.build.powder_temperature > 0 ?
                                 scene.build.powder_temperature :
                                 scene.heat.reference_temperature;
        const auto         r = recoater->recoat(points, layer, T);
        // The new points: alpha and the heat of the cells they entered.
        point_heat.follow_points();
        pcout << "Recoat: layer " << r.layer << " at t = " << t
              << " s: " << r.grains << " grains, packing fraction "
              << std::setprecision(3) << r.packing << " of the "
              << r.fill_volume << (dim == 3 ? " m^3" : " m^2")
              << " between the surface (z " << r.surface_min << " to "
              << r.surface_max << " m) and the top " << layer.top << " m; "
              << r.points << " points at " << T << " K" << std::setprecision(6)
              << std::endl;
      }
  }

  template class BuildSteps<2>;
  template class BuildSteps<3>;
} // namespace femp
