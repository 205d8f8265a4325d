// Checkpoint and resume of a finite-element zone that a hand-over grew into
// a set of cells that is not a box (doc/checkpoint.md, sections "points",
// "fe zone" and "solid"; fe_zone.h; doc/builds.md "Handing cooled metal to
// finite elements"). No equation of the paper: a resumed run must continue
// bit for bit as the run that did not stop.
//
// A 2D substrate block, 1.6 m x 0.8 m, cells of 0.1 m, 2 x 2 solid points
// per cell; finite elements below y = 0.2 m. Bottom fixed, sides on
// rollers, gravity; elastic-plastic (the yield stress softens with
// temperature). A hot spot at (0.8, 0.3) heats by 100 K in 1 s and cools
// back in the next (prescribed cell temperatures, no heat solver). At
// t = 2 s SolidSubCycle::hand_over_cells() hands the cells of the row
// 0.2-0.3 m but two (x = 0.5-0.7 m: an island of material-point cells, as
// a pore leaves) and those of the row 0.3-0.4 m for x < 1 m (a
// step) to finite elements; then the spot heats again by 50 K/s.
// Run A goes straight through to step N = 60 (t = 3 s). Run B stops at
// step k = 50 and writes the checkpoint sections "points", "fe zone" and
// "solid" through Checkpoint<dim> (files on disk, as femp writes them);
// fresh objects read it the way FempProblem does (the "fe zone" section
// before SolidSubCycle::initialize(), then the points and the solid) and
// go on to step N. Checks:
//   - the zone is not a box: its cells against its bounding box's, the
//     island's cells, the elements and material points (printed);
//   - run B against run A at step N: the material points (by id) positions,
//     velocities and all other properties, the cell fields (stresses, von
//     Mises, plastic strain: the elements' in the zone), the kinetic and
//     internal energies, the numbers of elements and points, the zone's
//     bounding box and mask: every difference exactly 0;
//   - the stresses, plastic strain and velocities are not 0 (printed
//     magnitudes, checked above a floor) so the comparison compares state;
//   - negative check: the same checkpoint loaded into fresh objects whose
//     zone is the scene's box (no "fe zone" section read) is refused, the
//     refusal naming the checkpoint's elements that are none of the box
//     zone's (those of the handed cells).
// Runs on 1 and 2 ranks against one output.
#include <femp/base/state_stream.h>
#include <femp/grid/material_points.h>
#include <femp/io/checkpoint.h>
#include <femp/solid/solid_sub_cycle.h>

#include <algorithm>
#include <map>

#include "solid_tools.h"

using namespace femp_test;

namespace
{
  constexpr int    dim = 2;
  constexpr double h   = 0.1;

  /// The hot spot's rise above 300 K at time @p t: 100 K at t = 1 s, back
  /// to 0 at 2 s, then rising by 50 K/s.
  double
  rise(const double t)
  {
    const double a = t <= 1 ? t : t <= 2 ? 2 - t : 0.5 * (t - 2);
    return 100 * a;
  }

  /// The cells handed over at t = 2 s: the row j = 2 less the island
  /// i = 5, 6, and the row j = 3 for i < 10.
  std::vector<std::array<int, dim>>
  handed_cells()
  {
    std::vector<std::array<int, dim>> cells;
    for (int i = 0; i < 16; ++i)
      if (i != 5 && i != 6)
        cells.push_back({{i, 2}});
    for (int i = 0; i < 10; ++i)
      cells.push_back({{i, 3}});
    return cells;
  }

  struct Scene : HandoverBlock
  {
    explicit Scene(MPI_Comm comm)
        : HandoverBlock(comm, rise)
    {
    }
    /// Steps 1 ... 40, the hand-over, steps 41 ... @p k.
    void
    run_to(const int k)
    {
      solid->initialize(T, "");
      run(0, 40);
      solid->hand_over_cells(handed_cells());
      run(40, k);
    }
  };

  /// What a checkpoint must share with the scene that resumes it.
  Checkpoint<dim>::Scene
  checkpoint_scene(const Scene &s)
  {
    Checkpoint<dim>::Scene cs;
    for (int d = 0; d < dim; ++d)
      {
        cs.n_cells[d]      = s.block.grid.n_cells()[d];
        cs.lower_corner[d] = s.block.grid.origin()[d];
      }
    cs.cell_size          = h;
    cs.solid              = 1;
    cs.fe_zone            = 1;
    cs.fe_upper           = {{1.6, 0.2, 0.}};
    cs.n_point_properties = s.block.points->n_properties();
    return cs;
  }

  /// Every point's id, position and properties (all ranks'), by id.
  std::map<std::uint64_t, std::vector<double>>
  all_points(const MaterialPoints<dim> &points, MPI_Comm comm)
  {
    points.flush_point_temperatures();
    const unsigned int  n = points.n_properties();
    std::vector<double> mine;
    for (const auto &p : points.particle_handler())
      {
        mine.push_back(p.get_id());
        for (int d = 0; d < dim; ++d)
          mine.push_back(p.get_location()[d]);
        const auto props = p.get_properties();
        mine.insert(mine.end(), props.begin(), props.begin() + n);
      }
    std::map<std::uint64_t, std::vector<double>> all;
    for (const auto &part : Utilities::MPI::all_gather(comm, mine))
      for (std::size_t i = 0; i < part.size(); i += 1 + dim + n)
        all[std::uint64_t(part[i])] =
          std::vector<double>(part.begin() + i + 1,
                              part.begin() + i + 1 + dim + n);
    return all;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  const int                        N = 60, k = 50;
  try
    {
      // Run A: straight through (with the calls of runs B and C: an advance
      // with final = true ends exactly at its time, others need not).
      Scene a(comm);
      a.run_to(k);
      a.run(k, N);

      // Run B to step k, its checkpoint written through Checkpoint<dim>.
      typename Checkpoint<dim>::Parameters cp;
      cp.directory = "fe_zone_mask_restart_checkpoint_" +
                     std::to_string(Utilities::MPI::n_mpi_processes(comm));
      {
        Scene b(comm);
        b.run_to(k);
        StateWriter points, zone, solid;
        b.block.points->save_state(points);
        b.solid->save_fe_zone(zone);
        b.solid->save_state(solid);
        Checkpoint<dim> out(cp, ".", checkpoint_scene(b), comm);
        out.write(k,
                  0.05 * k,
                  {{"points", &points}, {"fe zone", &zone}, {"solid", &solid}});
      }

      // Fresh objects resume it as FempProblem does and go on to step N.
      cp.resume_from = cp.directory;
      Scene           c(comm);
      Checkpoint<dim> in(cp, ".", checkpoint_scene(c), comm);
      in.read();
      {
        auto parts = in.section("fe zone");
        c.solid->resume_fe_zone(parts);
      }
      c.solid->initialize(c.T, "");
      {
        auto parts = in.section("points");
        c.block.points->load_state(parts);
      }
      {
        auto parts = in.section("solid");
        c.solid->load_state(parts, "");
      }
      c.run(k, N);

      // The zone: not a box, grown by the hand-over.
      const FeZone<dim> &z        = *a.solid->fe_zone();
      const double       n_box    = z.n_cells()[0] * z.n_cells()[1];
      double             n_island = 0; // outside the zone, zone cells above
      for (int i = 0; i < z.n_cells()[0]; ++i)
        for (int j = 0; j < z.n_cells()[1]; ++j)
          {
            const std::array<int, dim> ijk{
              {z.first_cell()[0] + i, z.first_cell()[1] + j}};
            if (z.contains_cell(ijk))
              continue;
            for (int jj = ijk[1] + 1; jj < z.first_cell()[1] + z.n_cells()[1];
                 ++jj)
              if (z.contains_cell({{ijk[0], jj}}))
                {
                  n_island += 1;
                  break;
                }
          }
      checks.in_range("the zone is a box (1 = yes)", z.is_box(), 0, 0);
      checks.print("cells of the zone's bounding box", n_box);
      checks.print("cells of the zone", z.n_zone_cells());
      checks.in_range("island cells (outside the zone, under zone cells)",
                      n_island,
                      2,
                      2);
      const auto sa = a.solid->sizes(), sc = c.solid->sizes();
      checks.print("finite elements", sa[1]);
      checks.print("material points of the solid", sa[0]);

      // Run B against run A at step N.
      const FeZone<dim> &zc        = *c.solid->fe_zone();
      double             zone_diff = zc.mask() != z.mask();
      for (int d = 0; d < dim; ++d)
        zone_diff += std::abs(zc.first_cell()[d] - z.first_cell()[d]) +
                     std::abs(zc.n_cells()[d] - z.n_cells()[d]);
      checks.at_most(
        "resumed - straight: zone's box and mask (cells differing)",
        zone_diff,
        0);
      checks.at_most("resumed - straight: |elements| + |points|",
                     std::abs(sc[1] - sa[1]) + std::abs(sc[0] - sa[0]),
                     0);
      const auto pa = all_points(*a.block.points, comm);
      const auto pc = all_points(*c.block.points, comm);
      const auto iv = dim + MaterialPoints<dim>::PropertyIndex::velocity;
      double     dx = 0, dv = 0, dprop = 0, v_max = 0;
      double     missing = pa.size() != pc.size();
      for (const auto &[id, va] : pa)
        {
          const auto it = pc.find(id);
          if (it == pc.end())
            {
              missing += 1;
              continue;
            }
          const auto &vc = it->second;
          for (std::size_t i = 0; i < va.size(); ++i)
            {
              const double e = std::abs(vc[i] - va[i]);
              if (i < dim)
                dx = std::max(dx, e);
              else if (i >= iv && i < iv + dim)
                dv = std::max(dv, e), v_max = std::max(v_max, std::abs(va[i]));
              else
                dprop = std::max(dprop, e);
            }
        }
      checks.print("material points compared", pa.size());
      checks.at_most("resumed - straight: points missing", missing, 0);
      checks.at_most("resumed - straight: max |x|, m", dx, 0);
      checks.at_most("resumed - straight: max |v| of the points, m/s", dv, 0);
      checks.at_most("resumed - straight: max |other point properties|",
                     dprop,
                     0);

      std::vector<std::vector<double>> fa, fc;
      a.solid->cell_fields(fa);
      c.solid->cell_fields(fc);
      double ds = 0, s_fe = 0, p_fe = 0;
      for (const auto cell : a.block.grid.owned_cells())
        {
          for (std::size_t f = 0; f < fa.size(); ++f)
            ds = std::max(ds, std::abs(fc[f][cell] - fa[f][cell]));
          if (z.contains_cell(a.block.grid.global_index(cell)))
            {
              s_fe = std::max(s_fe, std::abs(fa[0][cell]));
              p_fe = std::max(p_fe, fa[4][cell]);
            }
        }
      ds   = Utilities::MPI::max(ds, comm);
      s_fe = Utilities::MPI::max(s_fe, comm);
      p_fe = Utilities::MPI::max(p_fe, comm);
      checks.at_most("resumed - straight: max |cell fields| (stresses, "
                     "plastic strain), Pa or -",
                     ds,
                     0);
      const auto ea = a.solid->energies(), ec = c.solid->energies();
      checks.at_most("resumed - straight: |kinetic| + |internal energy|, J/m",
                     std::abs(ec.kinetic - ea.kinetic) +
                       std::abs(ec.internal - ea.internal),
                     0);
      checks.in_range("elements: max |sigma_xx| / 1e-3 Pa",
                      s_fe / 1e-3,
                      1,
                      1e3);
      checks.in_range("elements: max plastic strain / 1e-3",
                      p_fe / 1e-3,
                      1,
                      1e3);
      checks.in_range("points: max |v| / 1e-6 m/s",
                      Utilities::MPI::max(v_max, comm) / 1e-6,
                      1,
                      1e6);
      checks.in_range("kinetic energy / 1e-12 J/m", ea.kinetic / 1e-12, 1, 1e9);

      // Negative check: the checkpoint into objects with the scene's box.
      Scene d(comm);
      d.solid->initialize(d.T, "");
      bool        refused = false;
      std::string why;
      try
        {
          auto points = in.section("points");
          d.block.points->load_state(points);
          auto solid = in.section("solid");
          d.solid->load_state(solid, "");
        }
      catch (const std::exception &e)
        {
          why     = e.what();
          refused = why.find("checkpoint") != std::string::npos;
        }
      checks.in_range("negative check: loaded into the scene's box zone, "
                      "refused (1 = yes)",
                      Utilities::MPI::min(refused ? 1 : 0, comm),
                      1,
                      1);
      // The box zone's elements are all in the checkpoint; the
      // checkpoint's elements of the handed cells are none of the box's.
      const double      n_box_zone = d.solid->sizes()[1];
      const std::string unused =
        std::to_string(std::lround(sa[1] - n_box_zone)) + " of the " +
        std::to_string(std::lround(sa[1])) + " FE elements it holds";
      checks.in_range("negative check: the refusal names the checkpoint's " +
                        std::to_string(std::lround(sa[1] - n_box_zone)) +
                        " elements outside the box zone (1 = yes)",
                      Utilities::MPI::min(
                        why.find(unused) != std::string::npos ? 1 : 0, comm),
                      1,
                      1);
    }
  catch (const std::exception &e)
    {
      std::cerr << "error: " << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
