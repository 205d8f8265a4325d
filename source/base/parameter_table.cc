// femp: one place per parameter: the declaring and reading table
// (include/femp/base/parameter_table.h).
#include <femp/base/parameter_table.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace femp
{
  namespace
  {
    /// "3e-05" -> "3e-5", "2.68e+05" -> "2.68e5".
    std::string
    short_exponent(const std::string &text)
    {
      const std::size_t e = text.find('e');
      if (e == std::string::npos)
        return text;
      std::string exponent = text.substr(e + 1);
      std::string sign;
      if (exponent[0] == '-' || exponent[0] == '+')
        {
          sign     = exponent[0] == '-' ? "-" : "";
          exponent = exponent.substr(1);
        }
      exponent.erase(0, exponent.find_first_not_of('0'));
      return text.substr(0, e + 1) + sign + exponent;
    }

    /// An integer entry of type I (int, unsigned int) of @p table.
    template <typename I>
    void
    add_integer(ParameterTable              &table,
                const std::string           &name,
                I                           &member,
                const Patterns::PatternBase &pattern,
                const std::string           &help)
    {
      if (table.declaring())
        table.handler().declare_entry(name,
                                      std::to_string(member),
                                      pattern,
                                      help);
      else
        member = table.handler().get_integer(name);
    }
  } // namespace

  std::string
  number_text(const double x)
  {
    // The fewest significant digits that read back to x: plain between
    // 1e-3 and 1e6 (unless the exponent form is three characters
    // shorter), with an exponent elsewhere.
    char buffer[64];
    int  digits = 1;
    for (; digits < 17; ++digits)
      {
        std::snprintf(buffer, sizeof(buffer), "%.*e", digits - 1, x);
        if (std::strtod(buffer, nullptr) == x)
          break;
      }
    std::snprintf(buffer, sizeof(buffer), "%.*e", digits - 1, x);
    const std::string exponent = short_exponent(buffer);
    if (x == 0 || std::abs(x) >= 1e16 || std::abs(x) < 1e-6)
      return x == 0 ? "0" : exponent;
    const int power = static_cast<int>(std::floor(std::log10(std::abs(x))));
    std::snprintf(
      buffer, sizeof(buffer), "%.*f", std::max(0, digits - 1 - power), x);
    const std::string plain       = buffer;
    const bool        plain_range = std::abs(x) >= 1e-3 && std::abs(x) < 1e6;
    return plain_range && exponent.size() + 3 > plain.size() ? plain : exponent;
  }

  ParameterTable::ParameterTable(ParameterHandler &prm, const Mode mode)
      : prm(prm)
      , mode(mode)
  {
  }

  void
  ParameterTable::enter_subsection(const std::string &name)
  {
    prm.enter_subsection(name);
    sections.push_back(name);
  }

  void
  ParameterTable::leave_subsection()
  {
    prm.leave_subsection();
    sections.pop_back();
  }

  std::string
  ParameterTable::path(const std::string &name) const
  {
    std::string p;
    for (const auto &s : sections)
      p += s + "/";
    return p + name;
  }

  void
  ParameterTable::add(const std::string           &name,
                      double                      &member,
                      const Patterns::PatternBase &pattern,
                      const std::string           &help)
  {
    if (declaring())
      prm.declare_entry(name, number_text(member), pattern, help);
    else
      member = prm.get_double(name);
  }

  void
  ParameterTable::add(const std::string           &name,
                      unsigned int                &member,
                      const Patterns::PatternBase &pattern,
                      const std::string           &help)
  {
    add_integer(*this, name, member, pattern, help);
  }

  void
  ParameterTable::add(const std::string           &name,
                      int                         &member,
                      const Patterns::PatternBase &pattern,
                      const std::string           &help)
  {
    add_integer(*this, name, member, pattern, help);
  }

  void
  ParameterTable::add(const std::string &name,
                      bool              &member,
                      const std::string &help)
  {
    if (declaring())
      prm.declare_entry(name,
                        member ? "true" : "false",
                        Patterns::Bool(),
                        help);
    else
      member = prm.get_bool(name);
  }

  void
  ParameterTable::add(const std::string           &name,
                      std::string                 &member,
                      const Patterns::PatternBase &pattern,
                      const std::string           &help)
  {
    if (declaring())
      prm.declare_entry(name, member, pattern, help);
    else
      member = prm.get(name);
  }
} // namespace femp
