// The solid's energy check at the start from rest under a body load
// (SolidSubCycle::check_energy_created(), SolidEnergies::half_step;
// doc/stability.md, "Energy check"). The 2D block of the FE-zone hand-over
// tests: 1.6 m x 1.0 m, cells of 0.1 m, solid points (2 x 2 per cell) up
// to y = 0.8 m, finite elements below y = 0.2 m, the unit material, gravity
// 0.01 m/s^2, mass-scaling factor 100 (the solid step 0.028 s: two solid
// steps per temperature step of 0.05 s, one in the first), five
// temperature steps. The central-difference update books the works of a
// step against the kinetic energy at the whole step; taken at the
// half-step velocity, the kinetic energy of a body under a constant load
// after its first step is 1/2 m (g dt)^2, half the load's work m g^2 dt^2,
// and the balance shows a third of the check's scale as created (the
// check stops at a quarter).
//   - free block (no supports, a uniformly accelerated body): the balance
//     with the whole-step kinetic energy (what the check reads) over the
//     check's scale, the largest of the five checks, is round-off; printed
//     beside it the half-step balance of the energy file after the first
//     step, 1/3 of the scale (the leapfrog's half-step term);
//   - the block on its support (fixed bottom, rollers on the sides; the
//     block settles elastically under its weight): the same ratio (signed)
//     stays below 1e-3, far below the threshold 0.25 (a linear elastic
//     body leaves -dt^2/2 v . K v <= 0; +3.8e-4 at the end, after the
//     shortened last solid step), and the run reaches its end.
// With the half-step kinetic energy in the check the first temperature
// step of both runs stops (0.33 > 0.25).
// Runs on 1 and 2 ranks against one output.
#include <femp/solid/solid_sub_cycle.h>

#include "solid_tools.h"

using namespace femp_test;

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  constexpr int                    dim = 2;
  constexpr double                 h   = 0.1;
  const bool root = Utilities::MPI::this_mpi_process(comm) == 0;
  try
    {
      for (const bool supported : {false, true})
        {
          const std::string name = supported ? "supported block" : "free block";
          SolidBlock<dim>   block(
            Point<dim>(1.6, 1.0), h, 0.8, unit_material(), comm);
          SolidMaterial sm =
            block_material("300:0.02, 400:0.005", block.material);
          sm.poisson_ratio = 0.3;
          auto sp          = block_supports<dim>();
          if (!supported)
            sp.fixed_faces.clear(), sp.roller_faces.clear();
          sp.gravity[1]   = -0.01;
          sp.mass_scaling = 100;
          const auto fp   = fe_zone(Point<dim>(0, 0), Point<dim>(1.6, 0.2));
          SolidSubCycle<dim>  solid(sp, fp, sm, block.grid, *block.points);
          std::vector<double> T = block.grid.make_field(300.);
          solid.initialize(T, "");

          std::string error;
          double      largest = -1e300, first_half_step_balance = 0;
          unsigned    first_steps = 0;
          try
            {
              for (int s = 1; s <= 5; ++s)
                {
                  solid.advance(0.05 * s, T, s == 5);
                  const auto c = solid.energy_check_balance();
                  largest =
                    std::max(largest,
                             supported ? c[0] / c[1] : std::abs(c[0]) / c[1]);
                  if (s == 1)
                    {
                      first_steps = solid.n_steps();
                      first_half_step_balance =
                        solid.energies().balance() / c[1];
                    }
                }
            }
          catch (const std::exception &e)
            {
              error = e.what();
              if (root)
                std::cerr << error << std::endl;
            }
          checks.print(name + ": solid steps in the first temperature step",
                       first_steps,
                       6);
          checks.print(name + ": the half-step balance after the first step / "
                              "the check's scale",
                       first_half_step_balance,
                       3);
          if (supported)
            checks.at_most(name + ": largest whole-step balance / the check's "
                                  "scale",
                           largest,
                           1e-3);
          else
            checks.at_most(name +
                             ": largest |whole-step balance| / the check's "
                             "scale",
                           largest,
                           1e-9);
          checks.at_most(name + ": the run stopped (1 = yes)",
                         !error.empty(),
                         0);
        }
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
