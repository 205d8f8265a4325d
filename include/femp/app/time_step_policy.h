// femp: the time-step policy of a run, the rules that choose the
// temperature step and end the run early (in the spirit of ASPECT's
// time-stepping manager; the clock itself is SimulationControl):
//  - the step: 'Time stepping/Time step', or the safety factor times the
//    stable limit of the explicit heat step (eq. 1), or with a frozen
//    temperature the fluid step; a prescribed step above the stable limit
//    is refused (collective InputError);
//  - the projected number of steps, refused above 'Maximum number of
//    steps' at the first step;
//  - the cooling step 'Time step after solidification';
//  - the termination criteria: the solid's switch to its cooling step and
//    the stop 'Stop when peak temperature below'.
// It also sets the flow's sub-cycle its limits (the sub-step bound, the
// idle test: may the metal melt in this step?).
// The cooling step, the solid's switch and the stop test ask one question,
// after_path_and_below(): has the laser's path ended and is the metal
// attached to the substrate (MetalBodies' workpiece) below a temperature?
#ifndef femp_time_step_policy_h
#define femp_time_step_policy_h

#include <deal.II/base/conditional_ostream.h>

#include <femp/app/scene.h>
#include <femp/app/simulation_control.h>
#include <femp/flow/incompressible_flow.h>
#include <femp/grid/cell_fields.h>
#include <femp/grid/metal_bodies.h>
#include <femp/heat/heat_transfer.h>
#include <femp/heat/laser.h>
#include <femp/solid/solid_sub_cycle.h>

#include <functional>
#include <optional>

namespace femp
{
  using namespace dealii;

  template <int dim>
  class TimeStepPolicy
  {
  public:
    /// @p flow may be null (no melt flow); @p bodies: the bodies of the
    /// heat's alpha.
    TimeStepPolicy(const Scene<dim>              &scene,
                   const Laser<dim>              &laser,
                   HeatTransfer<dim>             &heat,
                   MetalBodies<dim>              &bodies,
                   const IncompressibleFlow<dim> *flow,
                   ConditionalOStream            &out);

    /// The wanted temperature step at (@p step, @p time) (the
    /// SimulationControl's step chooser): see the file's comment. At step
    /// 0 the exact stable limit is computed from @p fields.
    double
    choose(const unsigned int     step,
           const double           time,
           const CellFields<dim> &fields);

    /// A new temperature step begins: T and alpha are about to change,
    /// the workpiece's peak temperature is computed again when asked.
    void
    begin_step()
    {
      metal_peaks.reset();
    }

    /// Termination criterion 'Stop when peak temperature below': true (and
    /// said) when the laser's path has ended by @p time_end and the
    /// workpiece is below that temperature. Collective.
    bool
    cooled_down(const double time_end);

    /// Termination criterion of the solid's normal step: true when the
    /// solid has a larger cooling step that is not in use yet, the laser's
    /// path has ended by @p time and the workpiece is below the solidus.
    /// Collective.
    bool
    solid_may_cool(const double time, const bool solid_uses_cooling_step);

    /// The solid's switch to its cooling step when solid_may_cool() says
    /// so at @p time, said in a line. Collective.
    void
    cool_solid_when_due(SolidSubCycle<dim> &solid, const double time);

    /// The limits of the flow's sub-cycle over a temperature step: 'Run
    /// limits/Maximum flow sub-steps', the run's wall clock of @p control,
    /// the report of a long sub-cycle to the output stream.
    typename IncompressibleFlow<dim>::SubcycleControl
    flow_subcycle(const SimulationControl &control) const;
    /// The flow's idle test: may the metal melt in this step (the heat's
    /// peak temperature is not below the solidus)? Empty with a frozen
    /// temperature, where the flow never idles.
    std::function<bool()>
    flow_may_melt() const;

    /// Peak temperatures of the metal attached to the substrate and of the
    /// detached metal (MetalBodies::peak_temperatures()), computed once per
    /// temperature step. Collective.
    const MetalPeakTemperatures &
    metal_peak_temperatures();

    /// The temperature that the stop test and the cooling step compare,
    /// K: metal_peak_temperatures().workpiece(). Collective.
    double
    workpiece_peak_temperature();

  private:
    const Scene<dim>              &scene;
    const Laser<dim>              &laser;
    HeatTransfer<dim>             &heat;
    MetalBodies<dim>              &bodies;
    const IncompressibleFlow<dim> *flow;
    ConditionalOStream            &out;
    /// 'Time step after solidification' in use at this step.
    bool cooling_step = false;
    /// metal_peak_temperatures() of the current step.
    std::optional<MetalPeakTemperatures> metal_peaks;

    /// The one stop condition: the laser's path has ended at @p time and
    /// the workpiece's peak temperature is below @p T_limit.
    bool
    after_path_and_below(const double time, const double T_limit);
    /// Refuses (at the first step) a run that would need more than
    /// 'Time stepping/Maximum number of steps' steps of @p dt.
    void
    check_projected_steps(const unsigned int step, const double dt) const;
  };
} // namespace femp

#endif
