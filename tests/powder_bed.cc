// Powder bed generation: the same seed gives the same bed, grains do not
// overlap, each grain rests on the substrate or on another grain, all lie in
// the layer, and the packing fraction reached is printed. Also checks the
// material-point fill of a bed on the grid: point count against the grain
// and substrate volumes, and the metal fraction alpha of full cells.
#include <femp/grid/material_points.h>
#include <femp/grid/powder_bed.h>

#include "test_tools.h"

using namespace femp_test;

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);

  PowderBedSpec spec;
  spec.dim              = 3;
  spec.lower            = {{0, 0, 1e-4}};
  spec.upper            = {{4e-4, 2e-4, 1.5e-4}};
  spec.mean_diameter    = 30e-6;
  spec.std_diameter     = 6e-6;
  spec.min_diameter     = 15e-6;
  spec.max_diameter     = 45e-6;
  spec.packing_fraction = 0.5;
  spec.seed             = 42;
  const PowderBed a = pack_powder_bed(spec), b = pack_powder_bed(spec);
  bool            same = a.grains.size() == b.grains.size();
  for (std::size_t i = 0; same && i < a.grains.size(); ++i)
    same = a.grains[i].center == b.grains[i].center &&
           a.grains[i].radius == b.grains[i].radius;
  checks.at_most("same seed, different bed", same ? 0 : 1, 0);

  double max_overlap = 0, max_gap = 0, outside = 0;
  for (std::size_t i = 0; i < a.grains.size(); ++i)
    {
      const auto &g = a.grains[i];
      // Gap to the closest support (substrate or a grain touching below).
      double gap = g.center[2] - g.radius - spec.lower[2];
      for (std::size_t j = 0; j < a.grains.size(); ++j)
        if (j != i)
          {
            const auto  &o = a.grains[j];
            const double d = std::sqrt(std::pow(g.center[0] - o.center[0], 2) +
                                       std::pow(g.center[1] - o.center[1], 2) +
                                       std::pow(g.center[2] - o.center[2], 2));
            max_overlap =
              std::max(max_overlap, (g.radius + o.radius - d) / g.radius);
            if (o.center[2] < g.center[2])
              gap = std::min(gap, d - g.radius - o.radius);
          }
      max_gap = std::max(max_gap, gap / g.radius);
      outside += (g.center[2] + g.radius > spec.upper[2] * (1 + 1e-12)) ||
                 (g.center[2] - g.radius < spec.lower[2] * (1 - 1e-12));
    }
  checks.at_most("largest overlap / radius", max_overlap, 1e-9);
  checks.at_most("largest gap to a support / radius", max_gap, 1e-9);
  checks.at_most("grains sticking out of the layer", outside, 0);
  checks.print("grains", a.grains.size());
  checks.in_range("packing fraction reached",
                  a.achieved_packing_fraction,
                  0.3,
                  0.5);

  // Points on a grid: substrate of 10 x 10 x 6 cells, h = 8 um, s = 4 um.
  const int           dim = 3;
  BackgroundGrid<dim> grid(
    box<dim>(Point<dim>(0, 0, 0), Point<dim>(80e-6, 80e-6, 48e-6), 8e-6), comm);
  grid.create();
  MaterialPoints<dim>::Parameters mp;
  mp.point_spacing   = 4e-6;
  mp.substrate_top   = 24e-6;
  mp.layer_thickness = 0;
  const Material      mat;
  MaterialPoints<dim> points(mp, mat, grid);
  points.create(300);
  checks.print("substrate points", points.n_global_points());
  checks.at_most("|points - 20 x 20 x 6|",
                 std::abs(double(points.n_global_points()) - 2400.),
                 0);
  const auto alpha = points.metal_fraction();
  double     metal = 0;
  for (const auto idx : grid.owned_cells())
    metal += alpha[idx];
  checks.at_most("|sum alpha - 10 x 10 x 3 cells|",
                 std::abs(Utilities::MPI::sum(metal, comm) - 300.),
                 1e-12);
  return checks.exit_code();
}
