// A beam narrower than a cell must not be lost between cell centres.
// (a) The absorbed flux a surface cell receives, summed over a flat row of
// cells (2D) or a flat layer (3D) times the cell's face, equals the
// absorbed power eta P for beams of 1e-24 to 0.9 cells at any position
// of the axis within a cell (the deposit averages the Gaussian over each
// cell); a beam of one cell or more is sampled at the cell centres, whose
// sum then differs from eta P by the sampling error of a Gaussian, a few
// per cent at one cell. (b) A whole 2D scene whose beam is a quarter of a
// cell books eta P t as the laser energy of its energy report (point
// sampling booked 89 % of it in this scene, and nothing for a
// beam of 1e-30 m).
#include <deal.II/base/mpi.h>

#include <cmath>
#include <iostream>

#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

template <int dim>
double
deposit_error(const double rb_cells, const double offset_cells, const double h)
{
  typename Laser<dim>::Parameters p;
  p.power        = 200;
  p.absorptivity = 0.35;
  p.beam_radius  = rb_cells * h;
  p.start_point  = Point<dim>();
  p.end_point    = Point<dim>();
  p.end_point[0] = h; // a segment, never used here
  const Laser<dim> laser(p);
  Point<dim>       axis;
  for (int d = 0; d < dim - 1; ++d)
    axis[d] = (offset_cells + 0.13 * d) * h;
  const int n   = 20; // cells -n..n around the axis in each direction
  double    sum = 0;
  for (int i = -n; i <= n; ++i)
    for (int j = (dim == 3 ? -n : 0); j <= (dim == 3 ? n : 0); ++j)
      {
        Point<dim> c;
        c[0] = (i + 0.5) * h;
        if (dim == 3)
          c[1] = (j + 0.5) * h;
        sum += laser.cell_flux(c, axis, p.power, h) * std::pow(h, dim - 1);
      }
  return std::abs(sum / (p.absorptivity * p.power) - 1);
}

template <int dim>
void
check_deposits(Checks &checks)
{
  const double h           = 8e-6;
  double       narrow      = 0;
  double       one_cell    = 0;
  const double offsets[]   = {0, 0.3, 0.5, 0.77};
  const double narrow_rb[] = {1e-24, 0.1, 0.25, 0.5, 0.9};
  for (const double o : offsets)
    {
      for (const double rb : narrow_rb)
        narrow = std::max(narrow, deposit_error<dim>(rb, o, h));
      one_cell = std::max(one_cell, deposit_error<dim>(1., o, h));
    }
  // Round-off (1e-16 to 1e-15, different on each machine) printed as 0.
  const auto        rounded = [](const double e) { return e < 1e-13 ? 0. : e; };
  const std::string d       = std::to_string(dim) + "D";
  checks.at_most(d + ": beams of 1e-24 to 0.9 cells, deposited / eta P - 1",
                 rounded(narrow),
                 1e-12);
  checks.at_most(d + ": beam of one cell (sampled), deposited / eta P - 1",
                 std::round(one_cell * 100) / 100,
                 0.05);
}

int
main(int argc, char *argv[])
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  const MPI_Comm                   comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  check_deposits<2>(checks);
  check_deposits<3>(checks);

  // (b) The 2D scene of the input tests, with a beam of h/4 = 2 um: the
  // laser stays on the flat substrate for the whole run (start 50 um,
  // 2 m/s over 10 us).
  const double t_end = 1e-5, eta_P = 0.35 * 200;
  AssertThrow(argc > 1,
              ExcMessage("usage: test_laser_narrow_beam small_2d.prm"));
  const auto s = run_scene<2>(argv[1],
                              comm,
                              {{"Laser", "Beam radius", "2e-6"},
                               {"Time stepping", "End time", "1e-5"},
                               {"Output", "Directory", "narrow_beam"},
                               {"Output", "Write material points", "never"}});
  checks.at_most("2D scene, beam of h/4: laser energy / (eta P t) - 1",
                 std::abs(s.laser / (eta_P * t_end) - 1) < 1e-13 ?
                   0. :
                   std::abs(s.laser / (eta_P * t_end) - 1),
                 1e-9);
  return checks.exit_code();
}
