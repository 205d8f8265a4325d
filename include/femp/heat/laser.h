// femp: the Gaussian laser heat source q_laser of eq. (1) (ref. [12]) and
// its scan path. The beam is vertical (along -z in 3D, -y in 2D); its axis
// moves over the horizontal coordinates along a path of straight segments,
// each with its own speed and with the laser on or off. The absorbed flux
// density at horizontal distance r from the axis is
//   3D: q = 2 eta P / (pi r_b^2) exp(-2 r^2 / r_b^2)            (W/m^2)
//   2D: q = sqrt(2/pi) eta P / r_b exp(-2 r^2 / r_b^2), P in W/m (W/m^2)
// so that its integral over the surface plane is eta P.
#ifndef femp_laser_h
#define femp_laser_h

#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/point.h>

#include <femp/base/parameter_table.h>

#include <cmath>
#include <string>
#include <vector>

namespace femp
{
  using namespace dealii;

  /// The formats of 'Laser/Scan path file' (heat/scan_path.h).
  enum class ScanPathFormat
  {
    femp,
    adamantine_segment,
    adamantine_event_series,
    additivefoam
  };
  /// Their names in the input ('Laser/Scan path format').
  const Choices<ScanPathFormat> &
  scan_path_format_choices();

  template <int dim>
  class Laser
  {
  public:
    struct Segment
    {
      /// Last coordinate: the height of the layer for paths read in other
      /// formats (heat/scan_path.h), else 0; the beam deposits its energy
      /// where it meets the metal, whatever this height.
      Point<dim> start, end;
      double     speed; ///< m/s
      double     power; ///< W (3D) or W/m (2D); 0 = laser off
      double     t_begin, t_end;
    };

    struct Parameters
    {
      double         power        = 200.;
      double         absorptivity = 0.35;
      double         beam_radius  = 20e-6;
      double         scan_speed   = 2.;
      Point<dim>     start_point, end_point;
      double         start_time = 0.;
      std::string    scan_path_file;
      ScanPathFormat scan_path_format = ScanPathFormat::femp;

      /// Declare (the members' values are the defaults) or read the

      /// entries, each listed once.

      void

      add_parameters(ParameterTable &table);

      static void
      declare_parameters(ParameterHandler &prm);
      void
      parse_parameters(ParameterHandler &prm);
    };

    Laser(const Parameters &prm);

    /// Check that the path stays inside the horizontal extent of the box.
    void
    check_path_inside(const Point<dim> &lower, const Point<dim> &upper) const;

    /// True and the beam axis position if the laser is on at time @p t.
    bool
    position(const double t, Point<dim> &axis, double &power) const;

    /// Absorbed flux density (W/m^2) at horizontal offset squared @p r2 for
    /// laser power @p power.
    double
    flux(const double r2, const double power) const
    {
      const double a = prm.absorptivity * power;
      const double e = std::exp(-2. * r2 * inv_rb2);
      if (dim == 3)
        return 2. * a * inv_rb2 / M_PI * e;
      else
        return std::sqrt(2. / M_PI) * a / prm.beam_radius * e;
    }

    /// Absorbed flux (W/m^2, W/m in 2D) into the surface cell of centre
    /// @p c and width @p h for the beam axis at @p axis (horizontal
    /// coordinates). A beam at least as wide as the cell (r_b >= h) is
    /// sampled at the cell centre, flux(r2); a narrower one gives the
    /// average of the Gaussian over the cell's horizontal extent (a
    /// product of erf differences), so that the cells under it receive
    /// the whole absorbed power on a flat surface however narrow the beam
    /// is: point sampling would miss a beam that falls between centres.
    double
    cell_flux(const Point<dim> &c,
              const Point<dim> &axis,
              const double      power,
              const double      h) const
    {
      if (prm.beam_radius >= h)
        {
          double r2 = 0;
          for (int d = 0; d < dim - 1; ++d)
            r2 += (c[d] - axis[d]) * (c[d] - axis[d]);
          return flux(r2, power);
        }
      // (1/h) int exp(-2 u^2/r_b^2) du / (r_b sqrt(pi/2)/2) over the cell.
      const double s = std::sqrt(2.) / prm.beam_radius;
      double       f = prm.absorptivity * power;
      for (int d = 0; d < dim - 1; ++d)
        {
          const double u = c[d] - axis[d];
          f *= 0.5 *
               (std::erf(s * (u + 0.5 * h)) - std::erf(s * (u - 0.5 * h))) / h;
        }
      return f;
    }

    double
    beam_radius() const
    {
      return prm.beam_radius;
    }
    double
    absorptivity() const
    {
      return prm.absorptivity;
    }
    const std::vector<Segment> &
    segments() const
    {
      return path;
    }
    /// Time at which the last segment ends.
    double
    end_time() const
    {
      return path.empty() ? 0. : path.back().t_end;
    }

  private:
    Parameters           prm;
    double               inv_rb2;
    std::vector<Segment> path;
  };
} // namespace femp

#endif
