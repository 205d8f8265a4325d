// Thermal contraction of a finite-element zone narrower than the domain
// carries the material points beside its lateral face across the face's
// grid line, where they are held (SolidMPM::hold_on_zone_face(),
// solid_mpm.h; doc/builds.md "Points on the zone's faces"), through
// SolidSubCycle end to end. A 2D plate, 1.6 m x 0.8 m, cells of 0.1 m,
// solid points 2 x 2 per cell (spacing 0.05 m: a point is held on a face
// up to 0.025 m inside the zone) up to y = 0.4 m; the FE zone
// x = 0.6-1.0 m, y = 0-0.4 m (as tall as the plate: no point lies above
// its top). Elastic (E = 100 Pa, nu = 0.3, no yield), alpha = 1e-3 1/K;
// rollers at x = 0 and y = 0, the right end free. The zone's cells cool
// from 300 K to 200 K over 2 s (ten temperature steps), the plate beside
// it stays at 300 K: the zone contracts by up to 0.04 m towards
// x = 0.6 m, and the plate on its right follows its right lateral face,
// so that the points of the plate's first column (0.025 m right of the
// face's grid line) cross it by less than half a spacing. Checks:
//   - with the holds: the run ends normally, the points are held on a
//     lateral face (at least once) and never on the top face (no point
//     lies above it), no point leaves the solid, and the energy balance
//     stays within 0.05 of the stress work (fe_zone_handover's
//     tolerance). The first column held, the plate is compressed by the
//     rest following the zone: the stress work is mostly the holds' own,
//     and the kinetic energy they removed (the points' velocities into
//     the zone, booked by the transfers) is 0.1-1 of it, so the balance
//     tests their booking;
//   - the same run without the holds (SolidSubCycle::
//     set_hold_on_zone_faces(false)) stops with the diagnostic "a material
//     point entered the finite-element zone ... m deep ... near x = ...":
//     the depth it names lies within half a point spacing (0, 0.025] m
//     (the point would have been held) and the position at the right
//     lateral face (x in [0.975, 1.0] m, y in [0, 0.4] m).
// Runs on 1 and 2 ranks against one output.
#include <femp/solid/solid_sub_cycle.h>

#include <sstream>

#include "solid_tools.h"

using namespace femp_test;

namespace
{
  constexpr int    dim     = 2;
  constexpr double h       = 0.1;
  constexpr double spacing = h / 2;

  /// What a run of the scene left: the error message (empty: it ended
  /// normally), the holds, the energies and the solid's points.
  struct Result
  {
    std::string                           error;
    double                                top = 0, lateral = 0, kinetic = 0;
    typename SolidSubCycle<dim>::Energies e;
    double                                n0 = 0, n1 = 0;
  };

  Result
  run(MPI_Comm comm, const bool hold)
  {
    SolidBlock<dim> block(Point<dim>(1.6, 0.8), h, 0.4, unit_material(), comm);
    SolidMaterial   sm = block_material("1e30", block.material);
    sm.poisson_ratio   = 0.3;
    sm.expansion       = 1e-3;
    typename SolidSubCycle<dim>::Parameters sp;
    sp.roller_faces       = {"x-", "y-"};
    sp.energy_file        = "";
    const auto         fp = fe_zone(Point<dim>(0.6, 0), Point<dim>(1.0, 0.4));
    SolidSubCycle<dim> solid(sp, fp, sm, block.grid, *block.points);
    solid.set_hold_on_zone_faces(hold);
    std::vector<double> T = block.grid.make_field(300.);
    solid.initialize(T, "");
    Result r;
    r.n0 = solid.sizes()[0];
    try
      {
        for (int s = 1; s <= 10; ++s)
          {
            for (std::size_t c = 0; c < T.size(); ++c)
              {
                const Point<dim> x = block.grid.cell_center(c);
                T[c] = x[0] > 0.6 && x[0] < 1.0 ? 300. - 10. * s : 300.;
              }
            solid.advance(0.2 * s, T, s == 10);
          }
      }
    catch (const std::exception &e)
      {
        r.error = e.what();
      }
    r.top     = solid.n_points_held_at_zone_top();
    r.lateral = solid.n_points_held_at_zone_lateral();
    r.kinetic = solid.kinetic_held_at_zone();
    r.e       = solid.energies();
    r.n1      = solid.sizes()[0];
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
      const Result with = run(comm, true);
      if (!with.error.empty() && Utilities::MPI::this_mpi_process(comm) == 0)
        std::cerr << with.error << std::endl;
      checks.at_most("with the holds: run stopped (1 = yes)",
                     !with.error.empty(),
                     0);
      checks.print("with the holds: times held on a lateral face",
                   with.lateral,
                   6);
      checks.in_range("with the holds: held on a lateral face (>= 1)",
                      std::min(with.lateral, 1.),
                      1,
                      1);
      checks.at_most("with the holds: times held on the top face (no point "
                     "above it)",
                     with.top,
                     0);
      checks.at_most("with the holds: |solid points at the end - at the "
                     "start|",
                     std::abs(with.n1 - with.n0),
                     0);
      checks.print("with the holds: stress work (J/m)", with.e.internal, 3);
      checks.at_most("with the holds: |energy balance| / |stress work|",
                     std::abs(with.e.balance() / with.e.internal),
                     0.05);
      // The plate beyond the face follows the contracting zone while its
      // first column is held: the stress work is mostly the holds' own, and
      // their kinetic energy a large share of it, which the balance above
      // must book (it would miss by this share otherwise).
      checks.in_range("with the holds: kinetic energy removed by the holds / "
                      "|stress work|",
                      with.kinetic / std::abs(with.e.internal),
                      0.1,
                      1);

      const Result without = run(comm, false);
      if (Utilities::MPI::this_mpi_process(comm) == 0)
        std::cerr << without.error << std::endl;
      const std::string &what = without.error;
      checks.in_range("without the holds: run stopped (1 = yes)",
                      !what.empty(),
                      1,
                      1);
      const auto deep  = what.find(" m deep");
      const auto zone  = what.find("entered the finite-element zone ");
      const auto near  = what.find("near x = ");
      const bool named = deep != std::string::npos &&
                         zone != std::string::npos && near != std::string::npos;
      checks.in_range("without the holds: the message names the zone, the "
                      "depth and the position (1 = yes)",
                      named,
                      1,
                      1);
      double depth = -1, x = -1, y = -1;
      if (named)
        {
          std::istringstream(what.substr(zone + 32)) >> depth;
          std::istringstream(what.substr(near + 9)) >> x >> y;
        }
      checks.in_range("without the holds: depth named / half a spacing",
                      depth / (0.5 * spacing),
                      1e-9,
                      1);
      checks.in_range("without the holds: x named (m)", x, 0.975, 1.0);
      checks.in_range("without the holds: y named (m)", y, 0., 0.4);
    }
  catch (const std::exception &e)
    {
      std::cerr << "error: " << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
