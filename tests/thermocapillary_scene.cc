// Melt flow, thermocapillary return flow through a scene file:
// prm/thermocapillary_cavity.prm run by FempProblem as it is (h = 6.25 um,
// D = 16 cells, 0.05 s = 3.8 viscous times; at D = 8 cells the surface
// speed is 6.8 % low, outside the tolerance). The temperature is
// frozen (Physics/Heat transfer = false) at the function-valued initial
// field T = 1800 K + G x over a cold solid floor; the Marangoni shear
// tau_s = dsigma/dT G drives, at mid-length,
//   u(zeta) = tau_s D/(4 mu) (3 zeta^2 - 2 zeta)   (doc/verification.md).
// The test reads u_x on the probe line 'mid' (cell centres at x = L/2 + h/2)
// of the last output and checks: the surface speed (quadratic through the
// three top cells, extrapolated to zeta = 1) within 5 % of U_s, the zero
// crossing within 5 % of zeta = 2/3; it prints the largest pointwise error
// (over the cell centres, relative to U_s). The reference is computed from
// the scene's parameters (read from the file). 1 and 2 ranks identical.
#include <deal.II/base/utilities.h>

#include <fstream>
#include <sstream>

#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  try
    {
      // Parameters of the scene (the reference is computed from them).
      ParameterHandler prm;
      femp::declare_all_parameters(prm);
      prm.parse_input(argv[1]);
      prm.enter_subsection("Melt flow");
      const double mu = prm.get_double("Viscosity");
      const double dsdT =
        prm.get_double("Surface tension temperature derivative");
      prm.leave_subsection();
      prm.enter_subsection("Material");
      const double rho = prm.get_double("Density");
      prm.leave_subsection();
      prm.enter_subsection("Material points");
      const double top = prm.get_double("Substrate top");
      prm.leave_subsection();
      prm.enter_subsection("Background grid");
      const double h = prm.get_double("Cell size");
      const double H = Utilities::string_to_double(
        Utilities::split_string_list(prm.get("Upper corner"))[1]);
      const double L = Utilities::string_to_double(
        Utilities::split_string_list(prm.get("Upper corner"))[0]);
      prm.leave_subsection();
      // Layer geometry of the scene: solid floor 12.5 um thick below the
      // liquid ('Initial temperature' is 1000 K there), surface at the
      // substrate top; G the x-slope of 'Initial temperature'.
      const double floor = 12.5e-6, D = top - floor, G = 1000; // m, m, K/m
      const double U  = dsdT * G * D / (4 * mu);
      const int    ny = int(std::round(H / h));
      // Probe line through the cell centres of the column right of x = L/2.
      std::ostringstream line;
      line << std::setprecision(10) << "mid: " << L / 2 + h / 2 << ", " << h / 2
           << " -> " << L / 2 + h / 2 << ", " << (ny - 0.5) * h << " : " << ny;
      const auto s = run_scene<2>(argv[1],
                                  comm,
                                  {{"Output", "Directory", "output"},
                                   {"Output", "Output interval", "1"},
                                   {"Output", "Write material points", "never"},
                                   {"Output", "Probe lines", line.str()}});
      checks.print("time steps", s.steps, 8);
      checks.print("fluid steps", s.flow_steps, 8);
      checks.print("material points", s.n_points, 8);

      // The probe line of the last output (number 1: the only one after
      // the initial output), rank 0 reads it; results are broadcast.
      std::vector<double> y, u;
      if (Utilities::MPI::this_mpi_process(comm) == 0)
        {
          std::ifstream in("output/probe_line_mid_00001.csv");
          AssertThrow(
            in, ExcMessage("no probe line output/probe_line_mid_00001.csv"));
          std::string text;
          std::getline(in, text); // # time
          std::getline(in, text); // header
          const auto names = Utilities::split_string_list(text, ',');
          const auto col_y =
            std::find(names.begin(), names.end(), "y") - names.begin();
          const auto col_u =
            std::find(names.begin(), names.end(), "u_x") - names.begin();
          AssertThrow(col_u < long(names.size()), ExcMessage("no u_x column"));
          while (std::getline(in, text))
            {
              const auto v = Utilities::split_string_list(text, ',');
              y.push_back(Utilities::string_to_double(v[col_y]));
              u.push_back(Utilities::string_to_double(v[col_u]));
            }
        }
      y = Utilities::MPI::broadcast(comm, y, 0);
      u = Utilities::MPI::broadcast(comm, u, 0);

      // Cell centres inside the liquid layer.
      std::vector<double> zeta, prof;
      for (std::size_t i = 0; i < y.size(); ++i)
        {
          const double z = (y[i] - floor) / D;
          if (z > 0 && z < 1)
            zeta.push_back(z), prof.push_back(u[i] / U);
        }
      const int n = zeta.size();
      AssertThrow(n >= 3, ExcMessage("fewer than 3 cells in the layer"));
      double err = 0, zero = -1;
      for (int j = 0; j < n; ++j)
        {
          const double z   = zeta[j];
          const double ref = 3 * z * z - 2 * z;
          err              = std::max(err, std::abs(prof[j] - ref));
          checks.print("u/U_s at zeta = " + std::to_string(z).substr(0, 6) +
                         " (analytic " + std::to_string(ref).substr(0, 6) + ")",
                       std::round(prof[j] * 1000) / 1000);
          if (j > 0 && zero < 0 && prof[j - 1] * prof[j] <= 0 &&
              prof[j] != prof[j - 1])
            zero = zeta[j - 1] + (zeta[j] - zeta[j - 1]) * prof[j - 1] /
                                   (prof[j - 1] - prof[j]);
        }
      // Surface speed: the quadratic through the three top cells at zeta = 1
      // (Lagrange extrapolation).
      double us = 0;
      for (int a = n - 3; a < n; ++a)
        {
          double w = 1;
          for (int b = n - 3; b < n; ++b)
            if (b != a)
              w *= (1 - zeta[b]) / (zeta[a] - zeta[b]);
          us += w * prof[a];
        }
      checks.print("U_s = tau_s D/(4 mu) (m/s)", U, 4);
      checks.print("Reynolds number rho |U_s| D/mu",
                   std::abs(rho * U * D / mu),
                   2);
      checks.print("surface speed / U_s", std::round(us * 1000) / 1000);
      checks.at_most("|surface speed - U_s| / |U_s|", std::abs(us - 1), 0.05);
      checks.print("zero crossing zeta", std::round(zero * 1000) / 1000);
      checks.at_most("|zero crossing - 2/3| / (2/3)",
                     std::abs(zero - 2. / 3) * 1.5,
                     0.05);
      checks.at_most("max |u - u_exact| / U_s over the cells", err, 0.05);
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
