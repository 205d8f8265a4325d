// femp: one place per parameter. A module lists each of its parameters once
// (name, member, pattern, help) in a function that takes a ParameterTable;
// the same list declares the parameters (the member's initial value is the
// default) and reads them back into the members. A choice among names is
// read into an enum class once, through its list of (value, name) pairs.
#ifndef femp_parameter_table_h
#define femp_parameter_table_h

#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/point.h>

#include <femp/base/input_checks.h>

#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace femp
{
  using namespace dealii;

  /// The names of an enum's values as they are written in the input.
  template <typename E>
  using Choices = std::vector<std::pair<E, std::string>>;

  /// The input name of @p value in @p choices.
  template <typename E>
  const std::string &
  choice_name(const E value, const Choices<E> &choices)
  {
    for (const auto &c : choices)
      if (c.first == value)
        return c.second;
    throw std::logic_error("femp: an enum value without a name");
  }

  /// A 'true|false|auto' switch: on, off, or decided from the scene.
  enum class AutoSwitch
  {
    on,
    off,
    automatic
  };

  /// A number as the shortest text that reads back to the same double,
  /// with a short exponent (3e-5, 2.68e5, 0.5).
  std::string
  number_text(const double x);

  class ParameterTable
  {
  public:
    enum class Mode
    {
      declare, ///< declare each entry with the member's value as default
      parse    ///< read each entry into its member
    };

    ParameterTable(ParameterHandler &prm, const Mode mode);

    bool
    declaring() const
    {
      return mode == Mode::declare;
    }

    ParameterHandler &
    handler()
    {
      return prm;
    }

    void
    enter_subsection(const std::string &name);
    void
    leave_subsection();

    /// "Section/Subsection/name", for messages.
    std::string
    path(const std::string &name) const;

    /// A number, integer, flag or text entry.
    void
    add(const std::string           &name,
        double                      &member,
        const Patterns::PatternBase &pattern,
        const std::string           &help);
    void
    add(const std::string           &name,
        unsigned int                &member,
        const Patterns::PatternBase &pattern,
        const std::string           &help);
    void
    add(const std::string           &name,
        int                         &member,
        const Patterns::PatternBase &pattern,
        const std::string           &help);
    void
    add(const std::string &name, bool &member, const std::string &help);
    void
    add(const std::string           &name,
        std::string                 &member,
        const Patterns::PatternBase &pattern,
        const std::string           &help);

    /// A point, written as its coordinates separated by commas.
    template <int dim>
    void
    add(const std::string &name, Point<dim> &member, const std::string &help)
    {
      if (declaring())
        {
          std::string text;
          for (int d = 0; d < dim; ++d)
            text += (d > 0 ? ", " : "") + number_text(member[d]);
          prm.declare_entry(name, text, Patterns::Anything(), help);
        }
      else
        member = parse_point<dim>(prm.get(name), path(name));
    }

    /// A choice among the names of @p choices (a Selection in the order
    /// given), read into an enum.
    template <typename E>
    void
    add(const std::string &name,
        E                 &member,
        const Choices<E>  &choices,
        const std::string &help)
    {
      static_assert(std::is_enum<E>::value || std::is_same<E, bool>::value,
                    "a choice is an enum or a flag");
      if (declaring())
        {
          std::string names;
          for (const auto &c : choices)
            names += (names.empty() ? "" : "|") + c.second;
          prm.declare_entry(name,
                            choice_name(member, choices),
                            Patterns::Selection(names),
                            help);
          return;
        }
      const std::string text = Utilities::trim(prm.get(name));
      for (const auto &c : choices)
        if (c.second == text)
          {
            member = c.first;
            return;
          }
      throw InputError(path(name), text, "it is not one of the choices");
    }

  private:
    ParameterHandler        &prm;
    const Mode               mode;
    std::vector<std::string> sections;
  };
} // namespace femp

#endif
