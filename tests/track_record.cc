// The track record (TrackRecord, doc/builds.md "Tracks and layers") on
// prescribed tracks of known geometry (3D, 30 x 24 x 16 cells of h = 10 um):
//   - layer 1 on a plate whose top is z = 8 h: track 1 along +x at
//     y = 9.5 h, track 2 back along -x at y = 15.5 h (hatch 6 h), each
//     from x = 5 h to 25 h; layer 2 (spread at 245 us; its base prescribed
//     flat at z = 12 h): track 3 along +y at x = 15.5 h from y = 4 h to 20 h;
//   - the peak temperature of track k while its laser is on:
//     T_s + A (1 - (w / a)^2 - ((z - z0) / b)^2) (w: the distance from its
//     axis), so the fusion zone (T >= T_s) is an elliptic cylinder of
//     half-width a and half-depth b about z0; track 1's pool is still
//     molten when track 2 starts and solidifies a step later: it must not
//     count in track 2's zone;
//   - the fused surface after track k: a parabolic bead of height H and
//     half-width c on the base, written as the fused fraction of each cell
//     (the share of its height below the surface).
// References (closed form): width 2 a (z0 lies on a cell centre row),
// re-melt depth z_base - (z0 - b), bead height H, overlap of tracks 1 and 2
// 2 a - hatch (ratio (2 a - hatch) / 2 a); none for tracks 1 and 3 (first
// of their layers). Tolerances: the fusion zone's boundary is the crossing
// of the linear interpolant of the cell-centre values, h^2 / (16 a) from
// the true one for a quadratic peak (0.02 h here; 0.05 h allowed); the
// surface is the crossing of the fused fraction 1/2 between cell centres,
// within h / 12 of the true one (h / 8 allowed). Runs on 1 and 2 ranks
// with the same output.
#include <femp/builds/track_record.h>

#include <filesystem>
#include <fstream>

#include "test_tools.h"

using namespace femp_test;

namespace
{
  constexpr int    dim = 3;
  constexpr double h   = 1e-5;
  constexpr double Ts  = 1658; // K, the solidus
  constexpr double A   = 1000; // K

  struct Zone
  {
    bool   along_x;    // axis along x (else along y)
    double axis;       // its y (along x) or x (along y), m
    double a, b, z0;   // fusion zone: half-width, half-depth, centre, m
    double base, H, c; // bead: base height, height, half-width, m
  };
  const Zone zones[3] = {
    {true, 9.5 * h, 4 * h, 3 * h, 7.5 * h, 8 * h, 2.25 * h, 4 * h},
    {true, 15.5 * h, 4 * h, 3 * h, 7.5 * h, 8 * h, 2.25 * h, 4 * h},
    {false, 15.5 * h, 3 * h, 2 * h, 11.5 * h, 12 * h, 1.5 * h, 3 * h}};

  double
  lateral(const Zone &z, const Point<dim> &x)
  {
    return (z.along_x ? x[1] : x[0]) - z.axis;
  }
  double
  peak(const Zone &z, const Point<dim> &x)
  {
    const double w = lateral(z, x) / z.a, v = (x[2] - z.z0) / z.b;
    return Ts + A * (1 - w * w - v * v);
  }
  // The fused surface after zones [0, n) of the layer of zone @p last.
  double
  surface(const int n, const Point<dim> &x)
  {
    const Zone &l    = zones[n - 1];
    double      zmax = l.base;
    for (int k = 0; k < n; ++k)
      if (zones[k].base == l.base)
        {
          const double w = lateral(zones[k], x) / zones[k].c;
          zmax = std::max(zmax, zones[k].base + zones[k].H * (1 - w * w));
        }
    return zmax;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);

  BackgroundGrid<dim> grid(
    box<dim>(Point<dim>(0, 0, 0), Point<dim>(30 * h, 24 * h, 16 * h), h), comm);
  grid.create();

  // The scan path: three tracks, a jump between tracks 1 and 2, a dwell
  // and the jump up to layer 2 (spread at 245 us) before track 3. Each
  // segment: start and end (x, y, z in h), power (W), times (s). Times on
  // half steps (dt = 10 us), so that each record opens and closes in a
  // step beyond round-off.
  const double table[6][9] = {
    {5, 9.5, 10, 25, 9.5, 10, 200, 5e-6, 1.05e-4},
    {25, 9.5, 10, 25, 15.5, 10, 0, 1.05e-4, 1.25e-4},
    {25, 15.5, 10, 5, 15.5, 10, 200, 1.25e-4, 2.25e-4},
    {5, 15.5, 10, 5, 15.5, 10, 0, 2.25e-4, 2.45e-4},
    {5, 15.5, 14, 15.5, 4, 14, 0, 2.45e-4, 2.65e-4},
    {15.5, 4, 14, 15.5, 20, 14, 200, 2.65e-4, 3.45e-4}};
  std::vector<Laser<dim>::Segment> path;
  for (const auto &row : table)
    {
      Laser<dim>::Segment s;
      s.start   = Point<dim>(row[0] * h, row[1] * h, row[2] * h);
      s.end     = Point<dim>(row[3] * h, row[4] * h, row[5] * h);
      s.power   = row[6];
      s.t_begin = row[7];
      s.t_end   = row[8];
      s.speed   = s.start.distance(s.end) / (s.t_end - s.t_begin);
      path.push_back(s);
    }
  const std::vector<double> layer_starts = {2.45e-4};
  const auto tracks = TrackRecord<dim>::find_tracks(path, layer_starts);
  checks.at_most("|tracks found - 3|", std::abs(double(tracks.size()) - 3), 0);
  if (tracks.size() != 3)
    return checks.exit_code();
  for (unsigned int k = 0; k < 3; ++k)
    if (Utilities::MPI::this_mpi_process(comm) == 0)
      std::cout << "track " << k + 1 << ": layer " << tracks[k].layer
                << ", number " << tracks[k].in_layer << " in it, on "
                << tracks[k].t_start << " s to " << tracks[k].t_end
                << " s, record closes at " << tracks[k].t_close << " s"
                << std::endl;
  checks.at_most("|record of track 2 closes - layer 2 starts| (s)",
                 std::abs(tracks[1].t_close - 2.45e-4),
                 0);

  const std::string dir = "track_record_output";
  if (Utilities::MPI::this_mpi_process(comm) == 0)
    std::filesystem::create_directories(dir);
  MPI_Barrier(comm);
  TrackRecord<dim> record(grid, tracks, Ts, dir);

  // The prescribed fields. The temperature of step n, [n dt, (n + 1) dt):
  // the peak of the track whose laser is on; track 1's pool (its peak
  // field) stays molten through the jump (steps 10, 11) and the first
  // step of track 2 (12), solidifies in the next (13: its peak less 1.5 A,
  // below T_s everywhere), then track 2's zone (14-22): the record of
  // track 2 opens with track 1's pool molten and must not count it (its
  // width is 2 a, not that of both zones). The dwell and jump to layer 2
  // (23-25) and the step after track 3 (35): 300 K. The record sees the
  // temperature of the step before when it opens or closes (300 K at
  // n = 0). The fused fraction at time t holds the beads finished by then,
  // layer 2's flat base from 250 us (after track 2's record closed at
  // 240 us).
  auto temperature = [&](const int n, std::vector<double> &T) {
    const double shift = n == 13 ? -1.5 * A : 0.;
    const int    zone = n <= 13 ? 0 : n <= 22 ? 1 : n >= 26 && n <= 34 ? 2 : -1;
    for (const auto i : grid.owned_cells())
      T[i] = zone < 0 ? 300. : peak(zones[zone], grid.cell_center(i)) + shift;
  };
  auto fused = [&](const double t, std::vector<double> &f) {
    for (const auto i : grid.owned_cells())
      {
        const Point<dim> x  = grid.cell_center(i);
        const double     zs = t < 1.05e-4 ? 8 * h :
                              t < 2.25e-4 ? surface(1, x) :
                              t < 2.5e-4  ? surface(2, x) :
                              t < 3.45e-4 ? 12 * h :
                                            surface(3, x);
        f[i] = std::min(1., std::max(0., (zs - (x[2] - 0.5 * h)) / h));
      }
  };
  std::vector<double> T = grid.make_field(300.), f = grid.make_field(0.);
  const double        dt = 1e-5;
  std::vector<TrackRecord<dim>::Row> rows;
  for (int n = 0; n < 36; ++n)
    {
      const double t = n * dt;
      fused(t, f);
      if (record.due(t + dt))
        for (const auto &r : record.update(t, t + dt, f, T))
          rows.push_back(r);
      temperature(n, T);
      fused(t + dt, f);
      record.observe(T, f);
    }
  fused(36 * dt, f);
  for (const auto &r : record.finish(36 * dt, f, T))
    rows.push_back(r);
  checks.at_most("|rows - 3|", std::abs(double(rows.size()) - 3), 0);
  if (rows.size() != 3)
    return checks.exit_code();

  for (unsigned int k = 0; k < 3; ++k)
    {
      const auto       &r = rows[k];
      const Zone       &z = zones[k];
      const std::string n = "track " + std::to_string(k + 1) + ": ";
      checks.print(n + "width / h", r.width / h);
      checks.at_most(n + "|width - 2 a| / h",
                     std::abs(r.width - 2 * z.a) / h,
                     0.05);
      checks.print(n + "re-melt depth / h", r.remelt_depth / h);
      checks.at_most(n + "|re-melt depth - (base - z0 + b)| / h",
                     std::abs(r.remelt_depth - (z.base - z.z0 + z.b)) / h,
                     0.05);
      checks.print(n + "bead height / h", r.bead_height / h);
      checks.at_most(n + "|bead height - H| / h",
                     std::abs(r.bead_height - z.H) / h,
                     0.125);
      checks.print(n + "sections", r.sections);
      if (k == 1)
        {
          const double overlap = 2 * z.a - 6 * h;
          checks.print(n + "overlap / h", r.overlap / h);
          checks.at_most(n + "|overlap - (2 a - hatch)| / h",
                         std::abs(r.overlap - overlap) / h,
                         0.05);
          checks.at_most(n + "|overlap ratio - (2 a - hatch) / 2 a|",
                         std::abs(r.overlap_ratio - overlap / (2 * z.a)),
                         0.01);
        }
      else
        checks.at_most(n +
                         "no previous track in its layer: overlap nan (1 = no)",
                       std::isnan(r.overlap) ? 0 : 1,
                       0);
    }
  // layers.csv: both layers complete.
  if (Utilities::MPI::this_mpi_process(comm) == 0)
    {
      std::ifstream in(dir + "/layers.csv");
      std::string   line;
      int           n = -1;
      while (std::getline(in, line))
        ++n;
      std::cout << "rows of layers.csv = " << n << std::endl;
    }
  return checks.exit_code();
}
