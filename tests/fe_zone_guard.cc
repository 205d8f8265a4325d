// The automatic finite-element zone and its guard (fe_zone_depth.h,
// doc/cases.md):
// 1. The melt-depth estimate against its two closed-form limits: at high
//    Peclet number Rosenthal's point source melts as deep as the line
//    source, d = sqrt(2 Q / (pi e rho c v dT)); at low Peclet number as deep
//    as the resting point source, d = Q / (2 pi k dT). Gate 1 % each (the
//    numerical maximum over the position behind the source and the
//    bisection in depth). Printed: the conservative depth and the 'auto'
//    zone top of the paper's case 3.2 (prm/case_3_2_femp.prm) at 50, 100
//    and 200 W.
// 2. tests/fe_zone_guard.prm, a laser track on a bare substrate with
//    thermal stress, FE zone top one cell below the surface: the melt
//    reaches the zone and the run must stop with FeZoneMelted, naming the
//    element and a zone top below it.
// 3. The same scene with 'Zone upper corner = auto': the driver must report
//    the top of point 1's formula, and the run must end normally, with the
//    largest temperature in the zone below the solidus (the guard did not
//    fire).
#include <femp/solid/fe_zone_depth.h>

#include <regex>
#include <sstream>

#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

namespace
{
  /// Run the scene with std::cout in @p log (restored also when the run
  /// throws), 'Solid FEM/Zone upper corner' set to @p top.
  FempProblem<3>::Summary
  run(const std::string  &file,
      MPI_Comm            comm,
      const std::string  &top,
      std::ostringstream &log)
  {
    ParameterHandler prm;
    declare_all_parameters(prm);
    prm.parse_input(file);
    prm.enter_subsection("Solid FEM");
    prm.set("Zone upper corner", top);
    prm.leave_subsection();
    struct Redirect
    {
      std::streambuf *old;
      ~Redirect()
      {
        std::cout.rdbuf(old);
      }
    } redirect{std::cout.rdbuf(log.rdbuf())};
    FempProblem<3> problem(prm, comm);
    problem.run();
    return problem.summary();
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
      // 1. Limits of the estimate (316L-like numbers).
      const double Q = 70, rho_c = 7955 * 426.6, dT = 1370;
      {
        const double k = 0.5, v = 2; // Pe = v r / (2 a) with r = 20 um: 270
        const double d = rosenthal_melt_depth(Q, v, k, rho_c, dT);
        checks.at_most("high Peclet: |d_Rosenthal / d_line - 1|",
                       std::abs(d / line_source_melt_depth(Q, v, rho_c, dT) -
                                1),
                       0.01);
      }
      {
        const double k = 20, v = 1e-4; // resting source
        const double d = rosenthal_melt_depth(Q, v, k, rho_c, dT);
        checks.at_most("low Peclet: |d_Rosenthal / (Q / (2 pi k dT)) - 1|",
                       std::abs(d / (Q / (2 * M_PI * k * dT)) - 1),
                       0.01);
      }
      Material m; // the scene's (femp's default 316L tables)
      {
        ParameterHandler prm;
        declare_all_parameters(prm);
        prm.parse_input(argv[1]);
        m.parse_parameters(prm);
      }
      for (const double P : {50., 100., 200.})
        {
          const double d = conservative_melt_depth(m, 0.35 * P, 2., 300.);
          checks.print("case 3.2 at " + std::to_string(int(P)) +
                         " W: conservative melt depth (um)",
                       std::round(d * 1e7) / 10,
                       3);
          checks.print(
            "  'auto' FE zone top, substrate top 90 um (um)",
            std::round(automatic_fe_zone_top(d, 90e-6, 0, 4e-6) * 1e7) / 10,
            3);
        }

      // 2. The zone one cell below the surface: the guard stops the run.
      std::string message;
      try
        {
          std::ostringstream log;
          run(argv[1], comm, "96e-6, 64e-6, 88e-6", log);
        }
      catch (const FeZoneMelted &e)
        {
          message = e.what();
        }
      checks.print("zone top at 88 um: the guard stopped the run (1 = yes)",
                   !message.empty(),
                   1);
      std::smatch match;
      const bool  named = std::regex_search(
        message,
        match,
        std::regex(
          "finite element at \\(([-0-9.e]+), ([-0-9.e]+), ([-0-9.e]+)\\) "
           "m reached the solidus.*Zone upper corner.*at most "
           "([-0-9.e]+) m"));
      checks.print("  message names the element and the top to use (1 = yes)",
                   named,
                   1);
      if (named)
        {
          const double z = std::stod(match[3]), top = std::stod(match[4]);
          checks.print("  element centre z (um)", std::round(z * 1e7) / 10, 3);
          checks.in_range("  suggested top below the element's bottom (um)",
                          (z - 4e-6 - top) * 1e6,
                          15.9,
                          16.1);
        }

      // 3. 'auto'.
      std::ostringstream log;
      const auto         s        = run(argv[1], comm, "auto", log);
      const std::string  text     = log.str(); // rank 0 prints
      double             reported = -1;
      if (std::regex_search(text,
                            match,
                            std::regex("zone top 'auto' at z = ([-0-9.e]+) m")))
        reported = std::stod(match[1]);
      reported              = Utilities::MPI::max(reported, comm);
      const bool   found    = reported >= 0;
      const double expected = automatic_fe_zone_top(
        conservative_melt_depth(m, 70, 2, 300), 96e-6, 0, 8e-6);
      checks.print("'auto': reported zone top (um)",
                   found ? std::round(reported * 1e7) / 10 : -1,
                   3);
      checks.at_most("'auto': |reported - formula| (um)",
                     found ? std::abs(reported - expected) * 1e6 : 1e9,
                     1e-3);
      checks.print("'auto': run reached its end time (us)",
                   std::round(s.time * 1e7) / 10,
                   3);
      checks.in_range("'auto': the surface melted, peak temperature (K)",
                      std::round(s.T_max / 100) * 100,
                      1700,
                      1e5);
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
