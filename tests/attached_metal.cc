// The metal attached to the substrate (MetalBodies, metal_bodies.h), which the
// stop criterion 'Time stepping/Stop when peak temperature below' uses, on a
// prescribed scene: a substrate (alpha = 1, 400 K) in the bottom rows of a
// 16 x 8 x 14 cell box, and on it a thin winding tongue of metal that rises
// to the top rows, runs along x and comes back down to end one cell above
// the substrate without touching it (its tip, 1500 K, is attached only
// through the whole winding path, which crosses the ranks' boundaries).
// A partly filled cell (alpha = 0.3, 1600 K) sits on the tongue, and from
// the tongue hangs a chain of three partly filled cells (alpha = 0.12)
// that ends in a partly filled cell (alpha = 0.25, 1700 K) with no other
// metal neighbour: attached, through cells that conduct heat. Detached:
// a hot blob of 2 x 2 x 2 metal cells in the gas (2800 K), a single partly
// filled cell (alpha 0.4, 3000 K), a drop of two partly filled cells
// (alpha 0.2, 3100 K), and a metal cell (2500 K) that shares only an edge
// with the tongue. Checks against a serial flood fill over the global
// arrays: the number of attached cells, and the peak temperatures of the
// attached metal (1700 K, the hanging cell) and of the detached metal
// (3100 K, the drop). Then without the chain (1600 K), without the partly
// filled cell (1500 K, the tip), and with the blob joined to the substrate
// by a column of metal (2800 K). Runs on 1 and 2 ranks with the same
// output.
#include <femp/grid/metal_bodies.h>

#include <deque>

#include "test_tools.h"

using namespace femp_test;

namespace
{
  constexpr int dim = 3;
  constexpr int nx = 16, ny = 8, nz = 14;

  struct Scene
  {
    std::vector<double> alpha = std::vector<double>(nx * ny * nz, 0.);
    std::vector<double> T     = std::vector<double>(nx * ny * nz, 300.);
    static int
    at(int i, int j, int k)
    {
      return i + nx * (j + ny * k);
    }
    void
    set(int i, int j, int k, double a, double t)
    {
      alpha[at(i, j, k)] = a;
      T[at(i, j, k)]     = t;
    }
  };

  struct Parts
  {
    bool partial_on_tongue, chain, blob_joined;
  };

  Scene
  make_scene(const Parts &parts)
  {
    Scene s;
    for (int k = 0; k < 4; ++k)
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i)
          s.set(i, j, k, 1., 400.);
    // The tongue: up at i = 2, along x at k = 12, down at i = 13 to k = 6,
    // back along x at k = 5 to its tip at i = 7 (k = 4 below it is gas).
    for (int k = 4; k <= 12; ++k)
      s.set(2, 2, k, 1., 700.);
    for (int i = 2; i <= 13; ++i)
      s.set(i, 2, 12, 1., 900.);
    for (int k = 5; k <= 12; ++k)
      s.set(13, 2, k, 1., 1100.);
    for (int i = 7; i <= 13; ++i)
      s.set(i, 2, 5, 1., 1200.);
    s.set(7, 2, 5, 1., 1500.);
    if (parts.partial_on_tongue)
      s.set(6, 2, 13, 0.3, 1600.);
    if (parts.chain)
      {
        // From the tongue's cell (13, 2, 9) along x, then along y, then
        // down to the hanging cell.
        s.set(14, 2, 9, 0.12, 1650.);
        s.set(14, 3, 9, 0.12, 1650.);
        s.set(14, 4, 9, 0.12, 1650.);
        s.set(14, 4, 8, 0.25, 1700.);
      }
    // Detached: the blob, a partly filled cell, an edge contact.
    for (int k = 8; k <= 9; ++k)
      for (int j = 5; j <= 6; ++j)
        for (int i = 8; i <= 9; ++i)
          s.set(i, j, k, 1., 2800.);
    if (parts.blob_joined)
      for (int k = 4; k <= 7; ++k)
        s.set(8, 5, k, 0.9, 1000.);
    s.set(4, 6, 10, 0.4, 3000.);
    s.set(11, 6, 6, 0.2, 3100.); // the drop of two cells
    s.set(11, 6, 7, 0.2, 3100.);
    s.set(3, 3, 8, 1., 2500.); // shares only an edge with the tongue
    return s;
  }

  struct Reference
  {
    long   attached_cells = 0;
    double attached = 0, detached = 0;
  };

  /// Serial reference: the attached cells (a flood fill over the metal
  /// cells from the bottom row) and the peak temperatures.
  Reference
  reference(const Scene &s)
  {
    std::vector<char> attached(s.alpha.size(), 0);
    std::deque<int>   queue;
    const int         di[6][3] = {
              {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        if (s.alpha[Scene::at(i, j, 0)] > 0)
          {
            attached[Scene::at(i, j, 0)] = 1;
            queue.push_back(Scene::at(i, j, 0));
          }
    while (!queue.empty())
      {
        const int c = queue.front();
        queue.pop_front();
        const int i = c % nx, j = (c / nx) % ny, k = c / (nx * ny);
        for (const auto &d : di)
          {
            const int a = i + d[0], b = j + d[1], e = k + d[2];
            if (a < 0 || a >= nx || b < 0 || b >= ny || e < 0 || e >= nz)
              continue;
            const int n = Scene::at(a, b, e);
            if (!attached[n] && s.alpha[n] > 0)
              {
                attached[n] = 1;
                queue.push_back(n);
              }
          }
      }
    Reference r;
    for (int c = 0; c < int(s.alpha.size()); ++c)
      if (s.alpha[c] > 0)
        {
          double &peak = attached[c] ? r.attached : r.detached;
          peak         = std::max(peak, s.T[c]);
          r.attached_cells += attached[c];
        }
    return r;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);

  const double        h = 1e-5;
  BackgroundGrid<dim> grid(
    box<dim>(Point<dim>(0, 0, 0), Point<dim>(nx * h, ny * h, nz * h), h), comm);
  grid.create();
  const unsigned int n_ranks = Utilities::MPI::n_mpi_processes(comm);

  const std::pair<const char *, Parts> cases[] = {
    {"scene", {true, true, false}},
    {"without the hanging chain", {true, false, false}},
    {"without the partly filled cell", {false, false, false}},
    {"blob joined to the substrate", {false, false, true}}};
  for (const auto &[name, parts] : cases)
    {
      const Scene s     = make_scene(parts);
      auto        alpha = grid.make_field(0.), T = grid.make_field(300.);
      for (const auto idx : grid.owned_cells())
        {
          const auto g = grid.global_index(idx);
          alpha[idx]   = s.alpha[Scene::at(g[0], g[1], g[2])];
          T[idx]       = s.T[Scene::at(g[0], g[1], g[2])];
        }
      unsigned int sweeps   = 0;
      const auto   attached = attached_metal_cells(grid, alpha, &sweeps);
      long         n        = 0;
      for (const auto idx : grid.owned_cells())
        n += attached[idx];
      n                       = Utilities::MPI::sum(n, comm);
      const auto        ref   = reference(s);
      const auto        peaks = metal_peak_temperatures(grid, T, alpha);
      const std::string at    = std::string(name) + ": ";
      checks.print(at + "attached cells", n, 6);
      checks.at_most(at + "|attached cells - serial flood fill|",
                     std::abs(n - ref.attached_cells),
                     0);
      const double T_att = peaks.attached.value_or(-1);
      const double T_det = peaks.detached.value_or(-1);
      checks.print(at + "peak temperature of attached metal (K)", T_att, 6);
      checks.at_most(at + "|attached peak - serial| (K)",
                     std::abs(T_att - ref.attached),
                     0);
      checks.print(at + "peak temperature of detached metal (K)", T_det, 6);
      checks.at_most(at + "|detached peak - serial| (K)",
                     std::abs(T_det - ref.detached),
                     0);
      // One exchange round on one rank; on several, the tongue crosses
      // the partition and needs more (not printed: depends on the ranks).
      if (n_ranks == 1 && sweeps != 1)
        checks.at_most("exchange rounds on one rank", sweeps, 1);
      if (Utilities::MPI::this_mpi_process(comm) == 0)
        std::cerr << name << ": " << sweeps << " exchange rounds on " << n_ranks
                  << " ranks" << std::endl;
    }
  return checks.exit_code();
}
