// femp: input validation helpers and piecewise-linear property tables.
#include <deal.II/base/utilities.h>

#include <femp/base/input_checks.h>

#include <cmath>
#include <limits>

namespace femp
{
  InputError::InputError(const std::string &parameter,
                         const std::string &value,
                         const std::string &allowed)
      : std::runtime_error(
          "Invalid input: parameter '" + parameter + "' has the value '" +
          // A long value (a table, a list of bodies) is quoted in part.
          (value.size() <= 100 ?
             value :
             value.substr(0, 80) + " ... (" + std::to_string(value.size()) +
               " characters)") +
          "', but " + allowed + ".")
  {
  }

  PiecewiseLinear::PiecewiseLinear(const double constant)
      : T_{0.}
      , v_{constant}
  {
    seg.v0 = constant;
  }

  PiecewiseLinear
  PiecewiseLinear::parse(const std::string &text, const std::string &parameter)
  {
    const std::string allowed =
      "it must be a number or a list 'T1:v1, T2:v2, ...' of temperature (K) "
      ": value pairs with strictly increasing temperatures";
    PiecewiseLinear table;
    table.T_.clear();
    table.v_.clear();
    const auto entries =
      dealii::Utilities::split_string_list(dealii::Utilities::trim(text), ',');
    if (entries.empty())
      throw InputError(parameter, text, allowed);
    for (const auto &e : entries)
      {
        const auto parts = dealii::Utilities::split_string_list(e, ':');
        try
          {
            if (parts.size() == 1 && entries.size() == 1)
              {
                table.T_.push_back(0.);
                table.v_.push_back(
                  dealii::Utilities::string_to_double(parts[0]));
              }
            else if (parts.size() == 2)
              {
                table.T_.push_back(
                  dealii::Utilities::string_to_double(parts[0]));
                table.v_.push_back(
                  dealii::Utilities::string_to_double(parts[1]));
              }
            else
              throw InputError(parameter, text, allowed);
          }
        catch (const InputError &)
          {
            throw;
          }
        catch (...)
          {
            throw InputError(parameter, text, allowed);
          }
        if (table.T_.size() > 1 &&
            !(table.T_.back() > table.T_[table.T_.size() - 2]))
          throw InputError(parameter, text, allowed);
        if (!std::isfinite(table.v_.back()) || !std::isfinite(table.T_.back()))
          throw InputError(parameter, text, allowed);
      }
    table.seg.v0 = table.v_.front();
    table.seg.n  = table.T_.size() - 1;
    for (std::size_t i = 1; i < table.T_.size(); ++i)
      {
        table.inv_dT_.push_back(1. / (table.T_[i] - table.T_[i - 1]));
        if (i - 1 < max_segments)
          {
            table.seg.T[i - 1] = table.T_[i - 1];
            table.seg.w[i - 1] = table.T_[i] - table.T_[i - 1];
            table.seg.slope[i - 1] =
              (table.v_[i] - table.v_[i - 1]) * table.inv_dT_.back();
          }
      }
    return table;
  }

  double
  PiecewiseLinear::antiderivative(const double T) const
  {
    // Integral from T_.front() to T, with constant extension on both sides.
    if (T_.size() == 1 || T <= T_.front())
      return v_.front() * (T - T_.front());
    double sum = 0;
    for (std::size_t i = 1; i < T_.size(); ++i)
      {
        const double a = T_[i - 1];
        const double b = std::min(T, T_[i]);
        if (b <= a)
          break;
        const double vb = value(b);
        sum += 0.5 * (v_[i - 1] + vb) * (b - a);
        if (T <= T_[i])
          return sum;
      }
    return sum + v_.back() * (T - T_.back());
  }

  double
  PiecewiseLinear::integral(const double T0, const double T1) const
  {
    return antiderivative(T1) - antiderivative(T0);
  }

  double
  PiecewiseLinear::min_value() const
  {
    return *std::min_element(v_.begin(), v_.end());
  }

  double
  PiecewiseLinear::max_value() const
  {
    return *std::max_element(v_.begin(), v_.end());
  }

  template <int dim>
  dealii::Point<dim>
  parse_point(const std::string &text, const std::string &parameter)
  {
    const auto parts = dealii::Utilities::split_string_list(text, ',');
    if (parts.size() < static_cast<std::size_t>(dim))
      throw InputError(parameter, text, point_pattern_description(dim));
    dealii::Point<dim> p;
    try
      {
        for (int d = 0; d < dim; ++d)
          p[d] = dealii::Utilities::string_to_double(parts[d]);
      }
    catch (...)
      {
        throw InputError(parameter, text, point_pattern_description(dim));
      }
    return p;
  }

  std::string
  point_pattern_description(const int dim)
  {
    return "it must be a comma-separated list of " + std::to_string(dim) +
           " coordinates in m (further entries are ignored)";
  }

  template dealii::Point<1>
  parse_point<1>(const std::string &, const std::string &);
  template dealii::Point<2>
  parse_point<2>(const std::string &, const std::string &);
  template dealii::Point<3>
  parse_point<3>(const std::string &, const std::string &);
} // namespace femp
