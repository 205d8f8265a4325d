// The track record (TrackRecord, doc/builds.md "Tracks and layers") on
// prescribed tracks of known geometry (3D, 30 x 24 x 16 cells of h = 10 um):
//   - layer 1 on a plate whose top is z = 8 h: track 1 along +x at
//     y = 9.5 h, track 2 back along -x at y = 15.5 h (hatch 6 h), each
//     from x = 5 h to 25 h; layer 2 (spread at 245 us; its base prescribed
//     flat at z = 12 h): track 3 along +y at x = 15.5 h from y = 4 h to 20 h;
//   - the peak temperature of track k while its record is open:
//     T_s + A (1 - (w / a)^2 - ((z - z0) / b)^2) (w: the distance from its
//     axis), so the fusion zone (T >= T_s) is an elliptic cylinder of
//     half-width a and half-depth b about z0;
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
  // and the jump up to layer 2 (spread at 245 us) before track 3.
  using Segment = Laser<dim>::Segment;
  auto seg      = [](const Point<dim> &a,
                const Point<dim> &b,
                const double      P,
                const double      t0,
                const double      t1) {
    Segment s;
    s.start   = a;
    s.end     = b;
    s.power   = P;
    s.speed   = a.distance(b) / (t1 - t0);
    s.t_begin = t0;
    s.t_end   = t1;
    return s;
  };
  // Times on half steps (dt = 10 us), so that each record opens and
  // closes in a step beyond round-off.
  const std::vector<Segment> path         = {seg({5 * h, 9.5 * h, 10 * h},
                                         {25 * h, 9.5 * h, 10 * h},
                                         200,
                                         5e-6,
                                         1.05e-4),
                                             seg({25 * h, 9.5 * h, 10 * h},
                                         {25 * h, 15.5 * h, 10 * h},
                                         0,
                                         1.05e-4,
                                         1.25e-4),
                                             seg({25 * h, 15.5 * h, 10 * h},
                                         {5 * h, 15.5 * h, 10 * h},
                                         200,
                                         1.25e-4,
                                         2.25e-4),
                                             seg({5 * h, 15.5 * h, 10 * h},
                                         {5 * h, 15.5 * h, 10 * h},
                                         0,
                                         2.25e-4,
                                         2.45e-4),
                                             seg({5 * h, 15.5 * h, 14 * h},
                                         {15.5 * h, 4 * h, 14 * h},
                                         0,
                                         2.45e-4,
                                         2.65e-4),
                                             seg({15.5 * h, 4 * h, 14 * h},
                                         {15.5 * h, 20 * h, 14 * h},
                                         200,
                                         2.65e-4,
                                         3.45e-4)};
  const std::vector<double>  layer_starts = {2.45e-4};
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

  // The prescribed fields: the temperature of a step [t, t + dt) is the
  // peak of the track whose laser is on, or was on last, at its middle; the
  // fused fraction at time t holds the beads finished by then, layer 2's
  // flat base from 250 us (after track 2's record closed at 240 us).
  auto temperature = [&](const double t, std::vector<double> &T) {
    const double tm   = t + 5e-6;
    const int    zone = tm < 1.25e-4 ? 0 : (tm < 2.45e-4 ? 1 : 2);
    for (const auto i : grid.owned_cells())
      T[i] = peak(zones[zone], grid.cell_center(i));
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
  std::vector<double> T = grid.make_field(0.), f = grid.make_field(0.);
  const double        dt = 1e-5;
  std::vector<TrackRecord<dim>::Row> rows;
  for (int n = 0; n < 36; ++n)
    {
      const double t = n * dt;
      fused(t, f);
      temperature(t, T);
      if (record.due(t + dt))
        for (const auto &r : record.update(t, t + dt, f, T))
          rows.push_back(r);
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
