// femp: the subsection 'Physics' (include/femp/app/physics_switches.h).
#include <femp/app/physics_switches.h>

namespace femp
{
  void
  PhysicsSwitches::add_parameters(ParameterTable &table)
  {
    table.enter_subsection("Physics");
    table.add("Heat transfer",
              heat_transfer,
              "Solve the temperature equation (1). false: the "
              "temperature stays frozen at 'Heat transfer/Initial "
              "temperature' (a number or a function of x, y, z) and "
              "nothing of the heat equation is computed; the flow "
              "still takes its Marangoni stress, recoil and Darcy "
              "damping from this field, and points still change "
              "state with it. The step is then 'Time stepping/Time "
              "step', or with melt flow and 0 the fluid step.");
    table.add("Melt flow",
              melt_flow,
              "Solve the melt-pool flow (eqs. 3-4) of the fluid points "
              "(subsection Melt flow): gravity, viscosity, Darcy "
              "damping, surface tension, Marangoni stress and recoil "
              "pressure.");
    table.add("Solid stress",
              solid_stress,
              "Solve the thermal stress by MPM and FE (eqs. 5-17): "
              "subsections 'Solid' and 'Solid FEM'. With 'Melt flow' "
              "too, the flow moves the fluid points and the solid "
              "the solid points, and the fluid pressure and viscous "
              "forces on the faces to solid cells load the solid "
              "(doc/solid.md, 'Flow and solid together').");
    table.add("Gravity",
              gravity,
              Patterns::Double(),
              "Magnitude g of the gravitational acceleration, m/s^2, "
              "acting along -y (2D) or -z (3D) on the melt flow and "
              "on the solid (the one gravity of both); range [0, "
              "inf).");
    table.leave_subsection();
  }

  void
  PhysicsSwitches::declare_parameters(dealii::ParameterHandler &prm)
  {
    PhysicsSwitches defaults;
    ParameterTable  table(prm, ParameterTable::Mode::declare);
    defaults.add_parameters(table);
  }

  void
  PhysicsSwitches::parse_parameters(dealii::ParameterHandler &prm)
  {
    ParameterTable table(prm, ParameterTable::Mode::parse);
    add_parameters(table);
  }

  PhysicsSwitches
  PhysicsSwitches::of(const dealii::ParameterHandler &prm)
  {
    // Reading moves only the handler's position, which it restores.
    PhysicsSwitches p;
    p.parse_parameters(const_cast<dealii::ParameterHandler &>(prm));
    return p;
  }
} // namespace femp
