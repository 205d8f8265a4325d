// femp tests: run a whole scene from a prm file through FempProblem.
#ifndef femp_scene_driver_h
#define femp_scene_driver_h

#include <femp/app/femp_problem.h>
#include <femp/base/parameter_file.h>

#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace femp_test
{
  /// One parameter set on top of a scene file.
  struct Override
  {
    std::string section, entry, value;
  };

  /// Declare every parameter in @p prm, parse @p file and apply
  /// @p overrides ({subsection, entry, value}).
  inline void
  parse_scene(dealii::ParameterHandler    &prm,
              const std::string           &file,
              const std::vector<Override> &overrides)
  {
    femp::declare_all_parameters(prm);
    // 'include' lines relative to the scene's folder, as femp reads them.
    femp::parse_parameter_file(prm, file);
    // A section "A/B" is subsection B of A.
    for (const auto &[section, entry, value] : overrides)
      {
        unsigned int depth = 0;
        for (std::size_t a = 0;; ++depth)
          {
            const std::size_t b = section.find('/', a);
            prm.enter_subsection(section.substr(a, b - a));
            if (b == std::string::npos)
              break;
            a = b + 1;
          }
        prm.set(entry, value);
        for (unsigned int d = 0; d <= depth; ++d)
          prm.leave_subsection();
      }
  }

  /// Parse @p file, apply @p overrides ({subsection, entry, value}), and run
  /// the scene with std::cout silenced; returns the summary.
  template <int dim>
  typename femp::FempProblem<dim>::Summary
  run_scene(const std::string           &file,
            MPI_Comm                     comm,
            const std::vector<Override> &overrides = {})
  {
    dealii::ParameterHandler prm;
    parse_scene(prm, file, overrides);
    std::streambuf *old = std::cout.rdbuf();
    std::ofstream   log("scene.log");
    std::cout.rdbuf(log.rdbuf());
    auto problem = std::make_unique<femp::FempProblem<dim>>(prm, comm);
    femp::run_to_end(problem, prm, comm);
    std::cout.rdbuf(old);
    return problem->summary();
  }

  /// Columns of a CSV file written by femp: lines starting with '#' are
  /// skipped, the first other line names the columns; returns name ->
  /// values ("inf" read as infinity).
  inline std::map<std::string, std::vector<double>>
  read_csv_columns(const std::string &file)
  {
    std::ifstream in(file);
    AssertThrow(in, dealii::ExcMessage("cannot read " + file));
    std::string                                row;
    std::vector<std::string>                   names;
    std::map<std::string, std::vector<double>> columns;
    while (std::getline(in, row))
      {
        if (row.empty() || row[0] == '#')
          continue;
        const auto v = dealii::Utilities::split_string_list(row, ',');
        if (names.empty())
          {
            names = v;
            continue;
          }
        for (std::size_t i = 0; i < names.size() && i < v.size(); ++i)
          columns[names[i]].push_back(
            v[i] == "inf" ? std::numeric_limits<double>::infinity() :
                            dealii::Utilities::string_to_double(v[i]));
      }
    return columns;
  }
} // namespace femp_test

#endif
