// femp: reading single entries of a parsed scene by their path
// (include/femp/base/parameter_lookup.h).
#include <deal.II/base/utilities.h>

#include <femp/base/parameter_lookup.h>

#include <vector>

namespace femp
{
  namespace
  {
    /// @p read(prm) in the subsection @p path ("A/B") of @p prm_in; only
    /// the handler's position changes, and it is restored after.
    template <typename Read>
    auto
    in_subsection(const ParameterHandler &prm_in,
                  const std::string      &path,
                  Read                  &&read)
    {
      auto      &prm      = const_cast<ParameterHandler &>(prm_in);
      const auto sections = path.empty() ?
                              std::vector<std::string>() :
                              Utilities::split_string_list(path, '/');
      for (const auto &s : sections)
        prm.enter_subsection(s);
      const auto v = read(prm);
      for (std::size_t i = 0; i < sections.size(); ++i)
        prm.leave_subsection();
      return v;
    }
  } // namespace

  std::string
  parameter_text(const ParameterHandler &prm,
                 const std::string      &path,
                 const std::string      &name)
  {
    return in_subsection(prm, path, [&](ParameterHandler &p) {
      return p.get(name);
    });
  }

  double
  parameter_double(const ParameterHandler &prm,
                   const std::string      &path,
                   const std::string      &name)
  {
    return Utilities::string_to_double(parameter_text(prm, path, name));
  }

  bool
  parameter_bool(const ParameterHandler &prm,
                 const std::string      &path,
                 const std::string      &name)
  {
    return in_subsection(prm, path, [&](ParameterHandler &p) {
      return p.get_bool(name);
    });
  }

} // namespace femp
