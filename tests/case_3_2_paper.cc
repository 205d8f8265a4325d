// The paper-scale scenes of cases 3.2 and 3.3 (prm/case_3_2_femp.prm,
// prm/case_3_2_mpm.prm, prm/case_3_3_{50,100,200}W.prm; doc/cases.md), label
// 'long': every scene file is read as femp reads it ('include' next to the
// including scene; the repository root is the argument); the case 3.3
// files must differ from the FEMP scene in Laser/Power and Output/Directory
// only. Then the FEMP and the all-MPM scene run their first two
// temperature steps (0.2 us; about a minute each, mostly setup) and the
// test prints their sizes (grid cells, material points, solid points,
// finite elements: the paper's 624,000 cells, 180,000 elements), checks
// that the probe lines carry the stress fields, and that EF lies in the FE
// zone of the FEMP scene and CD above it. Expected output: the sizes as
// printed by femp for both scenes in the measured 2 us runs of doc/cases.md.
#include <femp/base/parameter_file.h>

#include <regex>
#include <sstream>

#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

namespace
{
  constexpr int dim = 3;

  void
  parse(ParameterHandler &prm, const std::string &root, const std::string &file)
  {
    declare_all_parameters(prm);
    femp::parse_parameter_file(prm, root + "/" + file);
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  const std::string                root = argv[1];
  try
    {
      ParameterHandler base;
      parse(base, root, "prm/case_3_2_femp.prm");
      std::ostringstream base_text;
      base.print_parameters(base_text, ParameterHandler::ShortPRM);
      for (const int P : {50, 100, 200})
        {
          ParameterHandler prm;
          parse(prm, root, "prm/case_3_3_" + std::to_string(P) + "W.prm");
          prm.enter_subsection("Laser");
          checks.print("case 3.3 file at " + std::to_string(P) +
                         " W: Laser/Power",
                       prm.get_double("Power"),
                       4);
          prm.set("Power", base.get({"Laser"}, "Power"));
          prm.leave_subsection();
          prm.enter_subsection("Output");
          prm.set("Directory", base.get({"Output"}, "Directory"));
          prm.leave_subsection();
          std::ostringstream text;
          prm.print_parameters(text, ParameterHandler::ShortPRM);
          checks.print("  otherwise the FEMP scene (1 = yes)",
                       text.str() == base_text.str(),
                       1);
        }

      for (const std::string name : {"femp", "mpm"})
        {
          ParameterHandler prm;
          parse(prm, root, "prm/case_3_2_" + name + ".prm");
          // Two temperature steps: the scenes prescribe the step.
          prm.enter_subsection("Time stepping");
          std::ostringstream end;
          end << std::setprecision(17) << 2 * prm.get_double("Time step");
          prm.set("End time", end.str());
          prm.leave_subsection();
          prm.enter_subsection("Output");
          prm.set("Directory", name);
          prm.set("Write material points", "never");
          prm.leave_subsection();
          std::ostringstream log;
          std::streambuf    *old = std::cout.rdbuf(log.rdbuf());
          FempProblem<dim>   problem(prm, comm);
          problem.run();
          std::cout.rdbuf(old);
          const std::string t = log.str();
          std::smatch       m;
          std::regex_search(t,
                            m,
                            std::regex("background grid: ([0-9]+) cells"));
          checks.print(name + ": grid cells", std::stod(m[1]), 8);
          std::regex_search(t,
                            m,
                            std::regex("solid: ([0-9]+) material points"
                                       "(?: \\([^)]*\\))?, "
                                       "([0-9]+) finite elements"));
          checks.print(name + ": solid material points", std::stod(m[1]), 8);
          checks.print(name + ": finite elements", std::stod(m[2]), 8);
          checks.print(name + ": steps run", problem.summary().steps, 3);
          std::ifstream line(name + "/probe_line_EF_00001.csv");
          std::string   row;
          std::getline(line, row), std::getline(line, row);
          checks.print(name +
                         ": EF carries sigma_xx ... plastic_strain (1 = yes)",
                       row.find(",sigma_xx,sigma_yy,sigma_zz,von_mises,"
                                "plastic_strain") != std::string::npos,
                       1);
        }
      // The lines against the FE zone of the FEMP scene.
      const auto zone =
        parse_point<dim>(base.get({"Solid FEM"}, "Zone upper corner"),
                         "Solid FEM/Zone upper corner");
      const auto lines =
        Utilities::split_string_list(base.get({"Output"}, "Probe lines"), ';');
      for (const auto &l : lines)
        {
          const auto parts = Utilities::split_string_list(l, ':');
          const auto a =
            parse_point<dim>(parts[1].substr(0, parts[1].find("->")), "line");
          checks.print("line " + parts[0] + " in the FE zone (1 = yes)",
                       a[dim - 1] < zone[dim - 1],
                       1);
        }
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
