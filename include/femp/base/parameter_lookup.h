// femp: reading single entries of a parsed scene by their path, for the
// checks that look at a few entries of several modules before any module
// reads its own (physical_bounds, run_checks); a module reads its entries
// through its ParameterTable (parameter_table.h).
#ifndef femp_parameter_lookup_h
#define femp_parameter_lookup_h

#include <deal.II/base/parameter_handler.h>

#include <femp/base/input_checks.h>
#include <femp/base/parameter_table.h>

#include <string>

namespace femp
{
  /// The entry @p name of the subsection @p path ("A/B"; "" for the top
  /// level) of @p prm: as text, as a number, as a flag, as a choice of
  /// @p choices. For the checks that read a few entries of several
  /// modules before any module reads its own.
  std::string
  parameter_text(const ParameterHandler &prm,
                 const std::string      &path,
                 const std::string      &name);
  double
  parameter_double(const ParameterHandler &prm,
                   const std::string      &path,
                   const std::string      &name);
  bool
  parameter_bool(const ParameterHandler &prm,
                 const std::string      &path,
                 const std::string      &name);
  template <typename E>
  E
  parameter_choice(const ParameterHandler &prm,
                   const std::string      &path,
                   const std::string      &name,
                   const Choices<E>       &choices)
  {
    const std::string text = Utilities::trim(parameter_text(prm, path, name));
    for (const auto &c : choices)
      if (c.second == text)
        return c.first;
    throw InputError(path + "/" + name, text, "it is not one of the choices");
  }

} // namespace femp

#endif
