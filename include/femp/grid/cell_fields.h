// femp: CellFields<dim>, the cell fields that one module writes and others
// read, handed to a reader at the call that needs them (no module keeps a
// pointer into another). Each field has one writer:
//
//   field              writer                          readers
//   temperature T      HeatTransfer: advance() (eq. 1) IncompressibleFlow
//                      and, for the cells whose        (Marangoni stress,
//                      points changed, the heat they   recoil pressure),
//                      bring (PointHeatExchange calls  points (eq. 2),
//                      its set_cell_temperature(),     solid, output
//                      take_point_enthalpy())
//   liquid fraction    HeatTransfer (from T, the       IncompressibleFlow
//     gamma            enthalpy relation)              (Darcy damping)
//   metal fraction     PointHeatExchange, whenever     HeatTransfer, output,
//     alpha            points changed cells (stored    probes, builds
//                      by HeatTransfer for its
//                      readers)
//   cell velocity u    IncompressibleFlow (mean of     HeatTransfer (upwind
//                      the nodes of fluid cells)       convection of T)
//
// What alpha's bodies of metal are (MetalBodies: the detached drops, the
// workpiece attached to the substrate) is found by the same writer from the
// same alpha, once per change, and read by HeatTransfer (drop losses),
// SolidSubCycle (points in drops set aside) and TimeStepPolicy (stop test);
// so is alpha's free surface (MetalSurface: the surface cells with
// |grad alpha|, the first-surface cells of the laser, the cells of detached
// drops), read by HeatTransfer (laser, surface losses).
//
// All fields cover the local box of the background grid with ghost values
// current. A missing field is nullptr (each reader says what it does then).
// FempProblem::cell_fields() builds the view of the present state.
#ifndef femp_cell_fields_h
#define femp_cell_fields_h

#include <array>
#include <vector>

namespace femp
{
  template <int dim>
  struct CellFields
  {
    /// Cell temperature, K (writer: HeatTransfer, with the heat of moved
    /// points from PointHeatExchange).
    const std::vector<double> *temperature = nullptr;
    /// Liquid fraction gamma in [0, 1] (writer: HeatTransfer).
    const std::vector<double> *liquid_fraction = nullptr;
    /// Metal fraction alpha in [0, 1] (writer: PointHeatExchange, from the
    /// points; kept by HeatTransfer).
    const std::vector<double> *metal_fraction = nullptr;
    /// Cell-centred fluid velocity, one array per direction, m/s (writer:
    /// IncompressibleFlow).
    const std::array<std::vector<double>, dim> *velocity = nullptr;
  };
} // namespace femp

#endif
