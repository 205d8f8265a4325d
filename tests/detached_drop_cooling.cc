// Heat loss of detached metal (Heat transfer/Detached drops = sphere,
// doc/equations.md "Detached drops"): a drop of at most 'Detached drop
// cells' face-connected metal cells (no other metal face neighbour inside
// the domain) cools as a sphere (2D: a cylinder) of its metal volume in
// still gas. With conduction to the gas the only loss (Nusselt number 2,
// coefficient 2 k_g/d, d the sphere's diameter), equal metal fractions and
// a constant specific heat, each cell's temperature obeys
//   C dT/dt = -(2 dim alpha/d) (2 k_g/d) (T - T_ref),
// C = alpha rho c + (1 - alpha) rho_g c_g the cell's heat capacity, so it
// decays as exp(-lambda t), d from the drop's metal volume. Checked, in 3D
// and 2D, for a one-point drop (alpha = 1/8 in 3D, 1/4 in 2D) inside the
// domain and on its top face, for a drop of two such cells, and for
// drops of three (an L) and four cells (a vertical line across the middle
// of the box, where two ranks split it, and a square):
//  - the computed temperature against the implicit step's own recursion
//    T_{n+1} - T_ref = (T_n - T_ref)/(1 + lambda dt) (round-off), and
//    against the exponential (the step's O(lambda dt) error);
//  - the booked convection loss against the enthalpy the cell lost;
//  - with 'off' a drop of one or two cells keeps its temperature (no
//    surface, no conduction); a line of five cells is no detached metal
//    with the default largest drop of four cells, nor a line of three
//    with 'Detached drop cells = 2' (no gas conduction).
// Also printed, not gated: a one-point drop of the default 316L data at
// 4 um cells with the default convection, radiation and evaporation: the
// time it takes to reach the solidus and 500 K from 2500 K with k_g =
// 0.043 W/(m K) (argon near 1000 K), the same without the model, and with
// the default k_g = 0.018 (argon at 300 K) from 2500 K and from 4830 K (the
// temperature of spatter held on the top face of the paper-scale track).
#include <array>
#include <tuple>

#include "test_tools.h"

using namespace femp_test;

namespace
{
  template <int dim>
  Point<dim>
  cube_corner(const double L)
  {
    Point<dim> p;
    for (int d = 0; d < dim; ++d)
      p[d] = L;
    return p;
  }

  template <int dim>
  struct Drop
  {
    BackgroundGrid<dim> grid;
    Laser<dim>          laser;
    std::vector<double> alpha;

    Drop(const double h, const int n, MPI_Comm comm)
        : grid(box<dim>(Point<dim>(), cube_corner<dim>(n * h), h), comm)
        , laser(laser_off<dim>())
    {
      grid.create();
      alpha = grid.make_field(0.);
    }

    /// Put metal fraction @p a into the cell whose centre is nearest @p x.
    void
    put(const Point<dim> &x, const double a)
    {
      for (std::size_t i = 0; i < alpha.size(); ++i)
        if (grid.cell_center(i).distance(x) < 0.5 * grid.h())
          alpha[i] = a;
    }

    /// Temperature of the cell at @p x over all ranks (collective).
    double
    temperature_at(const HeatTransfer<dim> &heat, const Point<dim> &x) const
    {
      double T = -1;
      for (const auto idx : grid.owned_cells())
        if (grid.cell_center(idx).distance(x) < 0.5 * grid.h())
          T = heat.temperature()[idx];
      return Utilities::MPI::max(T, grid.communicator());
    }
  };

  /// Cell offsets (in cells, x y z) of the drops checked.
  using Shape = std::vector<std::array<int, 3>>;

  template <int dim>
  void
  closed_form_check(Checks            &checks,
                    MPI_Comm           comm,
                    const bool         on_face,
                    const Shape       &shape = {{0, 0, 0}},
                    const std::string &name  = "")
  {
    const int    cells = shape.size();
    const double h = 4e-6, T0 = 1500, Tref = 300;
    const int    n = 8;
    Material     mat;
    mat.specific_heat = PiecewiseLinear(500.);
    mat.conductivity  = PiecewiseLinear(20.);
    mat.solidus = 1e5, mat.liquidus = 2e5, mat.latent_heat_fusion = 0;
    mat.gas_conductivity = 0.043;
    Drop<dim>  drop(h, n, comm);
    Point<dim> x;
    for (int d = 0; d < dim; ++d)
      x[d] = (n / 2 + 0.5) * h;
    if (on_face)
      x[dim - 1] = (n - 0.5) * h;
    const double a = 1. / (1 << dim); // one point of 2^dim per cell
    for (const auto &o : shape)
      {
        Point<dim> y = x;
        for (int d = 0; d < dim; ++d)
          y[d] += o[d] * h;
        drop.put(y, a);
      }
    auto p                  = heat_parameters<dim>(T0, {});
    p.reference_temperature = Tref;
    p.detached_drops        = true;
    HeatTransfer<dim> heat(p, mat, drop.laser, drop.grid);
    heat.initialize();
    MetalBodies<dim> bodies(drop.grid, p.detached_drop_cells);
    bodies.update(drop.alpha);
    heat.set_metal_fraction(drop.alpha, &bodies);
    const double V = cells * a * std::pow(h, dim);
    const double d =
      dim == 3 ? std::cbrt(6 * V / M_PI) : std::sqrt(4 * V / M_PI);
    const double C = a * mat.density * 500. +
                     (1 - a) * mat.gas_density * mat.gas_specific_heat;
    const double lambda =
      (2 * dim * a / d) * (2 * mat.gas_conductivity / d) / C;
    const double dt    = 0.01 / lambda;
    double       T_rec = T0;
    for (int k = 0; k < 100; ++k)
      {
        heat.advance(dt, k * dt);
        T_rec = Tref + (T_rec - Tref) / (1 + lambda * dt);
      }
    const double      T     = drop.temperature_at(heat, x);
    const double      T_exp = Tref + (T0 - Tref) * std::exp(-lambda * 100 * dt);
    const std::string at    = std::to_string(dim) + "D drop of " +
                           std::to_string(cells) + " cell(s) " + name +
                           (on_face ? "on the top face" : "inside") + ": ";
    checks.print(at + "decay rate lambda, 1/s", lambda);
    checks.print(at + "(T - T_ref)/(T0 - T_ref) at t = 1/lambda",
                 std::round((T - Tref) / (T0 - Tref) * 1e4) / 1e4);
    checks.at_most(at + "|T - implicit recursion| / (T0 - T_ref)",
                   std::abs(T - T_rec) / (T0 - Tref),
                   1e-10);
    checks.at_most(at + "|T - exponential| / (T0 - T_ref)",
                   std::abs(T - T_exp) / (T0 - Tref),
                   0.01);
    const double lost = cells * C * std::pow(h, dim) * (T0 - T);
    checks.at_most(at + "|booked convection / enthalpy lost - 1|",
                   std::abs(heat.energy_budget().convection / lost - 1),
                   1e-9);
  }

  template <int dim>
  void
  off_and_line_check(Checks &checks, MPI_Comm comm)
  {
    const double h = 4e-6, T0 = 1500;
    const int    n = 8;
    Material     mat;
    mat.gas_conductivity = 0.043;
    // (cells, on, largest drop): 1 and 2 on are the closed-form checks.
    const std::vector<std::tuple<int, bool, unsigned int>> cases = {
      {1, false, 4}, {2, false, 4}, {5, true, 4}, {3, true, 2}};
    for (const auto &[cells, on, largest] : cases)
      {
        // A line along x from cell 2 (the first cell) in the box of 8.
        Drop<dim>  drop(h, n, comm);
        Point<dim> x;
        for (int d = 0; d < dim; ++d)
          x[d] = (n / 2 + 0.5) * h;
        x[0] = 2.5 * h;
        drop.put(x, 0.5);
        for (int c = 1; c < cells; ++c)
          {
            Point<dim> y = x;
            y[0] += c * h;
            drop.put(y, 0.5);
          }
        auto p                  = heat_parameters<dim>(T0, {});
        p.reference_temperature = 300;
        p.detached_drops        = on;
        p.detached_drop_cells   = largest;
        HeatTransfer<dim> heat(p, mat, drop.laser, drop.grid);
        heat.initialize();
        MetalBodies<dim> bodies(drop.grid, on ? largest : 0);
        bodies.update(drop.alpha);
        heat.set_metal_fraction(drop.alpha, &bodies);
        for (int k = 0; k < 10; ++k)
          heat.advance(1e-7, k * 1e-7);
        const std::string at =
          std::to_string(dim) + "D, " + std::to_string(cells) + " cell(s), " +
          (on ? "sphere, largest drop " + std::to_string(largest) : "off") +
          ": ";
        checks.at_most(at + "|T - T0| of the first cell, K",
                       std::abs(drop.temperature_at(heat, x) - T0),
                       1e-9);
        checks.at_most(at + "convection loss, J",
                       std::abs(heat.energy_budget().convection),
                       1e-30);
      }
  }

  /// Not gated: cooling of a one-point 316L drop at 4 um cells.
  void
  steel_drop(Checks      &checks,
             MPI_Comm     comm,
             const bool   on,
             const double T0,
             const double k_g)
  {
    const double h = 4e-6;
    const int    n = 8;
    Material     mat; // 316L-like defaults
    mat.gas_conductivity = k_g;
    Drop<3>  drop(h, n, comm);
    Point<3> x((n / 2 + 0.5) * h, (n / 2 + 0.5) * h, (n / 2 + 0.5) * h);
    drop.put(x, 0.125);
    auto p                = HeatTransfer<3>::Parameters(); // default losses
    p.initial_temperature = T0;
    p.detached_drops      = on;
    HeatTransfer<3> heat(p, mat, drop.laser, drop.grid);
    heat.initialize();
    MetalBodies<3> bodies(drop.grid, on ? p.detached_drop_cells : 0);
    bodies.update(drop.alpha);
    heat.set_metal_fraction(drop.alpha, &bodies);
    const double dt      = 1e-7;
    double       t_solid = -1, t_500 = -1;
    for (int k = 0; k < 20000 && t_500 < 0; ++k)
      {
        heat.advance(dt, k * dt);
        const double T = drop.temperature_at(heat, x);
        if (t_solid < 0 && T < mat.solidus)
          t_solid = (k + 1) * dt;
        if (t_500 < 0 && T < 500)
          t_500 = (k + 1) * dt;
      }
    const std::string at = "316L one-point drop from " +
                           std::to_string(int(T0)) +
                           " K, k_g = " + std::to_string(k_g).substr(0, 5) +
                           ", " + (on ? "sphere" : "off") + ": ";
    checks.print(at + "time to the solidus, us (-1: not within 2 ms)",
                 t_solid > 0 ? std::round(t_solid * 1e7) / 10 : -1,
                 3);
    checks.print(at + "time to 500 K, us (-1: not within 2 ms)",
                 t_500 > 0 ? std::round(t_500 * 1e7) / 10 : -1,
                 3);
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
      for (const bool face : {false, true})
        {
          closed_form_check<3>(checks, comm, face);
          closed_form_check<2>(checks, comm, face);
        }
      closed_form_check<3>(checks, comm, false, {{0, 0, 0}, {1, 0, 0}});
      closed_form_check<2>(checks, comm, false, {{0, 0, 0}, {1, 0, 0}});
      const Shape el = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}};
      closed_form_check<3>(checks, comm, false, el, "(L) ");
      closed_form_check<2>(checks, comm, false, el, "(L) ");
      // Across the middle of the box in z (3D) or y (2D): split between
      // two ranks.
      closed_form_check<3>(checks,
                           comm,
                           false,
                           {{0, 0, -2}, {0, 0, -1}, {0, 0, 0}, {0, 0, 1}},
                           "(vertical line) ");
      closed_form_check<2>(checks,
                           comm,
                           false,
                           {{0, -2, 0}, {0, -1, 0}, {0, 0, 0}, {0, 1, 0}},
                           "(vertical line) ");
      const Shape square = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
      closed_form_check<3>(checks, comm, false, square, "(square) ");
      closed_form_check<2>(checks, comm, false, square, "(square) ");
      off_and_line_check<3>(checks, comm);
      off_and_line_check<2>(checks, comm);
      steel_drop(checks, comm, true, 2500, 0.043);
      steel_drop(checks, comm, false, 2500, 0.043);
      steel_drop(checks, comm, true, 2500, 0.018);
      steel_drop(checks, comm, true, 4830, 0.018);
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
