// femp tests: the set-up shared by the 2D solid block tests (a substrate
// block of material points on the background grid, the elastic-plastic
// test material, the finite-element zone, the supports and a prescribed
// hot spot), as tests/flow_tools.h does for the flow tests.
#ifndef femp_solid_tools_h
#define femp_solid_tools_h

#include <femp/grid/material_points.h>
#include <femp/solid/solid_sub_cycle.h>

#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "test_tools.h"

namespace femp_test
{
  /// Box [0, size] with cells of size h; solid material points (@p n_per_h
  /// per cell and direction, spacing h / n_per_h, as many sub-cells for the
  /// metal fraction) filling it up to y = @p top, at @p T0, of @p material
  /// (the grid is created first, then the points).
  template <int dim>
  struct SolidBlock
  {
    SolidBlock(const Point<dim> &size,
               const double      h,
               const double      top,
               const Material   &material,
               MPI_Comm          comm,
               const double      T0      = 300.,
               const unsigned    n_per_h = 2)
        : grid(box<dim>(Point<dim>(), size, h), comm)
        , material(material)
    {
      grid.create();
      typename MaterialPoints<dim>::Parameters pp;
      pp.point_spacing   = h / n_per_h;
      pp.substrate_top   = top;
      pp.layer_thickness = 0;
      pp.subcells        = n_per_h;
      points = std::make_unique<MaterialPoints<dim>>(pp, this->material, grid);
      points->create(T0);
    }

    BackgroundGrid<dim>                  grid;
    Material                             material;
    std::unique_ptr<MaterialPoints<dim>> points;
  };

  /// Rebuild the points of @p block (cells of size @p h, 2 x 2 points per
  /// cell) as its substrate up to @p top plus one solid body at 300 K
  /// filling the box [@p a, @p b] (a drop or a fragment).
  template <int dim>
  void
  add_solid_box(SolidBlock<dim>  &block,
                const double      h,
                const double      top,
                const Point<dim> &a,
                const Point<dim> &b)
  {
    typename MaterialPoints<dim>::Parameters pp;
    pp.point_spacing   = h / 2;
    pp.substrate_top   = top;
    pp.layer_thickness = 0;
    pp.subcells        = 2;
    typename MaterialPoints<dim>::Parameters::Body body;
    body.state = MaterialPoints<dim>::solid;
    body.box   = true;
    body.a     = a;
    body.b     = b;
    body.T     = 300;
    pp.bodies  = {body};
    block.points =
      std::make_unique<MaterialPoints<dim>>(pp, block.material, block.grid);
    block.points->create(300.);
  }

  /// The elastic-plastic block material: E = 100 Pa, hardening 5 Pa,
  /// yield stress table @p yield (T:sigma_y), alpha = 1e-4 1/K; density and
  /// solidus those of @p thermal (the block's material); Poisson ratio as
  /// SolidMaterial's default unless set by the caller.
  inline SolidMaterial
  block_material(const std::string &yield, const Material &thermal)
  {
    SolidMaterial sm(thermal);
    sm.youngs_modulus  = PiecewiseLinear(100.);
    sm.plastic_modulus = PiecewiseLinear(5.);
    sm.yield_stress    = PiecewiseLinear::parse(yield, "yield");
    sm.expansion       = 1e-4;
    return sm;
  }

  /// The linear-elastic block material of the stability tests: E = 100 Pa,
  /// nu = 0.3, no plasticity (yield stress 1e30 Pa), no thermal expansion;
  /// density and solidus those of @p thermal.
  inline SolidMaterial
  elastic_block_material(const Material &thermal)
  {
    SolidMaterial sm(thermal);
    sm.youngs_modulus  = PiecewiseLinear(100.);
    sm.plastic_modulus = PiecewiseLinear(0.);
    sm.yield_stress    = PiecewiseLinear(1e30);
    sm.poisson_ratio   = 0.3;
    sm.expansion       = 0;
    return sm;
  }

  /// A finite-element zone over the box [@p lower, @p upper], femp's
  /// defaults otherwise.
  template <int dim>
  typename SolidFEM<dim>::Parameters
  fe_zone(const Point<dim> &lower, const Point<dim> &upper)
  {
    typename SolidFEM<dim>::Parameters fp;
    fp.enabled      = true;
    fp.lower_corner = lower;
    fp.upper_corner = upper;
    return fp;
  }

  /// A finite-element zone (on when @p enabled) covering [0, @p size], with
  /// hourglass coefficient @p kappa and hourglass distortion limit
  /// @p distortion_limit (femp's default unless given).
  template <int dim>
  typename SolidFEM<dim>::Parameters
  fe_block(const bool        enabled,
           const Point<dim> &size,
           const double      kappa,
           const double      distortion_limit =
             typename SolidFEM<dim>::Parameters().hourglass_distortion_limit)
  {
    auto fp                       = fe_zone(Point<dim>(), size);
    fp.enabled                    = enabled;
    fp.hourglass_coefficient      = kappa;
    fp.hourglass_distortion_limit = distortion_limit;
    return fp;
  }

  /// Prescribed cell temperatures of a hot spot in a 2D block: at the
  /// centre x of each owned cell of @p grid, T = 300 K + @p rise
  /// exp(-|x - @p centre|^2 / @p spread) (@p spread in m^2).
  inline void
  hot_spot(const BackgroundGrid<2> &grid,
           const Point<2>          &centre,
           const double             rise,
           const double             spread,
           std::vector<double>     &T)
  {
    for (const auto c : grid.owned_cells())
      {
        const Point<2> x = grid.cell_center(c);
        T[c] =
          300 + rise * std::exp(-((x[0] - centre[0]) * (x[0] - centre[0]) +
                                  (x[1] - centre[1]) * (x[1] - centre[1])) /
                                spread);
      }
  }

  /// Supports of the blocks: bottom fixed, sides on rollers; no energy
  /// file.
  template <int dim>
  typename SolidSubCycle<dim>::Parameters
  block_supports()
  {
    typename SolidSubCycle<dim>::Parameters sp;
    sp.fixed_faces  = {"y-"};
    sp.roller_faces = {"x-", "x+"};
    sp.energy_file  = "";
    return sp;
  }

  /// The hand-over block of the FE-zone tests: a 1.6 m x 0.8 m block of
  /// 0.1 m cells (2D), its FE zone below y = 0.2 m, gravity 0.01 m/s^2, an
  /// elastic-plastic material (yield 0.02 Pa at 300 K, 0.005 Pa at 400 K,
  /// Poisson 0.3) and a hot spot at (0.8, 0.3) whose rise above 300 K
  /// (K) at time t (s) is @p rise(t). Not initialized: the caller calls
  /// solid->initialize() (or resumes a checkpoint first).
  struct HandoverBlock
  {
    HandoverBlock(MPI_Comm comm, std::function<double(double)> rise)
        : block(Point<2>(1.6, 0.8), h, 0.8, unit_material(), comm)
        , sm(block_material("300:0.02, 400:0.005", block.material))
        , spot_rise(std::move(rise))
    {
      sm.poisson_ratio = 0.3;
      auto sp          = block_supports<2>();
      sp.gravity[1]    = -0.01;
      const auto fp    = fe_zone(Point<2>(0, 0), Point<2>(1.6, 0.2));
      solid            = std::make_unique<SolidSubCycle<2>>(
        sp, fp, sm, block.grid, *block.points);
      T = block.grid.make_field(300.);
    }
    /// Advance through the temperature steps s0 + 1 ... s1 (0.05 s each).
    void
    run(const int s0, const int s1)
    {
      for (int s = s0 + 1; s <= s1; ++s)
        {
          const double t = 0.05 * s;
          hot_spot(block.grid, Point<2>(0.8, 0.3), spot_rise(t), 0.05, T);
          solid->advance(t, T, s == s1);
        }
    }
    static constexpr double           h = 0.1;
    SolidBlock<2>                     block;
    SolidMaterial                     sm; ///< reads block.material
    std::function<double(double)>     spot_rise;
    std::unique_ptr<SolidSubCycle<2>> solid;
    std::vector<double>               T;
  };
} // namespace femp_test

#endif
