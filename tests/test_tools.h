// femp tests: small helpers shared by the test programs. A verification test
// computes its reference, prints each error with its tolerance, and returns
// a non-zero exit code when one is exceeded.
#ifndef femp_test_tools_h
#define femp_test_tools_h

#include <deal.II/base/mpi.h>

#include <femp/base/material.h>
#include <femp/grid/background_grid.h>
#include <femp/heat/heat_transfer.h>
#include <femp/heat/laser.h>

#include <cmath>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

namespace femp_test
{
  using namespace dealii;
  using namespace femp;

  /// Collects pass/fail of checks; prints on rank 0 only.
  class Checks
  {
  public:
    explicit Checks(MPI_Comm comm)
        : root(Utilities::MPI::this_mpi_process(comm) == 0)
    {
    }
    /// Print "what = value" rounded to @p digits significant digits.
    void
    print(const std::string &what, const double value, const int digits = 4)
    {
      if (root)
        std::cout << what << " = " << std::setprecision(digits) << value
                  << std::endl;
    }
    /// Check value <= tolerance; print both.
    void
    at_most(const std::string &what, const double value, const double tolerance)
    {
      const bool ok = value <= tolerance && std::isfinite(value);
      failures += !ok;
      if (root)
        std::cout << what << " = " << std::setprecision(2) << value
                  << " (tolerance " << tolerance << ") "
                  << (ok ? "ok" : "FAILED") << std::endl;
    }
    /// Check lower <= value <= upper; print both.
    void
    in_range(const std::string &what,
             const double       value,
             const double       lower,
             const double       upper)
    {
      const bool ok = value >= lower && value <= upper;
      failures += !ok;
      if (root)
        std::cout << what << " = " << std::setprecision(3) << value
                  << " (allowed [" << lower << ", " << upper << "]) "
                  << (ok ? "ok" : "FAILED") << std::endl;
    }
    int
    exit_code() const
    {
      if (root)
        std::cout << (failures == 0 ? "all checks passed" : "CHECKS FAILED")
                  << std::endl;
      return failures == 0 ? 0 : 1;
    }

  private:
    bool root;
    int  failures = 0;
  };

  /// Material with all properties 1 and no phase change in [0, 1e6] K
  /// unless solidus/liquidus are set.
  inline Material
  unit_material()
  {
    Material m;
    m.density            = 1;
    m.specific_heat      = PiecewiseLinear(1.);
    m.conductivity       = PiecewiseLinear(1.);
    m.solidus            = 1e6;
    m.liquidus           = 2e6;
    m.latent_heat_fusion = 0;
    m.gas_density        = 0;
    m.gas_specific_heat  = 0;
    m.gas_conductivity   = 0;
    return m;
  }

  /// Heat-transfer parameters without any surface loss.
  inline typename HeatTransfer<3>::Parameters
  no_losses()
  {
    HeatTransfer<3>::Parameters p;
    p.convection_coefficient  = 0;
    p.emissivity              = 0;
    p.evaporation_coefficient = 0;
    return p;
  }

  template <int dim>
  typename HeatTransfer<dim>::Parameters
  heat_parameters(const double T0, const std::map<std::string, double> &fixed)
  {
    typename HeatTransfer<dim>::Parameters p;
    p.initial_temperature     = T0;
    p.reference_temperature   = T0;
    p.convection_coefficient  = 0;
    p.emissivity              = 0;
    p.evaporation_coefficient = 0;
    p.fixed_temperatures      = fixed;
    return p;
  }

  template <int dim>
  typename BackgroundGrid<dim>::Parameters
  box(const Point<dim> &lo, const Point<dim> &hi, const double h)
  {
    typename BackgroundGrid<dim>::Parameters p;
    p.lower_corner = lo;
    p.upper_corner = hi;
    p.cell_size    = h;
    return p;
  }

  /// A laser that never switches on.
  template <int dim>
  typename Laser<dim>::Parameters
  laser_off()
  {
    typename Laser<dim>::Parameters p;
    p.power      = 0;
    p.start_time = 1e30;
    return p;
  }
} // namespace femp_test

#endif
