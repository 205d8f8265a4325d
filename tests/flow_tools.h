// femp tests: a small flow scene (grid, fluid material points, the
// incompressible flow solver) for the melt-flow verification tests.
#ifndef femp_flow_tools_h
#define femp_flow_tools_h

#include <femp/flow/incompressible_flow.h>
#include <femp/grid/material_points.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>

#include "test_tools.h"

namespace femp_test
{
  /// The recoil pressure zeta_p p0 exp[L_v M (T - T_v)/(R T T_v)] of the
  /// scenes' material (the defaults' evaporation data) at temperature @p T,
  /// Pa: the closed form the recoil tests compare with.
  template <int dim>
  double
  recoil_pressure(const typename IncompressibleFlow<dim>::Parameters &prm,
                  const double                                        T)
  {
    const Material m;
    const double   R = 8.314462618;
    const double   p = prm.recoil_coefficient * m.ambient_pressure *
                     std::exp(m.latent_heat_evaporation * m.molar_mass *
                              (T - m.evaporation_temperature) /
                              (R * T * m.evaporation_temperature));
    // Melt flow/Recoil above ambient: net of the ambient pressure.
    return prm.recoil_above_ambient ? std::max(0., p - m.ambient_pressure) : p;
  }

  template <int dim>
  struct FlowScene
  {
    /// Box [0, size] with cells of size h, a fluid body where @p inside is
    /// true, points at spacing h/2, density rho.
    FlowScene(const Point<dim>                                   &size,
              const double                                        h,
              const double                                        rho,
              const std::function<bool(const Point<dim> &)>      &inside,
              const typename IncompressibleFlow<dim>::Parameters &flow_prm,
              MPI_Comm                                            comm)
        : grid(box<dim>(Point<dim>(), size, h), comm)
    {
      material         = unit_material();
      material.density = rho;
      grid.create();
      points_prm.point_spacing   = h / 2;
      points_prm.subcells        = 2;
      points_prm.layer_thickness = 0;
      points =
        std::make_unique<MaterialPoints<dim>>(points_prm, material, grid);
      points->create_region(inside, 300., MaterialPoints<dim>::fluid);
      flow = std::make_unique<IncompressibleFlow<dim>>(flow_prm,
                                                       material,
                                                       grid,
                                                       *points);
    }

    /// Maximum over fluid points of f(point), over all ranks.
    double
    max_over_points(
      const std::function<double(const Point<dim> &, ArrayView<const double>)>
        &f) const
    {
      double m = -1e300;
      for (const auto &p : points->particle_handler())
        m = std::max(m, f(p.get_location(), p.get_properties()));
      return Utilities::MPI::max(m, grid.communicator());
    }

    /// Mean pressure of the cells whose centre lies within @p r of
    /// @p centre, over all ranks (collective), Pa.
    double
    mean_pressure_within(const Point<dim> &centre, const double r) const
    {
      const auto &p    = flow->pressure();
      double      s[2] = {0, 0};
      for (const auto idx : grid.owned_cells())
        if (grid.cell_center(idx).distance(centre) < r)
          s[0] += p[idx], s[1] += 1;
      Utilities::MPI::sum(ArrayView<const double>(s, 2),
                          grid.communicator(),
                          ArrayView<double>(s, 2));
      return s[0] / s[1];
    }

    Material                                 material;
    BackgroundGrid<dim>                      grid;
    typename MaterialPoints<dim>::Parameters points_prm;
    std::unique_ptr<MaterialPoints<dim>>     points;
    std::unique_ptr<IncompressibleFlow<dim>> flow;
  };

  /// Speed of a point from its properties.
  template <int dim>
  double
  point_speed(ArrayView<const double> v)
  {
    double s = 0;
    for (int d = 0; d < dim; ++d)
      {
        const double u = v[MaterialPoints<dim>::PropertyIndex::velocity + d];
        s += u * u;
      }
    return std::sqrt(s);
  }

  /// The 2D oscillating droplet of tests/oscillating_droplet.cc and
  /// tests/flow_forced_step.cc: a drop r = R (1 + eps cos 2 theta) of
  /// R = 0.25 m, rho = 1000 kg/m^3, surface tension sigma = 1 N/m, in the
  /// middle of a box of 4 R, cells of R / @p R_over_h, no gravity; the
  /// viscosity and the other solver settings come with @p prm (gravity and
  /// surface tension are set here).
  struct Droplet
  {
    static constexpr double R = 0.25, rho = 1000, sigma = 1;

    Droplet(const double                               R_over_h,
            const double                               eps,
            typename IncompressibleFlow<2>::Parameters prm,
            MPI_Comm                                   comm)
        : scene(make(R_over_h, eps, prm, comm))
        , omega(std::sqrt(6 * sigma / (rho * R * R * R)))
        , gamma(4 * prm.viscosity / rho / (R * R))
    {
    }

    /// Period of the damped mode 2, 2 pi / sqrt(omega^2 - gamma^2), s.
    double
    period() const
    {
      return 2 * numbers::PI / std::sqrt(omega * omega - gamma * gamma);
    }

    std::unique_ptr<FlowScene<2>> scene;
    /// Mode-2 frequency sqrt(6 sigma / (rho R^3)) and viscous decay rate
    /// 4 mu / (rho R^2), 1/s.
    const double omega, gamma;

  private:
    static std::unique_ptr<FlowScene<2>>
    make(const double                                R_over_h,
         const double                                eps,
         typename IncompressibleFlow<2>::Parameters &prm,
         MPI_Comm                                    comm)
    {
      const double   L = 4 * R;
      const Point<2> centre(0.5 * L, 0.5 * L);
      prm.gravity         = Tensor<1, 2>();
      prm.surface_tension = sigma;
      return std::make_unique<FlowScene<2>>(
        Point<2>(L, L),
        R / R_over_h,
        rho,
        [&](const Point<2> &x) {
          const Tensor<1, 2> d = x - centre;
          const double       c2 =
            (d[0] * d[0] - d[1] * d[1]) / std::max(1e-300, d.norm_square());
          return d.norm() < R * (1 + eps * c2);
        },
        prm,
        comm);
    }
  };

  /// Shape measure S = (xx - yy) / (xx + yy) of the points about their
  /// centre of mass, xx and yy the variances of x and y (collective): 0
  /// for a circle, the sign tells which axis is the longer.
  template <int dim>
  double
  shape_measure(const FlowScene<dim> &scene, MPI_Comm comm)
  {
    double s[5] = {0, 0, 0, 0, 0}; // n, sum x, sum y, sum x^2, sum y^2
    for (const auto &p : scene.points->particle_handler())
      {
        const auto x = p.get_location();
        s[0] += 1, s[1] += x[0], s[2] += x[1], s[3] += x[0] * x[0],
          s[4] += x[1] * x[1];
      }
    Utilities::MPI::sum(ArrayView<const double>(s, 5),
                        comm,
                        ArrayView<double>(s, 5));
    const double xx = s[3] / s[0] - std::pow(s[1] / s[0], 2);
    const double yy = s[4] / s[0] - std::pow(s[2] / s[0], 2);
    return (xx - yy) / (xx + yy);
  }
} // namespace femp_test

#endif
