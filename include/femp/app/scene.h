// femp: the scene of a run: every module's parameters read from the input
// (one declaration of all of them, declare_parameters()), the checks that
// need the parameters of several modules, the automatic depth of the FE
// zone ('Solid FEM/Zone upper corner = auto', fe_zone_depth.h), the
// partition cost of a cell, the part of the scene a checkpoint must share,
// and the printout of the scene and its melting regime. It is built before
// any module and refuses bad input (InputError) before any work.
#ifndef femp_scene_h
#define femp_scene_h

#include <deal.II/base/conditional_ostream.h>
#include <deal.II/base/parameter_handler.h>

#include <femp/app/simulation_control.h>
#include <femp/base/material.h>
#include <femp/builds/pore_detector.h>
#include <femp/builds/recoater.h>
#include <femp/builds/track_record.h>
#include <femp/flow/incompressible_flow.h>
#include <femp/grid/background_grid.h>
#include <femp/grid/material_points.h>
#include <femp/heat/heat_transfer.h>
#include <femp/heat/laser.h>
#include <femp/heat/ray_traced_absorption.h>
#include <femp/heat/thermal_history.h>
#include <femp/io/checkpoint.h>
#include <femp/io/output.h>
#include <femp/io/track_shape.h>
#include <femp/solid/fe_zone_handover.h>
#include <femp/solid/solid_sub_cycle.h>

#include <functional>

namespace femp
{
  using namespace dealii;

  /// Declare every parameter of femp (all modules) in @p prm.
  void
  declare_all_parameters(ParameterHandler &prm);

  template <int dim>
  class Scene
  {
  public:
    /// Read every module's parameters from @p prm and check them, alone
    /// and across modules; 'Zone upper corner = auto' is resolved here
    /// (and said on @p out). Throws InputError before any work.
    Scene(ParameterHandler &prm, ConditionalOStream &out);
    Scene(const Scene &) = delete;
    Scene &
    operator=(const Scene &) = delete;

    // Physics switched on (subsection 'Physics').
    /// Physics/Heat transfer: false freezes the temperature field.
    bool heat_enabled = true;
    bool melt_flow    = false;
    bool solid        = false;
    /// Physics/Gravity, m/s^2: the one gravity of the flow and the solid.
    Tensor<1, dim> gravity;

    SimulationControl::Parameters time;
    /// The material, owner of the data that several modules read (density,
    /// solidus, liquidus, evaporation data), passed by const reference.
    Material                                      material;
    typename BackgroundGrid<dim>::Parameters      grid;
    typename MaterialPoints<dim>::Parameters      points;
    typename HeatTransfer<dim>::Parameters        heat;
    typename Laser<dim>::Parameters               laser;
    typename RayTracedAbsorption<dim>::Parameters absorption;
    typename Output<dim>::Parameters              output;
    typename ThermalHistory<dim>::Parameters      history;
    typename IncompressibleFlow<dim>::Parameters  flow;
    /// Reads the density and solidus of @ref material.
    SolidMaterial                           solid_material{material};
    typename SolidSubCycle<dim>::Parameters solid_stress;
    typename SolidFEM<dim>::Parameters      fem;
    typename TrackShape<dim>::Parameters    track;
    typename Checkpoint<dim>::Parameters    checkpoint;
    /// Layers, recoating and pores (doc/builds.md).
    typename LayerSchedule<dim>::Parameters build;
    typename PoreDetector<dim>::Parameters  porosity;
    typename TrackRecord<dim>::Parameters   track_record;
    /// The hand-over of cooled metal to the FE zone (Build subsection).
    typename FeZoneHandover<dim>::Parameters handover;

    /// The cadence of field output, time series and progress line (read
    /// from the Output parameters, here only).
    SimulationControl::Cadence
    cadence() const;
    /// The solid or the melt flow transfers velocities by APIC (the points
    /// carry C_p; the layout block of C_p follows the solid block, so
    /// the points then carry the solid block too).
    bool
    affine_points() const;
    /// Properties a material point carries in this scene.
    unsigned int
    n_point_properties() const;
    /// What a checkpoint must share with this scene.
    typename Checkpoint<dim>::Scene
    checkpoint_scene() const;
    /// Relative cost of a background cell (centre) for the partition over
    /// the ranks; empty: every cell costs the same. From the scene's
    /// geometry at the start, or, with @p resumed (the checkpoint read,
    /// null for a new run) and 'Checkpoint/Partition on resume =
    /// checkpoint', from the checkpoint's FE zone and points per cell.
    std::function<unsigned int(const Point<dim> &)>
    partition_cost(const Checkpoint<dim> *resumed = nullptr) const;

    /// The scene's printout: grid, points, solid sizes, output files and
    /// the melting regime of the laser. @p solid may be null.
    void
    print(ConditionalOStream        &out,
          const MPI_Comm             comm,
          const BackgroundGrid<dim> &bg,
          const MaterialPoints<dim> &mp,
          const HeatTransfer<dim>   &heat_module,
          const Laser<dim>          &laser_module,
          const SolidSubCycle<dim>  *solid_module) const;

  private:
    /// 'Solid FEM/Zone upper corner = auto': the FE zone's top below a
    /// conservative melt depth of the scene's laser (fe_zone_depth.h).
    void
    place_fe_zone_automatically(ConditionalOStream &out);
    /// Checks that need several modules' parameters.
    void
    check_across_modules() const;
    /// The melting regime of the laser (normalized enthalpy).
    void
    print_melting_regime(ConditionalOStream      &out,
                         const HeatTransfer<dim> &heat_module,
                         const Laser<dim>        &laser_module) const;
  };
} // namespace femp

#endif
