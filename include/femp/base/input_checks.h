// femp: input validation helpers and piecewise-linear property tables.
//
// Every physically impossible or inconsistent input is reported through
// InputError, whose message names the parameter (with its subsection path),
// the value that was given and what is allowed. main() prints it and exits
// with a non-zero status before any computation starts.
#ifndef femp_input_checks_h
#define femp_input_checks_h

#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/point.h>

#include <array>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace femp
{
  /// An error in the user's input. what() is a complete, user-facing message.
  class InputError : public std::runtime_error
  {
  public:
    InputError(const std::string &parameter,
               const std::string &value,
               const std::string &allowed);
  };

  /// A number for a message, with 6 significant digits (like %g).
  inline std::string
  num(const double x)
  {
    std::ostringstream s;
    s << x;
    return s.str();
  }

  /// Throw InputError unless @p condition holds.
  template <typename T>
  void
  require(const bool         condition,
          const std::string &parameter,
          const T           &value,
          const std::string &allowed)
  {
    if (!condition)
      {
        std::ostringstream s;
        s.precision(10);
        s << value;
        throw InputError(parameter, s.str(), allowed);
      }
  }

  /**
   * A property given as a piecewise-linear function of temperature, read from
   * a string "T1:v1, T2:v2, ..." (K : value, T strictly increasing) or a
   * single number for a constant. Outside the first and last breakpoints the
   * end values are held constant. The antiderivative is available for exact
   * enthalpy bookkeeping.
   */
  class PiecewiseLinear
  {
  public:
    PiecewiseLinear(const double constant = 0.);

    /// Parse @p text; @p parameter names the prm entry in error messages.
    static PiecewiseLinear
    parse(const std::string &text, const std::string &parameter);

    double
    value(const double T) const
    {
      if (T_.size() == 1 || T <= T_.front())
        return v_.front();
      if (T >= T_.back())
        return v_.back();
      std::size_t i = 1;
      while (T > T_[i])
        ++i;
      const double w = (T - T_[i - 1]) * inv_dT_[i - 1];
      return v_[i - 1] + w * (v_[i] - v_[i - 1]);
    }

    /// Integral of the property from @p T0 to @p T1 (exact for the table).
    double
    integral(const double T0, const double T1) const;

    /// Same as value(), without branches: v_0 + sum_i s_i clamp(T - T_i, 0,
    /// T_{i+1} - T_i), so that loops over cells vectorize.
    /// Tables of up to max_segments segments can be evaluated without
    /// branches, v_0 + sum_i s_i clamp(T - T_i, 0, w_i), so that loops over
    /// cells vectorize; a local copy of Segments avoids aliasing with the
    /// arrays the loop writes.
    static constexpr unsigned int max_segments = 8;
    struct Segments
    {
      double                           v0 = 0;
      std::array<double, max_segments> T{}, w{}, slope{}; // padded: slope 0
      unsigned int                     n = 0;             ///< segments in use
      /// Evaluate with the first N segments (N >= n).
      template <unsigned int N = max_segments>
      double
      eval(const double x) const
      {
        double v = v0;
#pragma GCC unroll 8
        for (unsigned int i = 0; i < N; ++i)
          {
            const double d = x - T[i];
            v += slope[i] * (d < 0 ? 0. : (d > w[i] ? w[i] : d));
          }
        return v;
      }
      double
      operator()(const double x) const
      {
        return eval<max_segments>(x);
      }
    };
    /// True if segments() may be used (at most max_segments).
    bool
    has_padded_segments() const
    {
      return T_.size() <= max_segments + 1;
    }
    /// Requires has_padded_segments().
    Segments
    segments() const
    {
      return seg;
    }

    /// Integral of the property from the first breakpoint to @p T.
    double
    antiderivative(const double T) const;

    /// True if the table has a single value.
    bool
    is_constant() const
    {
      return v_.size() == 1;
    }

    double
    min_value() const;
    double
    max_value() const;

  private:
    std::vector<double> T_, v_, inv_dT_;
    Segments            seg;
  };

  /// Parse a comma-separated list of dim numbers into a point.
  template <int dim>
  dealii::Point<dim>
  parse_point(const std::string &text, const std::string &parameter);

  /// Pattern for a list of exactly @p dim coordinates.
  std::string
  point_pattern_description(const int dim);
} // namespace femp

#endif
