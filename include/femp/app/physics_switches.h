// femp: PhysicsSwitches, the subsection 'Physics' of a scene: which of the
// paper's equations are solved (the temperature, eq. 1; the melt flow,
// eqs. 3-4; the solid stress, eqs. 5-17) and the one gravity of the flow
// and the solid. Read by the Scene and by the checks made before any work
// (physical_bounds, run_checks) from the same list.
#ifndef femp_physics_switches_h
#define femp_physics_switches_h

#include <deal.II/base/parameter_handler.h>

#include <femp/base/parameter_table.h>

namespace femp
{
  struct PhysicsSwitches
  {
    /// Physics/Heat transfer: solve eq. (1); false: T frozen.
    bool heat_transfer = true;
    /// Physics/Melt flow: solve eqs. (3-4).
    bool melt_flow = false;
    /// Physics/Solid stress: solve eqs. (5-17).
    bool solid_stress = false;
    /// Physics/Gravity: the magnitude g, m/s^2 (checked by the Scene).
    double gravity = 9.81;

    /// Declare (the members' values are the defaults) or read the
    /// entries, each listed once.
    void
    add_parameters(ParameterTable &table);
    static void
    declare_parameters(dealii::ParameterHandler &prm);
    void
    parse_parameters(dealii::ParameterHandler &prm);
    /// Read from a handler that is not changed (the checks before any
    /// work).
    static PhysicsSwitches
    of(const dealii::ParameterHandler &prm);
  };
} // namespace femp

#endif
