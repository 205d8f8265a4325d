// femp: command-line driver. `femp [--set Section/Name=value ...] scene.prm`
// runs a scene; `--help` and `--print-parameters[=json]` document the input.
//
// Errors: everything that can be refused is refused before any work, on
// every rank together (the ranks agree on a failure flag, the lowest failing
// rank prints one message, all exit with status 1). An error during the run
// that every rank meets together (a CollectiveError: a non-finite field, a
// step above its limit) is printed once and all ranks exit with status 1;
// any other error during the run (a file that cannot be written, a solver
// failure) is printed by the rank that meets it, which then ends every rank
// with MPI_Abort, so that no rank waits forever in a collective operation
// (doc/input_errors.md).
#include <deal.II/base/exceptions.h>
#include <deal.II/base/mpi.h>
#include <deal.II/base/parameter_handler.h>

#include <femp/app/femp_problem.h>
#include <femp/app/physical_bounds.h>
#include <femp/app/run_checks.h>
#include <femp/base/collective_error.h>
#include <femp/base/input_checks.h>
#include <femp/base/parameter_file.h>
#include <femp/base/progress_watchdog.h>

#include <cctype>
#include <chrono>
#include <fstream>
#include <iostream>
#include <memory>
#include <thread>

namespace
{
  void
  print_help(std::ostream &out)
  {
    out
      << "femp: laser powder bed fusion by the multi-physics finite "
         "element-material point method.\n\n"
         "Usage:\n"
         "  femp [options] scene.prm    run the scene described in scene.prm\n"
         "  mpirun -np N femp scene.prm run it on N MPI ranks\n"
         "  femp --print-parameters     list every parameter with its "
         "default, allowed values, unit and meaning (prm format)\n"
         "  femp --print-parameters=json  the same as JSON\n"
         "  femp --help                 this text\n\n"
         "Options:\n"
         "  --set 'Section/Name=value'  override one parameter of the scene "
         "(repeatable;\n"
         "                              nested subsections: "
         "'A/B/Name=value')\n"
         "  --resume DIR                continue from the checkpoint in "
         "DIR (doc/checkpoint.md;\n"
         "                              the same as --set "
         "'Checkpoint/Resume from=DIR')\n\n"
         "Output goes to the directory set in 'Output/Directory' "
         "(default ./output): open grid.pvd and points.pvd (grid.xdmf and "
         "points.xdmf with 'Output/Format = hdf5') in ParaView; "
         "melt_pool.csv, probe_points.csv and probe_line_*.csv hold the "
         "time series and line samples; parameters.prm the parameters "
         "used. Errors in the input are reported before any work, with "
         "exit status 1 (doc/input_errors.md).\n";
  }

  /// For an entry that an older femp declared elsewhere, where it is now
  /// (appended to deal.II's "No entry with name <...>" message).
  std::string
  moved_parameter_hint(const std::string &msg)
  {
    static const std::pair<const char *, const char *> moved[] = {
      {"Gravity",
       "'Melt flow/Gravity' and 'Solid/Gravity' are now the one "
       "'Physics/Gravity' (magnitude in m/s^2, acting along -y in 2D, -z in "
       "3D; 0 for none)"},
      {"Latent heat of evaporation",
       "'Heat transfer/Latent heat of evaporation' is now 'Material/Latent "
       "heat of evaporation'"},
      {"Evaporation temperature",
       "'Heat transfer/Evaporation temperature' is now 'Material/Evaporation "
       "temperature'"},
      {"Molar mass", "'Heat transfer/Molar mass' is now 'Material/Molar mass'"},
      {"Ambient pressure",
       "'Heat transfer/Ambient pressure' is now 'Material/Ambient pressure'"}};
    for (const auto &m : moved)
      if (msg.find("No entry with name <" + std::string(m.first) + ">") !=
          std::string::npos)
        return std::string(" (") + m.second + ")";
    return "";
  }

  /// One line of an exception's message: deal.II's explanation without its
  /// boilerplate and stack trace.
  std::string
  clean_message(const std::exception &e)
  {
    std::string msg = e.what();
    if (dynamic_cast<const dealii::ExceptionBase *>(&e) != nullptr)
      {
        const auto pos = msg.find("Additional information:");
        if (pos != std::string::npos)
          msg = msg.substr(pos + 23);
        const auto trace = msg.find("Stacktrace:");
        if (trace != std::string::npos)
          msg = msg.substr(0, trace);
      }
    std::string flat;
    for (const char c : msg)
      if (!std::isspace(static_cast<unsigned char>(c)))
        flat += c;
      else if (!flat.empty() && flat.back() != ' ')
        flat += ' ';
    while (!flat.empty() && flat.back() == ' ')
      flat.pop_back();
    return flat;
  }

  /// A --set override: "A/B/Name=value" as prm text.
  std::string
  override_as_prm(const std::string &text)
  {
    const auto eq = text.find('=');
    femp::require(eq != std::string::npos && eq > 0,
                  "--set (command line)",
                  femp::short_value(text),
                  "it must read 'Section/Name=value' (nested subsections: "
                  "'A/B/Name=value'; top-level parameters: 'Name=value')");
    const auto path =
      dealii::Utilities::split_string_list(text.substr(0, eq), '/');
    std::string prm_text;
    for (std::size_t i = 0; i + 1 < path.size(); ++i)
      prm_text += "subsection " + path[i] + "\n";
    prm_text += "set " + path.back() + " = " + text.substr(eq + 1) + "\n";
    for (std::size_t i = 0; i + 1 < path.size(); ++i)
      prm_text += "end\n";
    return prm_text;
  }

  /// Parse the scene file and the overrides; errors as one-line messages.
  void
  read_input(dealii::ParameterHandler       &prm,
             const std::string              &scene,
             const std::vector<std::string> &overrides)
  {
    femp::check_scene_file(scene);
    try
      {
        // .prm scenes: 'include' paths relative to the scene's folder
        // first (so a scene runs from any folder); JSON and XML as deal.II
        // reads them.
        const bool structured =
          scene.size() > 5 && (scene.substr(scene.size() - 5) == ".json" ||
                               scene.substr(scene.size() - 4) == ".xml");
        if (structured)
          prm.parse_input(scene);
        else
          femp::parse_parameter_file(prm, scene);
      }
    catch (const std::exception &e)
      {
        const std::string msg = clean_message(e);
        throw std::runtime_error("Invalid input in '" + scene + "': " + msg +
                                 moved_parameter_hint(msg));
      }
    for (const auto &o : overrides)
      {
        const std::string text = override_as_prm(o);
        try
          {
            prm.parse_input_from_string(text);
          }
        catch (const std::exception &e)
          {
            const std::string msg = clean_message(e);
            throw std::runtime_error("Invalid input in --set '" +
                                     femp::short_value(o) + "': " + msg +
                                     moved_parameter_hint(msg));
          }
      }
  }

  /// The problem of either dimension.
  struct Problem
  {
    std::unique_ptr<femp::FempProblem<2>> p2;
    std::unique_ptr<femp::FempProblem<3>> p3;
  };

  /// What the command line asks for: the scene, its --set and --resume
  /// overrides, and whether it was a request that is answered on the spot
  /// (--help, --print-parameters: nothing to run).
  struct CommandLine
  {
    std::string              scene;
    std::vector<std::string> overrides;
    bool                     answered = false;
  };

  /// --print-parameters[=prm|=json] (@p arg): every parameter of @p prm
  /// on std::cout, in declaration order.
  void
  print_parameters(dealii::ParameterHandler &prm, const std::string &arg)
  {
    using dealii::ParameterHandler;
    prm.print_parameters(std::cout,
                         ParameterHandler::OutputStyle(
                           (arg == "--print-parameters=json" ?
                              ParameterHandler::JSON :
                              ParameterHandler::PRM) |
                           ParameterHandler::KeepDeclarationOrder));
  }

  /// Reads the command line, in order: --help and --print-parameters are
  /// answered at once (on rank 0, @p root), the others collected; a bad
  /// argument throws an InputError naming it.
  CommandLine
  parse_command_line(const int                 argc,
                     char                     *argv[],
                     dealii::ParameterHandler &prm,
                     const bool                root)
  {
    CommandLine cl;
    for (int i = 1; i < argc; ++i)
      {
        const std::string arg = argv[i];
        if (arg == "--help" || arg == "-h")
          {
            if (root)
              print_help(std::cout);
            cl.answered = true;
          }
        else if (arg == "--print-parameters" ||
                 arg == "--print-parameters=prm" ||
                 arg == "--print-parameters=json")
          {
            if (root)
              print_parameters(prm, arg);
            cl.answered = true;
          }
        else if (arg == "--set" || arg.rfind("--set=", 0) == 0)
          {
            if (arg == "--set")
              {
                femp::require(i + 1 < argc,
                              "--set (command line)",
                              "",
                              "it needs an argument 'Section/Name=value'");
                cl.overrides.push_back(argv[++i]);
              }
            else
              cl.overrides.push_back(arg.substr(6));
          }
        else if (arg == "--resume" || arg.rfind("--resume=", 0) == 0)
          {
            // The same as --set 'Checkpoint/Resume from=DIR'.
            std::string dir;
            if (arg == "--resume")
              {
                femp::require(i + 1 < argc,
                              "--resume (command line)",
                              "",
                              "it needs a checkpoint directory");
                dir = argv[++i];
              }
            else
              dir = arg.substr(9);
            cl.overrides.push_back("Checkpoint/Resume from=" + dir);
          }
        else if (arg.size() > 1 && arg[0] == '-')
          femp::require(false,
                        "command line",
                        femp::short_value(arg),
                        "it is not an option of femp; the options are "
                        "--set 'Section/Name=value', --resume DIR, "
                        "--print-parameters[=json] and --help");
        else
          {
            femp::require(cl.scene.empty(),
                          "command line",
                          femp::short_value(arg),
                          "only one scene file may be given (the first was '" +
                            femp::short_value(cl.scene) + "')");
            cl.scene = arg;
          }
      }
    return cl;
  }

  /// Phase 1 on this rank: the command line, the input and every check,
  /// then the problem of the scene's dimension. Returns 0 (run), 1 (error,
  /// its one-line message in @p error) or 2 (done: help or listing).
  int
  set_up(const int                 argc,
         char                     *argv[],
         const MPI_Comm            comm,
         dealii::ParameterHandler &prm,
         Problem                  &problem,
         std::string              &error)
  {
    const bool root = dealii::Utilities::MPI::this_mpi_process(comm) == 0;
    try
      {
        femp::declare_all_parameters(prm);
        femp::declare_run_limits(prm);
        const CommandLine cl = parse_command_line(argc, argv, prm, root);
        if (cl.answered)
          return 2;
        if (cl.scene.empty())
          {
            if (root)
              print_help(std::cerr);
            throw std::runtime_error("no scene file given");
          }
        read_input(prm, cl.scene, cl.overrides);
        femp::check_output_file_names(prm);
        femp::check_values(prm);
        femp::check_physical_relations(prm);
        femp::check_step_floors(prm);
        femp::check_number_magnitudes(prm);
        femp::check_memory(prm, dealii::Utilities::MPI::n_mpi_processes(comm));
        femp::check_disk(prm);
        if (prm.get_integer("Dimension") == 2)
          problem.p2 = std::make_unique<femp::FempProblem<2>>(prm, comm);
        else
          problem.p3 = std::make_unique<femp::FempProblem<3>>(prm, comm);
        femp::prepare_output_directory(prm, comm);
        return 0;
      }
    catch (const std::exception &e)
      {
        error = clean_message(e);
        return 1;
      }
  }

  /// The ranks agree on a failure of phase 1 (@p status 1 on some rank):
  /// the lowest failing rank prints its @p error. True if any rank failed.
  bool
  report_set_up_failure(const int          status,
                        const std::string &error,
                        const MPI_Comm     comm)
  {
    const unsigned int rank    = dealii::Utilities::MPI::this_mpi_process(comm);
    const unsigned int n_ranks = dealii::Utilities::MPI::n_mpi_processes(comm);
    const unsigned int first_failed =
      dealii::Utilities::MPI::min(status == 1 ? rank : n_ranks, comm);
    if (first_failed < n_ranks && rank == first_failed)
      std::cerr << "femp: error: " << error << std::endl;
    return first_failed < n_ranks;
  }

  /// An error of the run met by this rank alone (not a CollectiveError):
  /// printed by this rank, then (several ranks) every rank is ended with
  /// MPI_Abort so that none waits in a collective operation. Returns the
  /// exit status (1).
  int
  abort_run(const std::exception &e, const MPI_Comm comm)
  {
    const unsigned int rank    = dealii::Utilities::MPI::this_mpi_process(comm);
    const unsigned int n_ranks = dealii::Utilities::MPI::n_mpi_processes(comm);
    const bool         root    = rank == 0;
    if (!root)
      {
        // If rank 0 fails too (the same error everywhere), let it speak.
        std::this_thread::sleep_for(std::chrono::milliseconds(500));
      }
    std::cerr << "femp: error"
              << (root ? std::string() : " (rank " + std::to_string(rank) + ")")
              << ": " << clean_message(e) << std::endl;
    std::cerr.flush();
    std::cout.flush();
    if (n_ranks > 1)
      MPI_Abort(comm, 1);
    return 1;
  }

  /// Phase 2: the run, with its rebalances (each a fresh problem that
  /// resumes the rebalance's checkpoint, made from @p prm). Returns the
  /// exit status; an error on one rank ends every rank.
  int
  run(Problem &problem, dealii::ParameterHandler &prm, const MPI_Comm comm)
  {
    try
      {
        if (problem.p2)
          femp::run_to_end(problem.p2, prm, comm);
        else
          femp::run_to_end(problem.p3, prm, comm);
      }
    catch (const femp::CollectiveError &e)
      {
        // Every rank stops here with the same message: print it once and
        // end normally (no MPI_Abort, whose banner would bury the message).
        std::cout.flush();
        if (dealii::Utilities::MPI::this_mpi_process(comm) == 0)
          std::cerr << "femp: error: " << clean_message(e) << std::endl;
        return 1;
      }
    catch (const std::exception &e)
      {
        return abort_run(e, comm);
      }
    return 0;
  }
} // namespace

int
main(int argc, char *argv[])
{
  dealii::Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  const MPI_Comm                           comm = MPI_COMM_WORLD;

  // Phase 1: command line, input and every check, on all ranks. A failure
  // on any rank ends all of them here, with one message.
  dealii::ParameterHandler prm;
  Problem                  problem;
  std::string              error;
  const int status = set_up(argc, argv, comm, prm, problem, error);
  if (report_set_up_failure(status, error, comm))
    return 1;
  if (status == 2)
    return 0;

  // Phase 2: the run. An error on one rank ends every rank. A line at
  // least every 30 s of wall time, whatever the run is doing.
  prm.enter_subsection("Run limits");
  femp::progress::start(comm, prm.get_double("Progress wall interval"));
  prm.leave_subsection();
  const int result = run(problem, prm, comm);
  femp::progress::stop();
  return result;
}
