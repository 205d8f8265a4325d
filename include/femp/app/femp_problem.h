// femp: the top-level problem. It owns the modules and runs the macro time
// step of the paper's sec. 2.6 (METHOD sec. 5):
//   1. tag cells from the points, update alpha, gamma and properties;
//   2. temperature in fluid, solid and powder (HeatTransfer, eq. 1);
//   3. flow in the melt pool (IncompressibleFlow, eqs. 3-4), sub-cycled;
//      with the solid, the fluid forces on the solid (pressure and viscous
//      force on the faces to solid cells, eq. 13);
//   4. solid by MPM + FE with transition-node coupling (SolidStress,
//      eqs. 5-17), sub-cycled to the macro time, loaded by those fluid
//      forces held constant over its sub-steps;
//   5. output, next step.
#ifndef femp_femp_problem_h
#define femp_femp_problem_h

#include <deal.II/base/conditional_ostream.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/timer.h>

#include <femp/grid/background_grid.h>
#include <femp/heat/heat_transfer.h>
#include <femp/flow/incompressible_flow.h>
#include <femp/heat/laser.h>
#include <femp/heat/thermal_history.h>
#include <femp/base/material.h>
#include <femp/grid/material_points.h>
#include <femp/io/output.h>
#include <femp/solid/solid_stress.h>

#include <array>
#include <limits>
#include <memory>

namespace femp
{
  using namespace dealii;

  /// Declare every parameter of femp (all modules) in @p prm.
  void
  declare_all_parameters(ParameterHandler &prm);

  template <int dim>
  class FempProblem
  {
  public:
    struct TimeParameters
    {
      double       end_time      = 1e-3;
      double       time_step     = 0;
      double       safety_factor = 0.5;
      unsigned int max_steps     = 100000000;

      static void
      declare_parameters(ParameterHandler &prm);
      void
      parse_parameters(ParameterHandler &prm);
    };

    /// Read and check all parameters; throws InputError before any work.
    FempProblem(ParameterHandler &prm, MPI_Comm comm);

    void
    run();

    /// Summary numbers of the finished run (for tests and benchmarks).
    struct Summary
    {
      unsigned int steps = 0;
      double       time  = 0;
      double       T_max = 0;
      MeltPoolSize pool;
      /// Energies over the run, J (2D: J/m): laser input, surface losses,
      /// heat in through fixed faces, change of stored enthalpy.
      double laser = 0, losses = 0, boundary = 0, stored = 0;
      /// With melt flow: energy created by the upwind convection of T (not
      /// conservative) and by points moving between cells (change of the
      /// stored enthalpy when alpha and the new metal cells are updated),
      /// J (2D: J/m); both are zero for a conservative scheme.
      double advection = 0, moved_points = 0;
      types::particle_index n_points = 0;
      double                point_T_mean = 0; ///< mean point temperature, K
      // Melt flow (zero when Physics/Melt flow is false).
      unsigned int flow_steps             = 0;
      unsigned int pressure_matrix_builds = 0; ///< matrix + AMG setups
      unsigned long pressure_cg_iterations = 0; ///< total
      double       max_fluid_speed        = 0; ///< m/s, at the end
      /// Fluid step limits, s: the smallest of each over the run, how many
      /// sub-steps each governed (convective, viscous, capillary,
      /// prescribed), and the sub-steps per temperature step.
      struct FlowLimits
      {
        double convective = std::numeric_limits<double>::infinity();
        double viscous    = std::numeric_limits<double>::infinity();
        double capillary  = std::numeric_limits<double>::infinity();
        double capillary_fraction = 1;
        std::array<unsigned long, 4> governed{};
        unsigned int min_substeps = std::numeric_limits<unsigned int>::max();
        unsigned int max_substeps = 0;
      } flow_limits;
      /// Solid (if Physics/Solid stress): steps and final energies.
      unsigned int solid_steps = 0;
      typename SolidStress<dim>::Energies solid_energy;
    };
    const Summary &
    summary() const
    {
      return result;
    }
    /// The material points after run() (tests read their stresses).
    const MaterialPoints<dim> &
    material_points() const
    {
      return *points;
    }

  private:
    MPI_Comm           comm;
    ConditionalOStream pcout;
    TimeParameters     time_prm;
    Material           material;
    typename BackgroundGrid<dim>::Parameters  grid_prm;
    typename MaterialPoints<dim>::Parameters  points_prm;
    typename HeatTransfer<dim>::Parameters    heat_prm;
    typename Laser<dim>::Parameters           laser_prm;
    typename Output<dim>::Parameters          output_prm;
    typename ThermalHistory<dim>::Parameters  history_prm;
    double                                    melt_temperature;
    bool                                      melt_flow = false;
    /// Physics/Heat transfer: false freezes the temperature field.
    bool                                      heat_enabled = true;
    typename IncompressibleFlow<dim>::Parameters flow_prm;
    bool                                      solid_enabled = false;
    SolidMaterial                             solid_material;
    typename SolidStress<dim>::Parameters     solid_prm;
    typename SolidFEM<dim>::Parameters        fem_prm;

    std::unique_ptr<BackgroundGrid<dim>> grid;
    std::unique_ptr<Laser<dim>>          laser;
    std::unique_ptr<MaterialPoints<dim>> points;
    std::unique_ptr<HeatTransfer<dim>>   heat;
    std::unique_ptr<IncompressibleFlow<dim>> flow;
    /// Step 3 of the macro step: the flow sub-cycled over @p dt, then alpha
    /// and the temperature of cells that gained points (METHOD sec. 2, 5).
    void
    flow_substeps(const double dt);
    std::unique_ptr<Output<dim>>         output;
    std::unique_ptr<SolidStress<dim>>    solid;
    std::unique_ptr<ThermalHistory<dim>> history; ///< null unless enabled
    /// Fluid forces on the solid's grid nodes (flow and solid together),
    /// and on the faces of the solid cells (per face and component).
    std::array<std::vector<double>, dim>           fluid_force;
    std::array<std::vector<double>, 2 * dim * dim> fluid_face_force;
    /// Step 3 with the solid: the fluid forces on the faces of the solid
    /// cells (IncompressibleFlow::fluid_forces_on_solid) to the faces' grid
    /// nodes, weighted by the solid mass they hold, into fluid_force
    /// (partial sums of this rank, summed by the solid).
    void
    fluid_forces_to_solid_nodes();
    TimerOutput                          timer;
    Summary                              result;

    void
    setup();
    double
    choose_time_step(const unsigned int step, const double time);
    void
    write_output(const unsigned int n, const double time, const bool last);
    std::vector<typename Output<dim>::Field>
    output_fields() const;
  };
} // namespace femp

#endif
