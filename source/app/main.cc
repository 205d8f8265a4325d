// femp: command-line driver. `femp scene.prm` runs a scene; `--help` and
// `--print-parameters` document the input.
#include <deal.II/base/mpi.h>
#include <deal.II/base/parameter_handler.h>

#include <femp/app/femp_problem.h>
#include <femp/base/input_checks.h>

#include <cctype>
#include <fstream>
#include <iostream>

namespace
{
  void
  print_help(std::ostream &out)
  {
    out << "femp: laser powder bed fusion by the multi-physics finite "
           "element-material point method.\n\n"
           "Usage:\n"
           "  femp scene.prm              run the scene described in scene.prm\n"
           "  mpirun -np N femp scene.prm run it on N MPI ranks\n"
           "  femp --print-parameters     list every parameter with its "
           "default, allowed values, unit and meaning\n"
           "  femp --help                 this text\n\n"
           "Output goes to the directory set in 'Output/Directory' "
           "(default ./output): open grid.pvd and points.pvd in ParaView; "
           "melt_pool.csv, probe_points.csv and probe_line_*.csv hold the "
           "time series and line samples.\n";
  }
} // namespace


int
main(int argc, char *argv[])
{
  using namespace dealii;
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  const bool root = Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0;
  try
    {
      ParameterHandler prm;
      femp::declare_all_parameters(prm);
      if (argc != 2)
        {
          if (root)
            print_help(std::cerr);
          return 1;
        }
      const std::string arg = argv[1];
      if (arg == "--help" || arg == "-h")
        {
          if (root)
            print_help(std::cout);
          return 0;
        }
      if (arg == "--print-parameters")
        {
          if (root)
            prm.print_parameters(std::cout, ParameterHandler::OutputStyle(ParameterHandler::PRM | ParameterHandler::KeepDeclarationOrder));
          return 0;
        }
      {
        std::ifstream in(arg);
        femp::require(static_cast<bool>(in), "scene file (command line)", arg,
                      "the file does not exist or cannot be read");
      }
      try
        {
          prm.parse_input(arg);
        }
      catch (const std::exception &e)
        {
          std::string msg = e.what();
          // Keep deal.II's explanation, drop its stack-trace boilerplate.
          const auto pos = msg.find("Additional information:");
          if (pos != std::string::npos)
            msg = msg.substr(pos + 23);
          const auto trace = msg.find("Stacktrace:");
          if (trace != std::string::npos)
            msg = msg.substr(0, trace);
          // One line: collapse deal.II's line breaks and indentation.
          std::string flat;
          for (const char c : msg)
            if (!std::isspace(static_cast<unsigned char>(c)))
              flat += c;
            else if (!flat.empty() && flat.back() != ' ')
              flat += ' ';
          throw std::runtime_error("Invalid input in '" + arg + "': " +
                                   dealii::Utilities::trim(flat));
        }
      const int dim = prm.get_integer("Dimension");
      if (dim == 2)
        {
          femp::FempProblem<2> problem(prm, MPI_COMM_WORLD);
          problem.run();
        }
      else
        {
          femp::FempProblem<3> problem(prm, MPI_COMM_WORLD);
          problem.run();
        }
    }
  catch (const std::exception &e)
    {
      if (root)
        std::cerr << "femp: error: " << e.what() << std::endl;
      return 1;
    }
  return 0;
}
