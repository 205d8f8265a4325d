// femp: laser absorption that follows the metal surface. Rays sampled over
// the beam's Gaussian profile travel down (-z in 3D, -y in 2D) into the
// current metal surface, the isosurface alpha = 1/2 of the cell-centred
// metal fraction (interpolated multilinearly), are partly absorbed there by
// the Fresnel relation for unpolarized light of the metal's complex
// refractive index n + i k at the laser wavelength, and reflected
// specularly with the rest of their power, until they leave the domain
// (escaping power) or carry less than a tiny part of their start power
// (which is then absorbed where they are); each hit's power is spread over
// the surface cells round it by its position along the surface. Every ray's
// power splits exactly into absorbed and escaping parts: their sum is P.
// The metal fraction round the beam is gathered onto every rank and each
// rank traces all rays, so the result does not depend on the partition.
// The fixed-absorptivity model of eq. (1) stays the default
// ('Laser/Absorption model = fixed'); see doc/absorption.md.
#ifndef femp_ray_traced_absorption_h
#define femp_ray_traced_absorption_h

#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/point.h>

#include <femp/base/parameter_table.h>
#include <femp/grid/background_grid.h>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace femp
{
  using namespace dealii;

  template <int dim>
  class RayTracedAbsorption
  {
  public:
    struct Parameters
    {
      /// 'fixed' (eq. 1, 'Laser/Absorptivity') or 'ray traced'.
      /// fixed: 'Absorptivity' times the beam's flux; ray traced: the
      /// Fresnel absorption of traced rays.
      enum class Model
      {
        fixed,
        ray_traced
      };
      Model        model                  = Model::fixed;
      double       refractive_index       = 3.83;
      double       extinction_coefficient = 5.34;
      unsigned int rays_per_beam_radius   = 4;
      unsigned int max_reflections        = 50;

      /// Entries of subsection Laser (declared beside Laser's own).
      /// Declare (the members' values are the defaults) or read the
      /// entries, each listed once.
      void
      add_parameters(ParameterTable &table);
      static void
      declare_parameters(ParameterHandler &prm);
      void
      parse_parameters(ParameterHandler &prm);
    };

    /// Global outcome of one trace (identical on all ranks), W (2D: W/m).
    struct Result
    {
      double       incident = 0, absorbed = 0, escaped = 0;
      unsigned int n_rays = 0, n_hits = 0;
    };

    RayTracedAbsorption(const Parameters &prm, const BackgroundGrid<dim> &grid);

    /// Fresnel absorptivity 1 - (R_s + R_p)/2 at incidence cos(theta).
    double
    fresnel_absorptivity(const double cos_theta) const;

    /// Trace a vertical Gaussian beam of power @p power and 1/e^2 radius
    /// @p beam_radius with its axis at @p axis (horizontal coordinates)
    /// into the metal fraction @p alpha (owned values and ghosts). Appends
    /// (owned local cell index, absorbed power W) to @p deposits. Collective.
    Result
    trace(const std::vector<double>                     &alpha,
          const Point<dim>                              &axis,
          const double                                   power,
          const double                                   beam_radius,
          std::vector<std::pair<std::uint32_t, double>> &deposits) const;

    const Parameters &
    parameters() const
    {
      return prm;
    }

  private:
    Parameters                 prm;
    const BackgroundGrid<dim> &grid;
  };
} // namespace femp

#endif
