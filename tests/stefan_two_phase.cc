// Verification: two-phase Stefan problem (Neumann solution,
// doc/verification.md, "Stefan problem"). All properties 1 (rho, c, lambda, L);
// solid initially 1 K below the melting point T_m = 10 K; the face x = 0 held
// 1 K above it. Closed form: front s = 2 lambda sqrt(t) with
// lambda = 0.377760. The simulation melts over the narrow range
// T_m -/+ 0.005 K; its front is the liquid amount sum(gamma h). Checks the
// front at t = 0.25, 0.5, 1 (2 % once it spans >= 20 cells) and the global
// energy balance: stored enthalpy = heat that entered through the faces.
// Optional arguments (for contrib/study.py; the test runs without them):
// cell size h (default 0.01) and the step as a fraction of the stable step
// (default 0.4; up to 4, above the limit for stability experiments,
// doc/stability.md); the front checks then print their errors as usual.
#include <cstdlib>
#include <fstream>
#include <iostream>

#include "test_tools.h"

using namespace femp_test;

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);

  const int    dim    = 2;
  const double h      = argc > 1 ? std::atof(argv[1]) : 0.01;
  const double safety = argc > 2 ? std::atof(argv[2]) : 0.4;
  const double Tm = 10, lambda = 0.377760;
  if (!(h > 0 && h <= 0.1) || !(safety > 0 && safety <= 4))
    {
      std::cerr << "usage: test_stefan_two_phase [h in (0, 0.1]] "
                   "[step fraction of the stable step in (0, 4]]\n";
      return 1;
    }
  const auto          gp = box<dim>(Point<dim>(0, 0), Point<dim>(3, 2 * h), h);
  BackgroundGrid<dim> grid(gp, comm);
  grid.create();
  Material mat           = unit_material();
  mat.solidus            = Tm - 0.005;
  mat.liquidus           = Tm + 0.005;
  mat.latent_heat_fusion = 1;
  Laser<dim> laser(laser_off<dim>());
  auto       p = heat_parameters<dim>(Tm - 1, {{"x-", Tm + 1}, {"x+", Tm - 1}});
  p.reference_temperature = Tm - 1;
  HeatTransfer<dim> heat(p, mat, laser, grid);
  heat.initialize();
  heat.set_metal_fraction(grid.make_field(1.));
  const double H0 = heat.stored_enthalpy();

  const double dt = safety * heat.stable_time_step();
  double       t  = 0;
  // Front history and the final profile for the plot in doc/
  // (contrib/plot_verification.py).
  std::ofstream history;
  if (Utilities::MPI::this_mpi_process(comm) == 0)
    {
      history.open("stefan_front.csv");
      history << "t,s_sim,s_exact\n";
    }
  auto front = [&]() {
    double liquid = 0;
    for (const auto idx : grid.owned_cells())
      liquid += heat.liquid_fraction()[idx] * h * h;
    return Utilities::MPI::sum(liquid, comm) / (2 * h);
  };
  unsigned int step = 0;
  for (const double t_check : {0.25, 0.5, 1.0})
    {
      while (t < t_check - 1e-12)
        {
          const double size = std::min(dt, t_check - t);
          heat.advance(size, t);
          t += size;
          if (++step % 50 == 0)
            {
              const double s_sim = front();
              if (history.is_open())
                history << t << ',' << s_sim << ',' << 2 * lambda * std::sqrt(t)
                        << '\n';
            }
        }
      // Front: liquid length along the strip (per row).
      const double       s     = front();
      const double       exact = 2 * lambda * std::sqrt(t);
      std::ostringstream what;
      what << "front t=" << t_check << " (" << std::setprecision(3) << exact / h
           << " cells): relative error";
      checks.at_most(what.str(), std::abs(s - exact) / exact, 0.02);
    }
  // Final profile against the Neumann solution (liquid and solid parts).
  {
    const double        nu = 1; // sqrt(alpha_l / alpha_s), all properties 1
    std::vector<double> T_row(grid.n_cells()[0], 0.), T_sum(T_row.size());
    for (const auto idx : grid.owned_cells())
      if (grid.global_index(idx)[1] == 0)
        T_row[grid.global_index(idx)[0]] = heat.temperature()[idx];
    Utilities::MPI::sum(ArrayView<const double>(T_row),
                        comm,
                        ArrayView<double>(T_sum));
    if (Utilities::MPI::this_mpi_process(comm) == 0)
      {
        std::ofstream out("stefan_profile.csv");
        out << "x,T_sim,T_exact\n";
        const double s = 2 * lambda * std::sqrt(t);
        for (unsigned int i = 0; i < T_sum.size(); ++i)
          {
            const double x   = (i + 0.5) * h;
            const double eta = x / (2 * std::sqrt(t));
            const double T_exact =
              x < s ? (Tm + 1) - std::erf(eta) / std::erf(lambda) :
                      (Tm - 1) + std::erfc(nu * eta) / std::erfc(nu * lambda);
            out << x << ',' << T_sum[i] << ',' << T_exact << '\n';
          }
      }
  }
  const double stored  = heat.stored_enthalpy() - H0;
  const double entered = heat.energy_budget().boundary;
  checks.print("stored enthalpy (J/m)", stored, 5);
  checks.at_most("energy balance |stored - entered| / entered",
                 std::abs(stored - entered) / std::abs(entered),
                 1e-9);
  return checks.exit_code();
}
