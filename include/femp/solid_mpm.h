// femp: SolidMPM<dim>, the explicit material point method for the fusible
// solid (paper eqs. 11-13, METHOD sec. 4).
//
// Points of state 'solid' outside the finite-element zone take part. Their
// state is copied from the ParticleHandler into flat arrays (structure of
// arrays) at the start of a solid advance and written back at its end, so
// that the hot loops touch no iterator. Transfers use trilinear (bilinear in
// 2D) tent functions of the cell that holds the point; node indices come
// from index arithmetic on the background grid (first node of the cell plus
// fixed corner offsets).
//
// Update variant: MUSL (modified update stress last), with the central
// difference of eq. (10):
//   1. P2G of mass, momentum and forces (eqs. 11-13):
//        m_I = sum N m_p, p_I = sum N m_p v_p,
//        f_I = -sum V_p sigma_p grad N + sum N m_p g (+ fluid forces);
//   2. p_I += dt f_I on the grid (with boundary conditions);
//   3. G2P: v_p += dt sum N f_I / m_I (FLIP), x_p += dt sum N p_I / m_I;
//   4. P2G of the new point momentum, v_I = p_I / m_I;
//   5. velocity gradient L_p = sum v_I (x) grad N and stress update (eq. 5).
// MUSL is chosen over USF/USL because the stress is computed from velocities
// re-mapped from the updated points: nodes with a tiny mass share of a point
// do not produce spurious strain rates (the classic USL instability), and it
// is the variant whose energy behaviour is best documented for explicit MPM.
// The extra P2G of momentum costs about a sixth of a step.
// The forces use sigma_p + q_p I, with the artificial bulk-viscosity
// pressure q_p = b1 rho c h tr(D) of the last stress update (see
// SolidMaterial::bulk_viscosity), stored with the point.
//
// Points move with the solid velocity. They are not re-sorted into cells:
// thermal-stress displacements are far below a cell (case 3.1: ~1e-3 h), so
// every point stays in its cell; if one leaves its cell, the run stops with
// a message naming the point position (moving points across cells is part of
// the melt-flow work).
#ifndef femp_solid_mpm_h
#define femp_solid_mpm_h

#include <deal.II/base/tensor.h>

#include <femp/background_grid.h>
#include <femp/constitutive.h>
#include <femp/material_points.h>

#include <array>
#include <vector>

namespace femp
{
  using namespace dealii;

  /// Node fields of the solid on the background grid (local node box).
  template <int dim>
  struct SolidNodeFields
  {
    std::vector<double>                 mass;
    std::array<std::vector<double>, dim> momentum, force, velocity;

    void
    resize(const std::size_t n)
    {
      mass.assign(n, 0.);
      for (int d = 0; d < dim; ++d)
        {
          momentum[d].assign(n, 0.);
          force[d].assign(n, 0.);
          velocity[d].assign(n, 0.);
        }
    }
  };

  template <int dim>
  class SolidMPM
  {
  public:
    SolidMPM(const BackgroundGrid<dim> &grid,
             const SolidMaterial &      material,
             MaterialPoints<dim> &      points);

    /// Copy the state of the solid points that lie in cells with
    /// @p excluded_cell[idx] == 0 into the flat arrays. Inertial masses are
    /// multiplied by @p mass_scaling (gravity uses the true mass).
    void
    gather(const std::vector<std::uint8_t> &excluded_cell,
           const double                      mass_scaling);
    /// Write positions, velocities, stresses and plastic strains back to
    /// the particles.
    void
    scatter();

    /// Step 1: add point mass, momentum and forces (internal and gravity) to
    /// the node fields (partial sums of this rank).
    void
    p2g(SolidNodeFields<dim> &nodes, const Tensor<1, dim> &gravity) const;
    /// Step 3: FLIP velocity update from nodal accelerations (stored in
    /// nodes.force as f_I / m_I) and position update from node velocities.
    /// Returns false if a point left its cell (see header comment).
    bool
    g2p(const SolidNodeFields<dim> &nodes, const double dt);
    /// Step 4: add point momentum to nodes.momentum (partial sums).
    void
    p2g_momentum(SolidNodeFields<dim> &nodes) const;
    /// Step 5: stress update from node velocities; @p T_old and @p T_new are
    /// cell temperatures at the start and end of the step. Returns the
    /// stress work sum V sigma : D dt of this rank.
    double
    update_stresses(const SolidNodeFields<dim> &nodes,
                    const double                dt,
                    const std::vector<double> & T_old,
                    const std::vector<double> & T_new);

    /// Kinetic energy of this rank's points, J (2D: J/m).
    double
    kinetic_energy() const;
    /// Work of gravity in a step of @p dt at the current velocities.
    double
    gravity_power(const Tensor<1, dim> &gravity) const;
    /// Number of points taking part (this rank).
    std::size_t
    n_points() const
    {
      return mass.size();
    }
    /// Mean sigma_xx and number of points in cell @p idx (this rank).
    std::pair<double, unsigned int>
    cell_stress_xx(const std::size_t idx) const;
    /// Add sigma_xx and the von Mises stress of every point to its cell
    /// (sums) and count the points per cell.
    void
    add_cell_stresses(std::vector<double> &sxx,
                      std::vector<double> &vm,
                      std::vector<double> &count) const;
    /// Position of the first point with a non-finite state, if any.
    bool
    find_non_finite(Point<dim> &where) const;
    /// Position of a point that left its cell in the last g2p().
    const Point<dim> &
    escaped_point() const
    {
      return escaped;
    }

  private:
    const BackgroundGrid<dim> &grid;
    const SolidMaterial &      mat;
    MaterialPoints<dim> &      points;
    static constexpr unsigned int n_corners = 1u << dim;
    std::array<std::ptrdiff_t, n_corners> corner_offset;

    // Structure of arrays.
    std::vector<std::array<double, dim>>            x, v, corner;
    std::vector<double>                             mass, true_mass, volume;
    std::vector<double>                             visc; ///< viscous pressure q, Pa
    std::vector<std::uint32_t>                      cell, node0;
    std::vector<StressPoint>                        stress;
    std::vector<typename Particles::ParticleHandler<dim>::particle_iterator>
      handle;
    Point<dim> escaped;

    /// Tent weights and gradients of point @p p.
    void
    shape(const std::size_t p, double *N, double (*dN)[dim]) const;
  };
} // namespace femp

#endif
