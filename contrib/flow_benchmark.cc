// femp contrib: benchmark of the melt-flow step (IncompressibleFlow, paper
// eqs. 3-4), one core, Release. A 3D box pool of n x n x m fluid cells
// (8 points per cell), no gravity; before every step the point velocities
// are set to fresh random values (1e-6 m/s: no point leaves its cell), so
// each pressure solve has a new right-hand side (no useful warm start) while
// the fluid set, and hence the matrix graph and the AMG hierarchy, stays the
// same. Prints the time per step of each part, ns per fluid point-step for
// the transfer, predictor and correction, and ms per pressure solve.
//
// Usage: flow_benchmark [n = 50] [m = 20] [steps = 10]
// (n = 50, m = 20: 50,000 fluid cells, 400,000 points)
#include <random>

#include "../tests/flow_tools.h"

using namespace femp_test;

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm  = MPI_COMM_WORLD;
  constexpr int                    dim   = 3;
  const unsigned int               n     = argc > 1 ? std::stoi(argv[1]) : 50;
  const unsigned int               m     = argc > 2 ? std::stoi(argv[2]) : 20;
  const unsigned int               steps = argc > 3 ? std::stoi(argv[3]) : 10;
  const double                     h     = 1e-3;
  typename IncompressibleFlow<dim>::Parameters prm;
  prm.viscosity = 1e-3;
  prm.gravity   = Tensor<1, dim>();
  FlowScene<dim> scene(
    Point<dim>(n * h, n * h, (m + 2) * h),
    h,
    1000,
    [&](const Point<dim> &x) { return x[2] < m * h; },
    prm,
    comm);
  ConditionalOStream pcout(std::cout,
                           Utilities::MPI::this_mpi_process(comm) == 0);
  TimerOutput timer(pcout, TimerOutput::never, TimerOutput::cpu_and_wall_times);
  scene.flow = std::make_unique<IncompressibleFlow<dim>>(
    prm, scene.material, scene.grid, *scene.points, &timer);
  std::mt19937                           rng(1);
  std::uniform_real_distribution<double> dist(-1e-6, 1e-6);
  const unsigned int vel      = MaterialPoints<dim>::PropertyIndex::velocity;
  const double       dt       = 1e-3;
  const auto         n_points = scene.points->n_global_points();
  for (unsigned int s = 0; s <= steps; ++s)
    {
      if (s == 1)
        timer.reset(); // step 0: matrix and AMG setup, timed separately
      for (auto &p : scene.points->particle_handler())
        for (int d = 0; d < dim; ++d)
          p.get_properties()[vel + d] = dist(rng);
      if (s == 0)
        {
          Timer t;
          scene.flow->step(dt);
          pcout << "first step (includes matrix + AMG setup): "
                << t.wall_time() * 1e3 << " ms" << std::endl;
          continue;
        }
      scene.flow->step(dt);
    }
  // CPU time of the process (the build machine is shared; wall times are
  // printed beside it).
  const auto  times = timer.get_summary_data(TimerOutput::total_cpu_time);
  const auto  walls = timer.get_summary_data(TimerOutput::total_wall_time);
  const auto &st    = scene.flow->statistics();
  pcout << "fluid cells " << st.n_fluid_cells << ", points " << n_points
        << ", timed steps " << steps << ", matrix graph / AMG builds "
        << st.matrix_rebuilds << " / " << st.amg_setups << ", CG iterations "
        << st.cg_iterations << " (incl. step 0)\n";
  const double per = 1e9 / (double(steps) * n_points);
  double       sum = 0;
  for (const auto &[name, t] : times)
    {
      pcout << std::left << std::setw(36) << name << std::right << std::setw(10)
            << std::setprecision(4) << t / steps * 1e3 << " ms/step "
            << std::setw(10) << t * per
            << " ns per fluid point-step (CPU; wall " << walls.at(name) * per
            << ")" << std::endl;
      if (name == "flow: transfer to grid" || name == "flow: predictor" ||
          name == "flow: correction")
        sum += t * per;
    }
  pcout << "transfer + predictor + correction: " << sum
        << " ns per fluid point-step, CPU time (goal <= 60)\n";
  if (times.count("flow: pressure solve"))
    pcout << "pressure solve: "
          << times.at("flow: pressure solve") / steps * 1e3
          << " ms per solve (CPU), hierarchy reused (goal <= 50)\n";
  return 0;
}
