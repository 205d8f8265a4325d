// Detection of a collapsed material point and of an inverted finite element
// (doc/stability.md). A 2D block (16 x 8 cells of 0.1 m, E = 100 Pa,
// nu = 0.3, rho = 1, elastic) is driven by nodal forces, calling
// SolidSubCycle directly:
// 1. all material points, a converging force f = -F (x - x_c) at every
//    node: the points are squeezed through the centre, a point volume
//    V (1 + tr L dt) turns negative while everything is still finite;
// 2. all finite elements, the same force: an element's centre Jacobian
//    ratio J (product of 1 + tr L dt) turns negative;
// 3. all finite elements, a checkerboard force f_y = F (-1)^(i + j), which
//    drives only the hourglass mode: with hourglass control on, the corner
//    Jacobian 1 + (J - 1) - B |q| (first order) reaches zero;
// 4. the same with hourglass control off: the mode grows without stiffness
//    until a corner inverts (the corners are checked with control off as
//    well), which must stop the run in the same way;
// 5. a weaker checkerboard force without control: with femp's hourglass
//    distortion limit (B sum |q| of a corner) the run stops on the
//    distorted corners, at an earlier step than the inversion (cases 1-4
//    run with the limit 1, which leaves only the inversion check).
// Each stop must be an exception naming the solid step, the time, the
// position and what to change, thrown on every rank at the same step.
#include <femp/grid/material_points.h>
#include <femp/solid/solid_sub_cycle.h>

#include "solid_tools.h"

using namespace femp_test;

namespace
{
  constexpr int dim = 2;

  enum class Load
  {
    converging,
    checkerboard
  };

  struct Outcome
  {
    bool        thrown = false;
    std::string message;
  };

  Outcome
  run(const bool   fe,
      const Load   load,
      const double F,
      const double kappa,
      MPI_Comm     comm,
      const double distortion_limit = 1)
  {
    const double        h = 0.1;
    const Point<dim>    size(1.6, 0.8);
    SolidBlock<dim>     block(size, h, 0.8, unit_material(), comm, 300., 1);
    auto               &grid   = block.grid;
    auto               &points = *block.points;
    const SolidMaterial sm     = elastic_block_material(block.material);
    typename SolidSubCycle<dim>::Parameters sp;
    sp.energy_file        = "";
    const auto         fp = fe_block<dim>(fe, size, kappa, distortion_limit);
    SolidSubCycle<dim> solid(sp, fp, sm, grid, points);
    const std::vector<double> T = grid.make_field(300.);
    solid.initialize(T, "");

    // Nodal forces, added by the rank that owns the cell named for the
    // node (the forces are partial sums over ranks).
    std::array<std::vector<double>, dim> force;
    for (int d = 0; d < dim; ++d)
      force[d] = grid.make_node_field(0.);
    for (int i = 0; i <= 16; ++i)
      for (int j = 0; j <= 8; ++j)
        {
          const std::array<int, dim> cell{{std::min(i, 15), std::min(j, 7)}};
          if (!grid.in_box(cell) ||
              grid.cell_status()[grid.local_index(cell)] !=
                BackgroundGrid<dim>::owned)
            continue;
          const unsigned int n = grid.local_node_index({{i, j}});
          if (load == Load::converging)
            {
              force[0][n] += -F * (i * h - 0.8);
              force[1][n] += -F * (j * h - 0.4);
            }
          else
            force[1][n] += ((i + j) % 2 ? -F : F);
        }

    Outcome o;
    try
      {
        solid.advance(1., T, true, &force);
      }
    catch (const std::exception &e)
      {
        o.thrown  = true;
        o.message = e.what();
      }
    // Every rank must have met the same outcome.
    const int thrown = o.thrown;
    if (Utilities::MPI::min(thrown, comm) != Utilities::MPI::max(thrown, comm))
      o.message = "not thrown on every rank";
    return o;
  }

  /// The solid step the message names (-1: none).
  int
  step_of(const std::string &m)
  {
    const auto k = m.find("at solid step ");
    return k == std::string::npos ? -1 : std::atoi(m.c_str() + k + 14);
  }

  bool
  has(const std::string &m, const std::string &what)
  {
    return m.find(what) != std::string::npos;
  }

  void
  check_stop(Checks            &checks,
             const std::string &name,
             const Outcome     &o,
             const std::string &kind)
  {
    checks.in_range(name + ": stopped with an exception", o.thrown, 1, 1);
    checks.in_range(name + ": message says '" + kind + "'",
                    has(o.message, kind),
                    1,
                    1);
    checks.in_range(name + ": message names step, time, position and what "
                           "to change",
                    step_of(o.message) > 0 && has(o.message, " s, near x = ") &&
                      has(o.message, "'Solid/Safety factor'") &&
                      has(o.message, "'Solid FEM/Hourglass coefficient'"),
                    1,
                    1);
    checks.in_range(name + ": before anything non-finite",
                    !has(o.message, "non-finite") && !has(o.message, "nan") &&
                      !has(o.message, "inf"),
                    1,
                    1);
    checks.print(name + ": stopped at solid step", step_of(o.message));
    if (std::getenv("FEMP_SHOW_MESSAGES"))
      checks.print("  message: " + o.message, 0);
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);

  const double  F_c    = argc > 1 ? std::atof(argv[1]) : 10;
  const double  F_h    = argc > 2 ? std::atof(argv[2]) : 3;
  const double  F_w    = argc > 3 ? std::atof(argv[3]) : 0.1;
  const Outcome points = run(false, Load::converging, F_c, 0.1, comm);
  check_stop(checks,
             "points, converging force",
             points,
             "a material point collapsed");
  const Outcome squeezed = run(true, Load::converging, F_c, 0.1, comm);
  check_stop(checks,
             "elements, converging force",
             squeezed,
             "a finite element inverted");
  const Outcome hourglass = run(true, Load::checkerboard, F_h, 0.1, comm);
  check_stop(checks,
             "elements, checkerboard force, hourglass control on",
             hourglass,
             "a finite element inverted");
  const Outcome off = run(true, Load::checkerboard, F_h, 0, comm);
  check_stop(checks,
             "elements, checkerboard force, hourglass control off",
             off,
             "a finite element inverted");
  // A weaker checkerboard force without control: the mode grows for many
  // steps before it inverts a corner. With femp's distortion limit the run
  // stops on the distorted corners, earlier.
  const double  limit = SolidFEM<dim>::Parameters().hourglass_distortion_limit;
  const Outcome weak_inverted = run(true, Load::checkerboard, F_w, 0, comm);
  check_stop(checks,
             "elements, weak checkerboard force, distortion limit 1",
             weak_inverted,
             "a finite element inverted");
  const Outcome weak = run(true, Load::checkerboard, F_w, 0, comm, limit);
  check_stop(checks,
             "elements, weak checkerboard force, femp's distortion limit",
             weak,
             "hourglass modes of a finite element distorted its corners");
  checks.in_range("weak checkerboard force: the distortion check stops first",
                  step_of(weak.message) < step_of(weak_inverted.message),
                  1,
                  1);
  return checks.exit_code();
}
