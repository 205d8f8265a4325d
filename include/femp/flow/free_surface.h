// femp: the free surface of the melt flow (paper sec. 2.3, eq. 3: the
// surface tension, Marangoni and recoil terms; doc/flow.md).
//
// From the metal points near the fluid it computes the smoothed metal
// fraction alpha (point volume mapped to the nodes with tent weights,
// divided by h^dim, averaged to the cell centres), the interface position
// theta on each face between a fluid and a gas cell (where alpha, linear
// between the two centres, is 1/2), and, when switched on,
//  - the capillary pressure p_s = sigma div(n) of the surface cells
//    (n = -grad alpha/|grad alpha| at the cell's nodes, div(n) at its
//    centre), the sharp-interface form of the CSF term sigma kappa n
//    |grad alpha| of eq. (3), optionally averaged along the surface
//    (Melt flow/Curvature smoothing);
//  - the recoil pressure zeta_p p0 exp[L_v M (T - T_v)/(R T T_v)] added to
//    p_s, from the cell's temperature limited to its surface neighbours'
//    (or the cell's own, or their median: Melt flow/Recoil temperature),
//    or its part above the ambient pressure p0 (Melt flow/Recoil above
//    ambient);
//  - the Marangoni traction dsigma/dT (grad T - (n.grad T) n) on the
//    fluid-gas faces, weighted by |n_d|, spread to the face nodes, with
//    dsigma/dT constant or, with the surfactant model, at the surface
//    cell's temperature (SurfaceTension).
// IncompressibleFlow imposes p_s as the Dirichlet pressure at the interface
// (ghost-fluid method, see PressureSolver) and adds the nodal Marangoni
// forces in its predictor.
#ifndef femp_free_surface_h
#define femp_free_surface_h

#include <deal.II/base/parameter_handler.h>

#include <femp/base/material.h>
#include <femp/base/parameter_table.h>
#include <femp/flow/flow_cells.h>
#include <femp/flow/surface_tension.h>
#include <femp/grid/background_grid.h>
#include <femp/grid/material_points.h>

#include <array>
#include <cstdint>
#include <vector>

namespace femp
{
  using namespace dealii;

  template <int dim>
  class FreeSurface
  {
  public:
    struct Parameters
    {
      double surface_tension          = 0; ///< sigma, N/m (0: off)
      double surface_tension_gradient = 0; ///< dsigma/dT, N/(m K)
      /// The law of dsigma/dT (Melt flow/Surface tension model): the
      /// constant surface_tension_gradient, or the surfactant model with
      /// the constants of Melt flow/Surfactant.
      SurfaceTension::Model surface_tension_model =
        SurfaceTension::Model::linear;
      SurfaceTension::Surfactant surfactant;
      double recoil_coefficient = 0; ///< zeta_p (0: no recoil)
      /// Which surface temperature the recoil pressure of a surface cell
      /// takes (Melt flow/Recoil temperature).
      enum class RecoilTemperature
      {
        median,  ///< median over the surface cells of the 3^dim stencil
        limited, ///< the cell's own, limited to its surface neighbours'
        cell     ///< the cell's own
      };
      RecoilTemperature recoil_temperature = RecoilTemperature::limited;
      /// Whether the surface pressure takes the recoil net of the ambient
      /// pressure, max(0, zeta_p p_sat(T) - p0) (Melt flow/Recoil above
      /// ambient; the default), instead of zeta_p p_sat(T).
      bool recoil_above_ambient = true;
      /// Passes of the curvature smoothing along the surface (0: none).
      unsigned int curvature_smoothing = 0;
      /// How the curvature is computed: from the divergence of alpha's
      /// normalized gradient, or from heights of alpha in columns of 7
      /// cells.
      enum class Curvature
      {
        alpha_gradient,
        height_function
      };
      Curvature curvature = Curvature::alpha_gradient;

      /// The free-surface entries of the subsection Melt flow (the caller
      /// has entered it): Curvature, Curvature smoothing, Surface tension,
      /// Surface tension temperature derivative, Surface tension model (and
      /// the subsection Surfactant), Recoil coefficient, Recoil temperature,
      /// Recoil above ambient.
      static void
      declare_parameters(ParameterHandler &prm);
      /// Declare or read these entries, each from its member.
      void
      add_parameters(ParameterTable &table);
      /// Read them (inside Melt flow) and check their ranges.
      void
      parse_parameters(ParameterHandler &prm);
      /// Whether any surface force is on (surface tension, Marangoni or
      /// recoil).
      bool
      any() const
      {
        return surface_tension > 0 || marangoni() || recoil_coefficient > 0;
      }
      /// The law of dsigma/dT of the Marangoni stress.
      SurfaceTension
      surface_tension_law() const
      {
        return SurfaceTension(surface_tension_model,
                              surface_tension_gradient,
                              surfactant);
      }
      /// Whether the Marangoni stress is on.
      bool
      marangoni() const
      {
        return surface_tension_law().marangoni();
      }
    };

    /// The recoil pressure takes the evaporation data of @p material.
    FreeSurface(const Parameters          &prm,
                const Material            &material,
                const BackgroundGrid<dim> &grid,
                const MaterialPoints<dim> &points);

    /// Everything of the surface for the current cell classes @p type
    /// (flow_cells::Type per cell of the local box, ghosts current) and the
    /// owned fluid cells @p fluid_cells: near-fluid marks, alpha, theta and
    /// (when on) p_s and the Marangoni nodal forces. @p T: the cell
    /// temperature (ghost values needed), K, for the Marangoni stress and
    /// the recoil pressure; required when either is switched on.
    void
    update(const std::vector<double>        &type,
           const std::vector<std::uint32_t> &fluid_cells,
           const std::vector<double>        *T);

    /// 1 on the cells within one cell of a fluid cell (ghosts exchanged),
    /// 0 elsewhere: where alpha_cell() is computed, and the band of the
    /// pressure system.
    const std::vector<double> &
    near_fluid() const
    {
      return near1;
    }
    /// Smoothed metal fraction at the nodes (near the fluid).
    const std::vector<double> &
    alpha_at_nodes() const
    {
      return alpha_node;
    }
    /// Smoothed metal fraction at the centres of the near_fluid() cells
    /// (ghosts exchanged).
    const std::vector<double> &
    alpha_at_cells() const
    {
      return alpha_cell;
    }
    /// Interface distance / h from the fluid cell centre, per face 2d+side
    /// of the fluid cells with a gas neighbour there (1/2 elsewhere; ghosts
    /// exchanged), in [theta_min, 1].
    const std::array<std::vector<double>, 2 * dim> &
    interface_position() const
    {
      return theta;
    }
    /// p_s = capillary + recoil pressure of the surface cells (ghosts
    /// exchanged), Pa; zero elsewhere or when no surface term is on.
    const std::vector<double> &
    surface_pressure() const
    {
      return p_surface;
    }
    /// The capillary part sigma div(n) of surface_pressure() (after its
    /// smoothing; owned surface cells), Pa: the recoil pressure of a
    /// surface cell is surface_pressure() minus this.
    const std::vector<double> &
    capillary_pressure() const
    {
      return p_capillary;
    }
    /// Marangoni force per node, N (2D: N/m), summed over ranks; zero when
    /// the Marangoni stress is off.
    const std::array<std::vector<double>, dim> &
    marangoni_force() const
    {
      return surface_force;
    }
    /// Nodal alpha at the corners of @p cell, doubled per direction at
    /// nodes on the domain boundary (where the node sum saw only half of
    /// its cells): the mirror-wall value.
    std::array<double, (1u << dim)>
    corner_alpha(const std::size_t cell) const;
    /// Per cell of the local box (ghosts exchanged), 1 where the surface
    /// boils and the recoil drives the melt: a surface cell among
    /// @p fluid_cells whose recoil pressure exceeds both zeta_p p0 (the
    /// saturation pressure exceeds the ambient one, T_s > T_v) and the
    /// magnitude of its capillary pressure; 0 elsewhere. Collective.
    void
    mark_recoil_driven(const std::vector<std::uint32_t> &fluid_cells,
                       std::vector<double>              &driven) const;

    static constexpr double theta_min = 0.05;

  private:
    /// near1/near2: cells within one/two cells of a fluid cell.
    void
    mark_near_fluid(const std::vector<double> &type);
    /// alpha_node from the points of the near2 cells, alpha_cell at the
    /// owned near1 cells.
    void
    map_metal_fraction();
    /// theta on the fluid-gas faces.
    void
    locate_interface(const std::vector<double>        &type,
                     const std::vector<std::uint32_t> &fluid_cells);
    /// Column sums of alpha along each direction for the height-function
    /// curvature: col3[d] (3 cells) on the owned near2 cells and col5[d]
    /// (5 cells) on the owned near1 cells, with ghosts; NaN where a
    /// column meets a cell whose alpha is not known (a non-gas cell beyond
    /// near1, or outside the domain). Two ghost exchanges per direction
    /// stand in for the three-cell reach that the one-cell ghost layer
    /// does not have.
    void
    height_columns(const std::vector<double> &type);
    /// div(n) of the surface cell @p c from the heights of the 7-cell
    /// columns along the largest component of its outward normal @p n
    /// through c and its 3^(dim-1) - 1 neighbours across; NaN where a
    /// column is not known or does not cross the surface.
    double
    height_function_curvature(const std::size_t c, const double *n) const;
    /// Capillary pressure of the surface cells, and their Marangoni
    /// traction.
    void
    capillary_and_marangoni(const std::vector<double>        &type,
                            const std::vector<std::uint32_t> &fluid_cells,
                            const std::vector<double>        *temperature);
    /// Add the recoil pressure of the surface cells to p_s, from their
    /// surface temperature (Parameters::recoil_temperature).
    void
    add_recoil_pressure(const std::vector<std::uint32_t> &fluid_cells,
                        const std::vector<double>        *temperature);
    /// Average the capillary part of p_s over neighbouring surface cells
    /// (Melt flow/Curvature smoothing passes).
    void
    smooth_capillary_pressure(const std::vector<std::uint32_t> &fluid_cells);

    const Parameters           prm;
    const SurfaceTension       tension; // dsigma/dT of the Marangoni stress
    const Material            &mat;
    const BackgroundGrid<dim> &grid;
    const MaterialPoints<dim> &points;

    static constexpr unsigned int         n_corners = 1u << dim;
    std::array<std::ptrdiff_t, n_corners> corner_offset; // node offsets
    std::array<std::ptrdiff_t, n_corners> around_offset; // cells round a node
    std::vector<std::ptrdiff_t>           stencil;       // 3^dim neighbourhood

    std::vector<double>                      near1, near2; // 0/1
    std::vector<double>                      alpha_node, alpha_cell;
    std::array<std::vector<double>, dim>     col3, col5; // height function
    std::array<std::vector<double>, 2 * dim> theta;
    std::vector<double>                      p_surface;
    std::vector<double> p_capillary, surface_mark;      // sigma div(n), 0/1
    std::array<std::vector<double>, dim> surface_force; // Marangoni, N
  };
} // namespace femp

#endif
