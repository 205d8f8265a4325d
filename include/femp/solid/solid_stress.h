// femp: the former name of SolidSubCycle<dim> (solid_sub_cycle.h), kept
// while the driver (app/) still uses it; new code uses SolidSubCycle.
#ifndef femp_solid_stress_h
#define femp_solid_stress_h

#include <femp/solid/solid_sub_cycle.h>

namespace femp
{
  template <int dim>
  using SolidStress = SolidSubCycle<dim>;
} // namespace femp

#endif
