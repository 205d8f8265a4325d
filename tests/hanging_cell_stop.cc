// 'Time stepping/Stop when peak temperature below' (TimeStepPolicy::
// cooled_down(), doc/cases.md "Residual stress after cooling") with a hot
// cell that hangs from the workpiece through a chain of partly filled cells
// (tests/hanging_cell_stop.prm: a heat-only box of 10 x 4 x 10 cells of
// 8 um, the bottom face at 300 K, a laser without power whose path ends at
// 4 us, T_stop = 600 K). The metal is put into the cells: a substrate
// (alpha = 1, the three bottom rows) and a bead on it (4 x 2 x 2 cells),
// all at 1000 K; from the bead's top a chain of three cells with
// alpha = 0.12 leads sideways and ends in a hanging cell (alpha = 0.25)
// with no other metal neighbour, also at 1000 K; a detached drop (one cell,
// alpha = 0.125, 2500 K, 'Detached drops = off': it keeps its temperature)
// sits in the gas. The chain conducts (its cells' conductivity alpha k_m)
// but little, so the hanging cell cools last.
// Stepped with the automatic step of the heat equation:
//  - with the chain, the run must stop (before 1 ms), at a step after which
//    the hanging cell is the hottest attached metal and below 600 K, and
//    after a step at which it was not yet below;
//  - the detached drop is reported apart (2500 K) and does not hold the
//    stop back;
//  - without the chain the run must stop earlier (the hanging cell is what
//    the rule waited for).
// Runs on 1 and 2 ranks with the same output.
#include <femp/app/scene.h>
#include <femp/app/time_step_policy.h>

#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

namespace
{
  constexpr int dim = 3;

  struct StopResult
  {
    bool   stopped  = false;
    double time     = 0;
    double attached = 0, detached = 0;
    /// The hanging cell's temperature at the stop, and the workpiece's
    /// peak at the step before.
    double hanging = 0, before = 0;
    long   n_attached = 0;
  };

  StopResult
  run(const std::string &file, MPI_Comm comm, const bool with_chain)
  {
    dealii::ParameterHandler prm;
    parse_scene(prm, file, {});
    ConditionalOStream  silent(std::cout, false);
    Scene<dim>          scene(prm, silent);
    Laser<dim>          laser(scene.laser);
    BackgroundGrid<dim> grid(scene.grid, comm);
    grid.create();
    HeatTransfer<dim> heat(scene.heat, scene.material, laser, grid);
    heat.initialize();

    // The metal by global cell (i, j, k): fraction and temperature.
    std::map<std::array<int, dim>, std::pair<double, double>> metal;
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 10; ++i)
          metal[{i, j, k}] = {1., 1000.};
    for (int k = 3; k <= 4; ++k)
      for (int j = 1; j <= 2; ++j)
        for (int i = 2; i <= 5; ++i)
          metal[{i, j, k}] = {1., 1000.};
    const std::array<int, dim> hanging_cell = {7, 1, 4};
    if (with_chain)
      {
        // Up from the bead's corner (5, 1, 4), along x, down to the tip.
        for (const auto &c : {std::array<int, dim>{5, 1, 5},
                              std::array<int, dim>{6, 1, 5},
                              std::array<int, dim>{7, 1, 5}})
          metal[c] = {0.12, 1000.};
        metal[hanging_cell] = {0.25, 1000.};
      }
    metal[{2, 2, 8}] = {0.125, 2500.}; // the detached drop

    auto alpha = grid.make_field(0.);
    for (const auto idx : grid.owned_cells())
      {
        const auto g  = grid.global_index(idx);
        const auto it = metal.find({g[0], g[1], g[2]});
        if (it == metal.end())
          continue;
        alpha[idx] = it->second.first;
        heat.set_cell_temperature(idx, it->second.second);
      }
    grid.update_ghosts(alpha);
    heat.update_ghosts();
    MetalBodies<dim> bodies(grid, 0);
    bodies.update(alpha);
    heat.set_metal_fraction(alpha, &bodies);

    TimeStepPolicy<dim> policy(scene, laser, heat, bodies, nullptr, silent);
    StopResult          r;
    const double        dt = scene.time.safety_factor * heat.stable_time_step();
    double              t  = 0;
    double              peak_before = 0;
    while (t < scene.time.end_time)
      {
        peak_before = policy.workpiece_peak_temperature();
        policy.begin_step();
        heat.advance(dt, t);
        t += dt;
        if (policy.cooled_down(t))
          {
            r.stopped = true;
            break;
          }
      }
    const auto &p = policy.metal_peak_temperatures();
    r.time        = t;
    r.attached    = p.attached.value_or(-1);
    r.detached    = p.detached.value_or(-1);
    r.before      = peak_before;
    double T_hang = -1;
    for (const auto idx : grid.owned_cells())
      {
        const auto g = grid.global_index(idx);
        if (g[0] == hanging_cell[0] && g[1] == hanging_cell[1] &&
            g[2] == hanging_cell[2])
          T_hang = heat.temperature()[idx];
        r.n_attached += bodies.workpiece_cells()[idx];
      }
    r.hanging    = Utilities::MPI::max(T_hang, comm);
    r.n_attached = Utilities::MPI::sum(r.n_attached, comm);
    return r;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  try
    {
      const auto with    = run(argv[1], comm, true);
      const auto without = run(argv[1], comm, false);

      checks.print("with the chain: attached cells", with.n_attached, 4);
      checks.in_range("with the chain: stopped (1: yes)", with.stopped, 1, 1);
      checks.print("with the chain: stopped at (us)",
                   std::round(with.time * 1e6),
                   4);
      checks.in_range("with the chain: the attached metal's peak below "
                      "600 K at the stop (1: yes)",
                      with.attached < 600,
                      1,
                      1);
      checks.in_range("with the chain: the attached metal's peak at or "
                      "above 600 K a step before (1: yes)",
                      with.before >= 600,
                      1,
                      1);
      checks.at_most("with the chain: |hanging cell - peak of the attached "
                     "metal| at the stop (K)",
                     std::abs(with.hanging - with.attached),
                     0);
      checks.print("with the chain: peak of the detached metal at the stop "
                   "(K)",
                   with.detached);
      checks.at_most("with the chain: |peak of the detached metal - 2500| "
                     "(K)",
                     std::abs(with.detached - 2500),
                     0);
      checks.print("without the chain: attached cells", without.n_attached, 4);
      checks.in_range("without the chain: stopped (1: yes)",
                      without.stopped,
                      1,
                      1);
      checks.print("without the chain: stopped at (us)",
                   std::round(without.time * 1e6),
                   4);
      checks.at_most("stop without the chain / with the chain",
                     std::round(100 * without.time / with.time) / 100,
                     0.99);
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
