// A thermal scene on a bare plate carries no material points ('Material
// points/Carry points = auto', doc/parameters.md): its metal fraction comes
// from the substrate's lattice instead of the points. Two checks:
//  1. alpha from the lattice against alpha from the points (sub-cell
//     occupation, MaterialPoints::metal_fraction()) on grids whose
//     substrate top cuts cells and sub-cells, with lattice spacings that do
//     and do not divide the cell, 2D and 3D, n = 1..4: the number of cells
//     that differ (exact comparison) must be 0;
//  2. the scene argv[1] run with 'Carry points' = always and = auto: the
//     summary numbers must be equal, and every file written by the auto
//     run (grid fields, incl. alpha and the zone tags, melt_pool.csv, the
//     probe lines, the indices) identical to the always run's (bar the
//     date line of the VTU files); the auto run carries no points and
//     writes no point files.
// Run on 1 and 2 ranks against the same expected output.
#include <deal.II/base/mpi.h>

#include <femp/grid/material_points.h>

#include <filesystem>
#include <set>

#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;
namespace fs = std::filesystem;

namespace
{
  struct LatticeCase
  {
    double       lower, upper, h, spacing, top;
    unsigned int n;
  };

  /// Cells (global) whose alpha from the points and from the lattice
  /// differ, and the number of cells cut by the substrate top (0 < alpha
  /// < 1).
  template <int dim>
  std::pair<double, double>
  compare_alpha(const LatticeCase &c, MPI_Comm comm)
  {
    Point<dim> lo, hi;
    for (int d = 0; d < dim; ++d)
      lo[d] = c.lower, hi[d] = c.upper;
    hi[0] = c.lower + 5 * c.h; // narrow horizontally, tall vertically
    BackgroundGrid<dim> grid(box<dim>(lo, hi, c.h), comm);
    grid.create();
    const Material                           mat = unit_material();
    typename MaterialPoints<dim>::Parameters p;
    p.point_spacing   = c.spacing;
    p.subcells        = c.n;
    p.substrate_top   = c.top;
    p.layer_thickness = 0;
    std::vector<double> alpha[2];
    for (const bool carried : {true, false})
      {
        p.carry_points = carried;
        MaterialPoints<dim> points(p, mat, grid);
        points.create(300);
        alpha[carried] = points.metal_fraction();
      }
    double differ = 0, cut = 0;
    for (const auto idx : grid.owned_cells())
      {
        differ += alpha[0][idx] != alpha[1][idx];
        cut += alpha[1][idx] > 0 && alpha[1][idx] < 1;
      }
    return {Utilities::MPI::sum(differ, comm), Utilities::MPI::sum(cut, comm)};
  }

  std::string
  file_text(const fs::path &name)
  {
    std::ifstream in(name, std::ios::binary);
    std::string   all, line;
    while (std::getline(in, line))
      if (line.rfind("#This file was generated", 0) != 0)
        all += line + "\n";
    return all;
  }

  /// Files of @p dir, by name.
  std::set<std::string>
  files_in(const std::string &dir)
  {
    std::set<std::string> names;
    for (const auto &e : fs::recursive_directory_iterator(dir))
      if (e.is_regular_file())
        names.insert(fs::relative(e.path(), dir).string());
    return names;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  const bool root = Utilities::MPI::this_mpi_process(comm) == 0;
  Checks     checks(comm);

  // 1. Lattice alpha against point alpha.
  const std::vector<LatticeCase> cases = {
    {0, 12, 1, 0.5, 6.6, 2},   // top in the upper sub-cell: alpha 1/2
    {0, 12, 1, 0.375, 5.8, 2}, // spacing not a divisor of h/n
    {-3, 9, 1, 0.3, 4.45, 3},  // n = 3, shifted origin
    {0, 12, 1, 0.25, 7.55, 4}, // n = 4, 3D: 64 sub-cells
    {0, 12, 1, 1, 5.6, 1},     // n = 1, one point per cell: none cut
    {-96e-6, 200e-6, 8e-6, 3e-6, 52.5e-6, 2}, // the scene's h, spacing, top
  };
  for (std::size_t k = 0; k < cases.size(); ++k)
    {
      const auto r2 = compare_alpha<2>(cases[k], comm);
      const auto r3 = compare_alpha<3>(cases[k], comm);
      if (root)
        std::cout << "lattice case " << k << ": cut cells 2D "
                  << long(r2.second) << ", 3D " << long(r3.second) << std::endl;
      checks.at_most("  cells whose alpha differs, 2D", r2.first, 0);
      checks.at_most("  cells whose alpha differs, 3D", r3.first, 0);
    }

  // 2. The scene with and without points.
  const std::string       scene = argv[1];
  FempProblem<3>::Summary s[2];
  for (const bool always : {true, false})
    {
      const std::string dir = always ? "always" : "auto";
      if (root)
        fs::remove_all(dir);
      MPI_Barrier(comm);
      s[always] = run_scene<3>(
        scene,
        comm,
        {{"Output", "Directory", dir},
         {"Material points", "Carry points", always ? "always" : "auto"}});
    }
  checks.print("material points with 'always'", s[1].n_points, 10);
  checks.print("material points with 'auto'", s[0].n_points, 10);
  checks.print("steps", s[1].steps, 8);
  checks.print("peak temperature (K)", s[1].T_max, 8);
  checks.print("melt pool length (m)", s[1].pool.length, 6);
  checks.print("melt pool depth (m)", s[1].pool.depth, 6);
  const double dT  = std::abs(s[1].T_max - s[0].T_max);
  const double dH  = std::abs(s[1].stored - s[0].stored);
  const double dL  = std::abs(s[1].losses - s[0].losses);
  const double dE  = std::abs(s[1].laser - s[0].laser);
  const double dpl = std::abs(s[1].pool.length - s[0].pool.length) +
                     std::abs(s[1].pool.width - s[0].pool.width) +
                     std::abs(s[1].pool.depth - s[0].pool.depth);
  checks.at_most("|peak temperature always - auto| (K)", dT, 0);
  checks.at_most("|stored enthalpy change always - auto| (J)", dH, 0);
  checks.at_most("|surface losses always - auto| (J)", dL, 0);
  checks.at_most("|laser energy always - auto| (J)", dE, 0);
  checks.at_most("|melt pool size always - auto| (m)", dpl, 0);

  // The files (rank 0 compares, all ranks fail).
  double differ = 0, missing = 0, point_files = 0, compared = 0,
         points_always = 0;
  if (root)
    {
      const auto a = files_in("always"), b = files_in("auto");
      for (const auto &f : a)
        {
          const bool is_points = f.rfind("points", 0) == 0;
          points_always += is_points;
          // timing.txt: the wall times of the run, not a result.
          if (is_points || f == "timing.txt")
            continue;
          if (!b.count(f))
            {
              ++missing;
              std::cout << "  missing with 'auto': " << f << std::endl;
              continue;
            }
          ++compared;
          if (file_text("always/" + f) != file_text("auto/" + f))
            {
              ++differ;
              std::cout << "  differs: " << f << std::endl;
            }
        }
      for (const auto &f : b)
        point_files += f.rfind("points", 0) == 0 || !a.count(f);
    }
  differ        = Utilities::MPI::broadcast(comm, differ, 0);
  missing       = Utilities::MPI::broadcast(comm, missing, 0);
  point_files   = Utilities::MPI::broadcast(comm, point_files, 0);
  compared      = Utilities::MPI::broadcast(comm, compared, 0);
  points_always = Utilities::MPI::broadcast(comm, points_always, 0);
  checks.in_range("point files written with 'always'", points_always > 0, 1, 1);
  checks.in_range("melt_pool.csv, grid and probe files compared",
                  compared >= 3,
                  1,
                  1);
  checks.at_most("files that differ", differ, 0);
  checks.at_most("files missing with 'auto'", missing, 0);
  checks.at_most("point (or extra) files written with 'auto'", point_files, 0);
  return checks.exit_code();
}
