// femp benchmark: cost of the temperature step and of the per-step point
// bookkeeping on the grid of the paper's case 3.2 (FEMP: 625k grid cells of
// 4 um; here 800 x 240 x 208 um = 200 x 60 x 52 = 624,000 cells, metal up
// to 120 um and gas above) with 316L tables, latent heat, all surface
// losses and a moving laser, and of creating ~2 million material points
// (substrate to 80 um at 2 um spacing plus a 40 um powder layer).
// Run on one core, Release:
//   build/contrib/bench_thermal [repetitions]
// Prints medians over the repetitions of the process CPU time per step.
#include <deal.II/base/mpi.h>
#include <deal.II/base/timer.h>

#include <femp/base/material.h>
#include <femp/grid/background_grid.h>
#include <femp/grid/material_points.h>
#include <femp/heat/heat_transfer.h>
#include <femp/heat/laser.h>

#include <algorithm>
#include <ctime>
#include <iomanip>
#include <iostream>

using namespace dealii;
using namespace femp;

// CPU time of this process (single-threaded): robust against other
// processes sharing the cores, unlike wall time.
double
cpu_seconds()
{
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

double
median(std::vector<double> v)
{
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  const int                        reps = argc > 1 ? std::atoi(argv[1]) : 5;
  const int                        dim  = 3;
  MPI_Comm                         comm = MPI_COMM_WORLD;
  ParameterHandler                 prm;
  Material::declare_parameters(prm);
  Material mat;
  mat.parse_parameters(prm); // 316L defaults (Kim 1975)

  BackgroundGrid<dim>::Parameters gp;
  gp.lower_corner = Point<dim>(0, 0, 0);
  gp.upper_corner = Point<dim>(800e-6, 240e-6, 208e-6);
  gp.cell_size    = 4e-6;
  Timer               timer;
  BackgroundGrid<dim> grid(gp, comm);
  grid.create();
  const double t_grid  = timer.wall_time();
  const double n_cells = grid.n_global_cells();

  // Points: substrate to 80 um at 2 um spacing (8 per cell), a 40 um powder
  // layer on top: about 2 million points.
  MaterialPoints<dim>::Parameters mp;
  mp.point_spacing   = 2e-6;
  mp.substrate_top   = 80e-6;
  mp.layer_thickness = 40e-6;
  mp.mean_diameter   = 26e-6;
  mp.std_diameter    = 6e-6;
  mp.min_diameter    = 15e-6;
  mp.max_diameter    = 40e-6;
  // A thermal scene: points carry only the base block of properties.
  MaterialPoints<dim> points(
    mp, mat, grid, MaterialPoints<dim>::PropertyIndex::n_used(false, false));
  timer.restart();
  points.create(300);
  const double t_points = timer.wall_time();
  const double n_points = points.n_global_points();
  timer.restart();
  const auto   alpha   = points.metal_fraction();
  const double t_alpha = timer.wall_time();

  Laser<dim>::Parameters lp;
  lp.start_point = Point<dim>(100e-6, 120e-6, 0);
  lp.end_point   = Point<dim>(700e-6, 120e-6, 0);
  Laser<dim>                    laser(lp);
  HeatTransfer<dim>::Parameters hp;
  hp.fixed_temperatures = {{"z-", 300.}};
  HeatTransfer<dim> heat(hp, mat, laser, grid);
  heat.initialize();
  heat.set_metal_fraction(alpha);
  // A hot track so that cells are solid, mushy and liquid.
  for (std::size_t i = 0; i < grid.n_local(); ++i)
    {
      const auto   c  = grid.cell_center(i);
      const double r2 = std::pow(c[1] - 120e-6, 2) + std::pow(c[2] - 100e-6, 2);
      heat.set_cell_temperature(i,
                                300 + 2700 *
                                        std::exp(-r2 / (2 * 30e-6 * 30e-6)) *
                                        (c[0] > 100e-6 && c[0] < 500e-6));
    }
  double metal = 0;
  for (const auto idx : grid.owned_cells())
    metal += alpha[idx] > 0;
  metal = Utilities::MPI::sum(metal, comm);

  double       time = 0;
  const double dt   = 0.5 * heat.stable_time_step();
  for (int i = 0; i < 3; ++i, time += dt)
    heat.advance(dt, time);
  const int           steps = 20;
  std::vector<double> t_step, t_c2p;
  for (int r = 0; r < reps; ++r)
    {
      double c0 = cpu_seconds();
      for (int i = 0; i < steps; ++i, time += dt)
        heat.advance(dt, time);
      t_step.push_back((cpu_seconds() - c0) / steps);
      c0 = cpu_seconds();
      for (int i = 0; i < steps; ++i)
        points.cells_to_points(heat.temperature());
      t_c2p.push_back((cpu_seconds() - c0) / steps);
    }
  // Baseline in the same run: a bare constant-coefficient 7-point stencil
  // over the same box (what memory bandwidth alone allows).
  std::vector<double> a(grid.n_local(), 1.), b(grid.n_local(), 0.);
  const auto         &st = grid.strides();
  std::vector<double> t_bare;
  for (int r = 0; r < reps; ++r)
    {
      const double c0 = cpu_seconds();
      for (int i = 0; i < steps; ++i)
        {
          const std::size_t n = a.size() - st[2];
#pragma omp simd
          for (std::size_t j = st[2]; j < n; ++j)
            b[j] =
              a[j] + 0.1 * (a[j - 1] + a[j + 1] + a[j - st[1]] + a[j + st[1]] +
                            a[j - st[2]] + a[j + st[2]] - 6 * a[j]);
          std::swap(a, b);
        }
      t_bare.push_back((cpu_seconds() - c0) / steps);
    }
  if (Utilities::MPI::this_mpi_process(comm) == 0)
    {
      std::cout << std::setprecision(3) << "bare 7-point stencil (median)   "
                << 1e9 * median(t_bare) / n_cells
                << " ns per cell-step (ratio temperature/bare "
                << median(t_step) / median(t_bare) << ")\n";
      std::cout << std::setprecision(3) << "grid cells                      "
                << n_cells << " (" << metal << " with metal)\n"
                << "grid creation                   " << t_grid << " s\n"
                << "material points                 " << n_points << "\n"
                << "point creation                  " << t_points << " s ("
                << 1e9 * t_points / n_points << " ns/point)\n"
                << "metal fraction (alpha)          "
                << 1e9 * t_alpha / n_points << " ns/point\n"
                << "phase-change cells per step     "
                << heat.n_phase_change_cells() << "\n"
                << "temperature step (median)       " << 1e3 * median(t_step)
                << " ms = " << 1e9 * median(t_step) / n_cells
                << " ns per cell-step (" << 1e9 * median(t_step) / metal
                << " per metal cell)\n"
                << "cells to points (median)        " << 1e3 * median(t_c2p)
                << " ms = " << 1e9 * median(t_c2p) / n_points
                << " ns per point-step\n";
    }
  return 0;
}
