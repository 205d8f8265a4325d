// Stability checks of the solid (doc/verification.md, "Stability").
// 1. Hourglass control: a 2D block of finite elements (16 x 8 cells of
//    0.1 m, E = 100 Pa, nu = 0.3, rho = 1, elastic), free, loaded by
//    a constant point force at the top centre node (an impact-like load that
//    excites the zero-energy modes of one-point elements). The energy of the
//    hourglass modes (measured with the reference stiffness kappa = 0.05)
//    grows without bound when control is off (constant force on a mode
//    without stiffness: amplitude ~ t^2) and stays bounded, and a small
//    fraction of the stress work, when it is on; in a bending test (the
//    block as a cantilever fixed at x = 0 with a tip shear load) the
//    hourglass energy stays below 10 % of the stress work.
// 2. A solid step above the elastic limit (forced past the input check)
//    blows up; the run must stop with a message naming the solid step and
//    the location instead of carrying non-finite values.
#include <femp/grid/material_points.h>
#include <femp/solid/solid_stress.h>

#include "solid_tools.h"

using namespace femp_test;

namespace
{
  constexpr int dim = 2;

  struct Result
  {
    double mode_half = 0, mode_end = 0, internal = 0, hourglass = 0;
  };

  /// Run the block to t_end with hourglass coefficient @p kappa and solid
  /// step @p dt (0: automatic).
  Result
  run(const double kappa, const double dt, const double t_end, MPI_Comm comm,
      const bool bending = false)
  {
    const double      h = 0.1;
    const Point<dim>  size(1.6, 0.8);
    SolidBlock<dim>   block(size, h, 0.8, unit_material(), comm, 300., 1);
    auto &            grid   = block.grid;
    auto &            points = *block.points;
    const SolidMaterial sm   = elastic_block_material(block.material);
    typename SolidStress<dim>::Parameters sp;
    sp.time_step   = dt;
    // Impact: free body (the checkerboard modes are zero-energy modes);
    // bending: a cantilever fixed at x = 0.
    if (bending)
      sp.fixed_faces = {"x-"};
    sp.energy_file = "";
    const auto fp = fe_block<dim>(true, size, kappa);
    SolidStress<dim> solid(sp, fp, sm, grid, points);
    const std::vector<double> T = grid.make_field(300.);
    solid.initialize(T, "");

    // Point force at the top centre node, added by the rank that counts it
    // (the forces are partial sums over ranks).
    std::array<std::vector<double>, dim> force;
    for (int d = 0; d < dim; ++d)
      force[d] = grid.make_node_field(0.);
    auto add_force = [&](const std::array<int, dim> node,
                         const std::array<int, dim> cell,
                         const double               f) {
      if (grid.in_box(cell) &&
          grid.cell_status()[grid.local_index(cell)] == BackgroundGrid<dim>::owned)
        force[1][grid.local_node_index(node)] += f;
    };
    if (bending) // tip shear load, spread over the nodes of the face x+
      for (int j = 0; j <= 8; ++j)
        add_force({{16, j}}, {{15, std::min(j, 7)}}, -1. / 9);
    else // point force at the top centre node
      add_force({{8, 8}}, {{8, 7}}, -1.);

    Result r;
    solid.advance(0.5 * t_end, T, true, &force);
    r.mode_half = solid.energies().hourglass_mode;
    solid.advance(t_end, T, true, &force);
    const auto e = solid.energies();
    r.mode_end   = e.hourglass_mode;
    r.internal   = e.internal;
    r.hourglass  = e.hourglass;
    return r;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);

  const Result off = run(0, 0, 2, comm);
  const Result on  = run(0.1, 0, 2, comm);
  checks.print("hourglass off: mode energy at t = 1 s", off.mode_half, 3);
  checks.print("hourglass off: mode energy at t = 2 s", off.mode_end, 3);
  checks.print("hourglass on: mode energy at t = 1 s", on.mode_half, 3);
  checks.print("hourglass on: mode energy at t = 2 s", on.mode_end, 3);
  checks.in_range("hourglass off: growth of the mode energy from t = 1 to 2 s",
                  off.mode_end / off.mode_half, 4, 1e30);
  checks.in_range("hourglass on: growth of the mode energy from t = 1 to 2 s",
                  on.mode_end / on.mode_half, 0, 2);
  checks.print("impact, hourglass on: hourglass energy / stress work at t = 2 s",
               on.hourglass / on.internal, 2);
  const Result bend = run(0.1, 0, 2, comm, true);
  checks.at_most("bending, hourglass on: hourglass energy / stress work at t = 2 s",
                 bend.hourglass / bend.internal, 0.1);
  checks.at_most("hourglass on / off: mode energy at t = 2 s",
                 on.mode_end / off.mode_end, 0.01);

  // Forced blow-up: three times the elastic limit.
  {
    const Material thermal = unit_material(); // density 1
    SolidMaterial  sm(thermal);
    sm.youngs_modulus = PiecewiseLinear(100.);
    sm.poisson_ratio  = 0.3;
    typename SolidStress<dim>::Parameters sp;
    const double limit = sp.stable_limit(sm, 0.1);
    bool         caught = false, named = false;
    try
      {
        run(0.1, 3 * limit, 50, comm);
      }
    catch (const std::runtime_error &e)
      {
        const std::string m = e.what();
        caught              = true;
        named = m.find("at solid step") != std::string::npos &&
                m.find("near x =") != std::string::npos;
      }
    checks.in_range("dt = 3x limit: blow-up stopped with an exception", caught, 1, 1);
    checks.in_range("dt = 3x limit: message names the step and the location",
                    named, 1, 1);
  }
  return checks.exit_code();
}
