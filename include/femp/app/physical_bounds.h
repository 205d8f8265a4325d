// femp: physical plausibility of a scene, checked before any work: every
// number read is finite and of a magnitude that SI quantities of a
// powder-bed scene can have, the material's temperatures are ordered
// (solidus < liquidus < evaporation), the gas is lighter than the metal,
// the beam is not far narrower than a cell, and every explicit scheme's
// step (temperature, melt flow, solid) stays above the floor the run can
// reach within its step bounds. No paper equations; the step limits are
// those of eqs. (1), (3)-(4) and (11)-(17) as the modules compute them.
#ifndef femp_app_physical_bounds_h
#define femp_app_physical_bounds_h

#include <deal.II/base/parameter_handler.h>

#include <femp/flow/incompressible_flow.h>

#include <string>

namespace femp
{
  /// Largest magnitude of a number in a scene (SI units).
  constexpr double largest_magnitude = 1e30;

  /// Every number in the parameters (plain values, lists, tables,
  /// coordinates, the numbers inside expressions; file and folder names
  /// excepted) must be finite with a magnitude of at most
  /// largest_magnitude.
  void
  check_number_magnitudes(const dealii::ParameterHandler &prm);

  /// Relations the physics requires between parameters: solidus <
  /// liquidus < evaporation temperature, gas density below the metal's,
  /// reference temperature below the evaporation temperature, a beam
  /// radius of at least 'min_beam_cells' cells.
  void
  check_physical_relations(const dealii::ParameterHandler &prm);

  /// The beam radius in cells below which the scene is refused.
  constexpr double min_beam_cells = 0.1;

  /// The step of each explicit scheme the scene switches on, from its
  /// parameters: the melt-flow sub-step (viscous, capillary and
  /// gravity-wave limits, or 'Melt flow/Time step') and the solid's
  /// sub-step (elastic limit or 'Solid/Time step'), against the
  /// temperature step (prescribed, or the stable step of a cell full of
  /// metal): more sub-steps per temperature step than 'Run limits' allows
  /// is refused, naming the parameter that sets the step.
  void
  check_step_floors(dealii::ParameterHandler &prm);

} // namespace femp

#endif
