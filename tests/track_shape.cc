// The track's shape (TrackShape, doc/cases.md "Bead shape") on a prescribed
// metal fraction with a known bump. A 3D box of metal below the substrate
// top z0 carries a ridge along x (x in [xa, xb]) with a parabolic profile
// across it:
//   H(x, y) = z0 + A max(0, 1 - ((y - y0) / w)^2)   for xa <= x <= xb,
//   H = z0 elsewhere,
// and the cells of the ridge above z0 (centre below H) are marked as
// re-solidified bead. Two metal fractions:
//   - diffuse: alpha = 0.5 + (H - z_c) / (3h), clipped to [0, 1], linear
//     in z across the alpha = 1/2 crossing, so the interpolated surface is
//     exact: z_s = H at every column centre (error ~ rounding);
//   - sharp (volume fraction): alpha = (H - z_bottom) / h clipped, the
//     volume of metal in the cell; the interpolation between a full or an
//     empty cell and the cut one errs by at most
//     max over a in [0, 1/2] of a (1/2 - a) / (1 - a) = (3/2 - sqrt 2) h
//     = 0.086 h (at a = 1 - 1/sqrt 2); tolerance 0.09 h.
// Closed forms: bead height A (the profile's top sits on a column centre);
// bead width: the columns whose first cell above z0 (centre z0 + h/2) lies
// below H, |y - y0| < w_e = w sqrt(1 - h / (2A)), so the measured width is
// within h of 2 w_e (whole columns); the bead's length on the centre line
// is xb - xa (grid lines). Runs on 1 and 2 ranks with the same output.
#include <femp/io/track_shape.h>

#include "test_tools.h"

using namespace femp_test;

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);

  constexpr int       dim = 3;
  const double        h   = 0.02;
  BackgroundGrid<dim> grid(
    box<dim>(Point<dim>(0, 0, 0), Point<dim>(0.64, 0.64, 0.48), h), comm);
  grid.create();

  const double z0 = 0.2, A = 0.1, w = 0.15, y0 = 0.31, xa = 0.2, xb = 0.44;
  const auto   H = [&](const Point<dim> &p) {
    if (p[0] < xa || p[0] > xb)
      return z0;
    return z0 + A * std::max(0., 1 - std::pow((p[1] - y0) / w, 2));
  };

  typename TrackShape<dim>::Parameters prm;
  prm.cross_sections = {0.31, 0.55}; // on the ridge, off it
  // Centre line at y0 (a column centre), substrate top z0.
  TrackShape<dim> shape(prm, grid, y0, z0, 0.);

  std::vector<double> diffuse = grid.make_field(0.);
  std::vector<double> sharp   = grid.make_field(0.);
  std::vector<double> bead    = grid.make_field(0.);
  for (std::size_t i = 0; i < diffuse.size(); ++i)
    {
      const auto   c  = grid.cell_center(i);
      const double Hc = H(c);
      diffuse[i]      = std::clamp(0.5 + (Hc - c[2]) / (3 * h), 0., 1.);
      sharp[i]        = std::clamp((Hc - (c[2] - 0.5 * h)) / h, 0., 1.);
      bead[i]         = c[2] > z0 && c[2] < Hc ? 1. : 0.;
    }

  const double w_e = w * std::sqrt(1 - h / (2 * A));
  for (const std::string kind : {"diffuse", "sharp"})
    {
      const auto sections =
        shape.measure(kind == "diffuse" ? diffuse : sharp, bead);
      AssertThrow(sections.size() == 3, ExcMessage("three sections"));
      double err = 0;
      for (const auto &s : sections)
        for (std::size_t c = 0; c < s.surface.size(); ++c)
          err =
            std::max(err,
                     std::abs(s.surface[c] - H(Point<dim>(s.x[c], s.y[c], 0))));
      const double tol = kind == "diffuse" ? 1e-9 : 0.09 * h;
      checks.at_most(kind + ": max |z_s - H| over all columns / h",
                     err / h,
                     tol / h);
      const auto &centre = sections[0], &cross = sections[1],
                 &off = sections[2];
      checks.at_most(kind + ": centre line: |bead length - (xb - xa)| / h",
                     std::abs(centre.width - (xb - xa)) / h,
                     1e-9);
      checks.at_most(kind + ": centre line: |bead height - A| / h",
                     std::abs(centre.height - A) / h,
                     tol / h);
      checks.at_most(kind + ": cross-section: |bead height - A| / h",
                     std::abs(cross.height - A) / h,
                     tol / h);
      checks.print(kind + ": cross-section: bead width / h",
                   std::round(cross.width / h),
                   3);
      checks.at_most(kind + ": cross-section: |bead width - 2 w_e| / h",
                     std::abs(cross.width - 2 * w_e) / h,
                     1.);
      checks.at_most(kind + ": off the ridge: bead width + height",
                     off.width + off.height,
                     0.);
    }
  return checks.exit_code();
}
