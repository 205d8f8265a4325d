// femp: CellFields<dim>, the cell fields that one module writes and others
// read, handed to a reader at the call that needs them (no module keeps a
// pointer into another). Each field has one writer:
//
//   field              writer                          readers
//   temperature T      HeatTransfer (eq. 1)            IncompressibleFlow
//                                                      (Marangoni stress,
//                                                      recoil pressure)
//   liquid fraction    HeatTransfer (from T, the       IncompressibleFlow
//     gamma            enthalpy relation)              (Darcy damping)
//   metal fraction     HeatTransfer::set_metal_fraction (output, probes)
//     alpha            from the points (PointHeatExchange)
//   cell velocity u    IncompressibleFlow (mean of     HeatTransfer (upwind
//                      the nodes of fluid cells)       convection of T)
//
// All fields cover the local box of the background grid with ghost values
// current. A field the caller does not have stays nullptr; each reader
// documents what it does then (e.g. the flow takes gamma = 1).
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
    /// Cell temperature, K (writer: HeatTransfer).
    const std::vector<double> *temperature = nullptr;
    /// Liquid fraction gamma in [0, 1] (writer: HeatTransfer).
    const std::vector<double> *liquid_fraction = nullptr;
    /// Metal fraction alpha in [0, 1] (writer: HeatTransfer, from the
    /// points).
    const std::vector<double> *metal_fraction = nullptr;
    /// Cell-centred fluid velocity, one array per direction, m/s (writer:
    /// IncompressibleFlow).
    const std::array<std::vector<double>, dim> *velocity = nullptr;
  };
} // namespace femp

#endif
