// femp: SolidMPM<dim>, the explicit material point method for the fusible
// solid (paper eqs. 11-13, doc/method.md, "Solid").
//
// Points of state 'solid' outside the finite-element zone take part. Their
// state is copied from the ParticleHandler into flat arrays (structure of
// arrays, SolidPointStore, solid_point_store.h) at the start of a solid
// advance and written back at its end, so that the hot loops touch no
// iterator; SolidMPM is the step on that store, its vectorised kernels are
// in mpm_kernels.h. Transfers use trilinear (bilinear in
// 2D) tent functions of the cell that holds the point; node indices come
// from index arithmetic on the background grid (first node of the cell plus
// fixed corner offsets).
//
// Update variant: MUSL (modified update stress last), with the central
// difference of eq. (10):
//   1. P2G of mass, momentum and forces (eqs. 11-13):
//        m_I = sum N m_p, p_I = sum N m_p v_p(x_I),
//        f_I = -sum V_p sigma_p grad N + sum N m_p g (+ fluid forces);
//      with the melt flow also the stiffness row sums of the light-node
//      mass floor, r_I = sum m_p h |grad N_I| h sum_J |grad N_J|
//      (set_stiffness_rows(), doc/solid.md "Small node masses");
//   2. p_I += dt f_I on the grid (with boundary conditions);
//   3. G2P of the new point velocity, then (same loop)
//   4. P2G of the new point momentum (re-map), v_I = p_I / m_I;
//   5. velocity gradient L_p = sum v_I (x) grad N and stress update (eq. 5);
//      then the point moves, x_p += dt sum N v_I (grid velocities of 2).
// All transfers of a step use the tents at the point's position at the
// start of the step (the textbook MUSL): the re-map then divides by the node
// masses of the same weights. (Re-mapping with the weights at the moved
// position, as this code did before, gives nodes at a free surface that a
// point leaves a momentum that does not match their mass.)
// MUSL is chosen over USF/USL because the stress is computed from velocities
// re-mapped from the updated points: nodes with a tiny mass share of a point
// do not produce spurious strain rates (the classic USL instability), and it
// is the variant whose energy behaviour is best documented for explicit MPM.
//
// Velocity transfer ("Solid/Velocity transfer"):
//   FLIP: v_p += dt sum N a_I, point velocity field v_p(x_I) = v_p;
//   APIC (default; Jiang et al. 2015): v_p = sum N v_I,
//         C_p = sum v_I (x) grad N (the B D^-1 form of APIC equals this for
//         multilinear tents), v_p(x_I) = v_p + C_p (x_I - x_p).
// With one point per cell and linear tents, APIC gives back the nodal
// velocities exactly in the next P2G (for any point position in the cell),
// so the MPM wave operator is that of the lumped-mass one-point FE; FLIP
// smooths the nodal velocities by (1/4 1/2 1/4) in every round trip, which
// made case 3.1 dispersive (doc/solid.md). The point kinetic energy of APIC
// includes the affine part, 1/2 m_p (|v_p|^2 + C_p : C_p D_p), D_p = sum N
// (x_I - x_p)(x_I - x_p)^T = diag(h^2 xi_d (1 - xi_d)), the kinetic energy
// the point hands to the grid.
//
// Speed: two passes over the points per step when sub-cycling: G2P + MUSL
// re-map (steps 3-4), and the stress update (5) + move fused with the P2G
// (1) of the next step, whose node sums wait in a buffer of SolidMPM until
// p2g() hands them over (the P2G of a point needs only that point's state
// after its stress update, so the fusion changes no arithmetic). The first
// step after a gather() runs a separate P2G pass. Flat arrays per component,
// node indices by the first node of the cell plus fixed corner offsets, tent
// weights recomputed from the local coordinate in registers (a cache of
// 2^dim (dim + 1) weights per point would cost more memory traffic than the
// few multiplications). G2P and the velocity gradient of the stress update
// evaluate the multilinear interpolant of the nodal velocities in monomial
// form, with coefficients computed once per cell (the points are sorted by
// cell), instead of summing tents times nodal values (the same polynomial:
// equal up to round-off). The point arrays are prefetched a few points
// ahead. Kinetic energy and gravity power are summed in the stress loop.
//
// The forces use sigma_p + q_p I, with the artificial bulk-viscosity
// pressure q_p = b1 rho c h tr(D) of the last stress update (see
// SolidMaterial::bulk_viscosity), stored with the point.
//
// Cell crossing: after the stress update a point that left its cell is
// bound to its new cell when that cell is owned by this rank (flat arrays
// only; the ParticleHandler is updated by MaterialPoints::relocate_points()
// when the state is written back). When a point enters a cell of another
// rank, SolidSubCycle calls resort() after the step: write back, send it to
// that rank (MaterialPoints::relocate_points()), gather again. A point that
// crosses a face of the finite-element zone from outside by less than half
// a point spacing is held on that face (hold_on_zone_face()): the zone's
// elements are the grid's cells and its faces grid lines, whose nodes the
// points beside the zone share through the transition nodes (every face of
// the zone that is not a domain face: the top, and the lateral faces of a
// zone narrower than the domain); a point that lay on such a line (a
// raised zone's top, fe_zone_handover.h; the plate's lattice beside a
// lateral face) and moved with those nodes stays in the solid. It is put
// back on the face nearest to it that borders a cell outside the zone (at
// a corner, on the two or three faces it crossed if that is nearer), its
// velocity into the zone removed (the kinetic energy is booked by the next
// transfer, as for the domain's faces). Any other point that enters the
// finite-element zone, or one that leaves the domain, stops the run with a
// message that gives its position and how deep it lies in the zone (the
// FE zone has no place for it).
#ifndef femp_solid_mpm_h
#define femp_solid_mpm_h

#include <deal.II/base/tensor.h>

#include <femp/grid/background_grid.h>
#include <femp/grid/material_points.h>
#include <femp/solid/constitutive.h>
#include <femp/solid/solid_point_store.h>

#include <array>
#include <limits>
#include <vector>

namespace femp
{
  using namespace dealii;

  class StateWriter;
  class StateReader;

  /// Node fields of the solid on the background grid (local node box).
  template <int dim>
  struct SolidNodeFields
  {
    std::vector<double>                  mass;
    std::array<std::vector<double>, dim> momentum, force, velocity;
    /// With SolidMPM::set_stiffness_rows(true) only: per node I, the sum
    /// over the points of m_p h |grad N_Ip| h sum_J |grad N_Jp| (kg), the
    /// row sum that bounds the node's stiffness over its mass (doc/solid.md
    /// "Small node masses"); empty otherwise (sized by its owner).
    std::vector<double> stiffness;

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
  class SolidMPM : public SolidPointStore<dim>
  {
  public:
    SolidMPM(const BackgroundGrid<dim> &grid,
             const SolidMaterial       &material,
             MaterialPoints<dim>       &points);

    /// Copy the state of the solid points that lie in cells with
    /// @p excluded_cell[idx] == 0 into the flat arrays. Inertial masses are
    /// multiplied by @p mass_scaling (gravity uses the true mass). Points in
    /// state fluid get zero stress, plastic strain, viscous pressure and
    /// affine velocity, and, unless the melt flow owns them
    /// (set_flow_owns_fluid_points()), zero velocity; with a flow that
    /// carries C_p itself their affine velocity is the flow's.
    /// With @p same_members (exchange_since_gather() found no point melted,
    /// solidified or lost on this rank) and the same mask: when the handler
    /// has not moved a point into or out of a cell of the members since the
    /// last gather (MaterialPoints::layout_unchanged()), the arrays written
    /// back by the last scatter() are still the points' state, in the
    /// handler's order: they are kept, not copied again (the same result).
    void
    gather(const std::vector<std::uint8_t> &excluded_cell,
           const double                     mass_scaling,
           const bool                       same_members = false);
    /// After a step in which some point (on any rank) entered a cell of
    /// another rank: scatter, send to the neighbours, gather (collective).
    void
    resort();

    /// Step 1: add point mass, momentum and forces (internal and gravity) to
    /// the node fields (partial sums of this rank).
    /// When the last update_stresses() already computed these sums (fused
    /// pass), they are added from its buffer.
    void
    p2g(SolidNodeFields<dim> &nodes, const Tensor<1, dim> &gravity);
    /// Steps 3 and 4: velocity update (FLIP from the nodal accelerations in
    /// nodes.force = f_I / m_I, or APIC from nodes.velocity) and re-map of
    /// the new point momenta into nodes.momentum (partial sums; the caller
    /// zeroes it before).
    void
    g2p(SolidNodeFields<dim> &nodes, const double dt);
    /// Whether p2g() also sums nodes.stiffness (the light-node mass floor
    /// of the solid's grid update; off by default, and then the P2G costs
    /// nothing more).
    void
    set_stiffness_rows(const bool on);
    /// Step 5: stress update from node velocities; @p T_old and @p T_new are
    /// cell temperatures at the start and end of the step. Returns the
    /// stress work sum V sigma : D dt of this rank. Then moves the points by
    /// the grid velocity of g2p() and binds points that left their cell to
    /// their new owned cell (see n_left_rank()). From the second step after
    /// a gather() on, the same pass also computes the P2G sums of the next
    /// step (with the gravity of the last p2g()) for the next p2g().
    double
    update_stresses(const SolidNodeFields<dim> &nodes,
                    const double                dt,
                    const std::vector<double>  &T_old,
                    const std::vector<double>  &T_new);
    /// Points of this rank that entered a cell of another rank in the last
    /// update_stresses() (resort() needed).
    unsigned int
    n_left_rank() const
    {
      return left_rank;
    }
    /// True if in the last update_stresses() a point entered the FE zone or
    /// left the domain (the run must stop; see escaped_point()).
    bool
    point_lost() const
    {
      return lost;
    }
    /// True if in the last update_stresses() a point's volume V (1 + tr L
    /// dt) became zero or negative (compressed through zero in one step:
    /// the step is too large for the deformation; see find_collapsed()).
    bool
    volume_collapsed() const
    {
      return !(min_volume > 0);
    }

    /// Kinetic energy of this rank's points, J (2D: J/m); APIC includes the
    /// affine part. Summed in gather() and update_stresses().
    double
    kinetic_energy() const
    {
      return kinetic;
    }
    /// New inertial-mass factor @p s between two gathers (adaptive mass
    /// scaling): the points keep their velocities, the kinetic energy
    /// follows the mass (call after scatter(), before the next gather()).
    void
    set_mass_scaling(const double s)
    {
      kinetic *= s / scaling;
      scaling = s;
    }
    /// Stored elastic energy sum V_p sigma_p : C(T)^-1 : sigma_p / 2 of this
    /// rank's points, with T the cell temperatures @p T, J (2D: J/m).
    double
    elastic_energy(const std::vector<double> &T) const;
    /// Power of gravity at the current velocities, W.
    double
    gravity_power(const Tensor<1, dim> &gravity) const
    {
      double w = 0;
      for (int d = 0; d < dim; ++d)
        w += gravity[d] * weight_momentum[d];
      return w;
    }
    /// Mean sigma_xx and number of points in cell @p idx (this rank).
    std::pair<double, unsigned int>
    cell_stress_xx(const std::size_t idx) const;
    /// Add sigma_xx, sigma_yy, sigma_zz, the von Mises stress and the
    /// equivalent plastic strain of every point to its cell (sums, into
    /// @p f[0..4]) and count the points per cell.
    void
    add_cell_fields(std::vector<std::vector<double>> &f,
                    std::vector<double>              &count) const;
    /// Add the stress {xx, yy, zz, xy, xz, yz} and the equivalent plastic
    /// strain of every member in a cell with @p mask[idx] != 0 to that
    /// cell's entry of @p sums (entries 0-5 and 6) and count it (entry 7):
    /// the sums of the hand-over to finite elements (fe_zone_handover.h).
    void
    add_cell_state(const std::vector<std::uint8_t>    &mask,
                   std::vector<std::array<double, 8>> &sums) const;
    /// Position of the first point with a non-finite state, if any.
    bool
    find_non_finite(Point<dim> &where) const;
    /// Position of the first point with a volume <= 0 (and that volume in
    /// @p V), if any.
    bool
    find_collapsed(Point<dim> &where, double &V) const;
    /// Points of this rank held at the domain's faces so far (melt-flow
    /// scenes: spatter that reached a face; see hold_in_domain()).
    unsigned long
    n_held() const
    {
      return held;
    }
    /// Times a point of this rank was held on the FE zone's top face so far
    /// (a face normal to the last direction: the top, or the bottom of a
    /// zone above the domain's bottom; see hold_on_zone_face()). A hold on
    /// a top and a lateral face at once (at a concave edge of a zone with a
    /// step) counts here and in n_held_at_zone_lateral().
    unsigned long
    n_held_at_zone_top() const
    {
      return held_at_top;
    }
    /// Times a point of this rank was held on a lateral face of the FE zone
    /// so far (a face normal to x, or in 3D y; see hold_on_zone_face()).
    unsigned long
    n_held_at_zone_lateral() const
    {
      return held_at_lateral;
    }
    /// When false, a point that enters the FE zone stops the run however
    /// shallow (no hold on its faces; tests compare runs with and without
    /// the holds). Default true.
    void
    set_hold_on_zone_faces(const bool hold)
    {
      hold_at_zone = hold;
    }
    /// Kinetic energy the holds on the FE zone's faces removed from this
    /// rank's points so far (the velocity components into the zone), J
    /// (2D: J/m, inertial mass); booked by the next transfer.
    double
    held_at_zone_kinetic() const
    {
      return held_kinetic;
    }
    /// How far inside the FE zone a point that crossed one of its faces is
    /// still held on it (m): half the point spacing.
    double
    zone_hold_distance() const
    {
      return zone_face_tolerance;
    }
    /// Position of a point that entered the FE zone or left the domain.
    const Point<dim> &
    escaped_point() const
    {
      return escaped;
    }
    /// For escaped_point(): how far it lies inside the FE zone (m), its
    /// distance to the nearest cell outside the zone across the faces of
    /// its cell (more than half a point spacing: it was not held); -1 when
    /// it left the domain instead; NaN when no face of its cell borders a
    /// cell outside the zone.
    double
    escaped_depth() const
    {
      return escaped_at;
    }
    /// The grid nodes that a transfer of this rank may have written since
    /// the last gather(): the corners of every cell that held one of its
    /// points since then (local node indices, no repeats, in the order
    /// found; new entries are appended when a point enters a cell). Zero
    /// node mass elsewhere.
    const std::vector<std::uint32_t> &
    nodes_reached() const
    {
      return next_nodes;
    }
    /// The cells (local indices) that held one of this rank's points since
    /// the last gather(), no repeats, in the order found, appended like
    /// nodes_reached().
    const std::vector<std::uint32_t> &
    cells_reached() const
    {
      return reached_cells;
    }

    /// Restore the store's part of a checkpoint (SolidPointStore::
    /// load_state()) and clear the step's sums.
    void
    load_state(std::vector<StateReader> &parts);

  private:
    static constexpr unsigned int         n_corners = 1u << dim;
    std::array<std::ptrdiff_t, n_corners> corner_offset;
    /// p2g() and the fused pass also sum nodes.stiffness
    /// (set_stiffness_rows()).
    bool stiffness_rows = false;

    using Store = SolidPointStore<dim>;
    using Store::apic;
    using Store::C;
    using Store::cell;
    using Store::corner;
    using Store::eps_p;
    using Store::excluded;
    using Store::flow_owns_fluid;
    using Store::grid;
    using Store::left_cells;
    using Store::left_rank_points;
    using Store::mat;
    using Store::moved_cell;
    using Store::n_stress;
    using Store::node0;
    using Store::points;
    using Store::scaling;
    using Store::sigma;
    using Store::true_mass;
    using Store::v;
    using Store::visc;
    using Store::volume;
    using Store::x;

    /// Solid/Volumetric strain rate = centroid: the points' volumetric
    /// strain rate at the volume centroid of their cell's points and the
    /// pressure's nodal forces with the tent gradients there (B-bar;
    /// stress_block(), p2g_block()).
    bool
    centroid_volumetric() const
    {
      return mat.volumetric_strain_rate ==
             SolidMaterial::VolumetricStrainRate::centroid;
    }
    /// For centroid_volumetric(): per cell of the grid (local index), the
    /// local coordinates of the volume centroid of its points,
    /// sum V_p xi_p / sum V_p, of the last p2g() (its points' positions
    /// and volumes at the start of the step), and the points' volume.
    std::array<std::vector<double>, dim> cell_centroid;
    std::vector<double>                  cell_volume;
    /// Fills cell_centroid for the cells that hold points (a pass over the
    /// points: position, corner, volume).
    void
    compute_centroids();

    /// Solid/Pressure smoothing (SolidMaterial::pressure_smoothing): per
    /// point, saved by save_pressure_state() before the stress update, the
    /// mean stress tr(sigma)/3, the volume (0 for a point whose cell is at
    /// or above the solidus: it carries no stress and takes no part), the
    /// first node and local coordinates of its cell (those of the stress
    /// update; the move may change them); per local grid node the sums of
    /// V N_a and V N_a dm of smooth_pressure_increment().
    std::vector<double>                  ps_mean, ps_volume;
    std::vector<std::uint32_t>           ps_node0;
    std::array<std::vector<double>, dim> ps_xi;
    std::vector<double>                  ps_weight, ps_sum;
    /// Saves the state above of every point (a pass over the points).
    void
    save_pressure_state(const std::vector<double> &T_new);
    /// Replaces each taking part point's increment dm of tr(sigma)/3 since
    /// save_pressure_state() by sum_a N_a (sum_q V_q N_a dm_q) / (sum_q
    /// V_q N_a), the sums over the points of all ranks (a node of a rank
    /// boundary holds both ranks' sums); adds the shift to sigma_xx,
    /// sigma_yy and sigma_zz. Returns the change of the step's stress work
    /// sum (sigma_old + sigma_new)/2 : D dt V that the shift makes,
    /// sum shift (V_new - V_old) / 2 (D's trace is V_new / V_old - 1).
    double
    smooth_pressure_increment();

    /// Grid velocity at x_p (FLIP; with APIC it is v).
    std::array<std::vector<double>, dim> xdot;
    double                               kinetic = 0;
    /// Smallest point volume after the last update_stresses(), m^dim
    /// (infinite without points).
    double min_volume = std::numeric_limits<double>::infinity();
    std::array<double, dim> weight_momentum{}; ///< sum m_true v
    bool                    lost        = false;
    unsigned int            left_rank   = 0;
    unsigned long           held        = 0; ///< see n_held()
    unsigned long           held_at_top = 0; ///< see n_held_at_zone_top()
    unsigned long held_at_lateral       = 0; ///< see n_held_at_zone_lateral()
    bool          hold_at_zone = true;       ///< see set_hold_on_zone_faces()
    double        held_kinetic = 0;          ///< see held_at_zone_kinetic()
    Point<dim>    escaped;
    double        escaped_at = -1; ///< see escaped_depth()
    /// How far inside the FE zone a point is held on its faces: half the
    /// point spacing (the gap between a face and the first points beside
    /// it on the unmoved lattice).
    double zone_face_tolerance = 0;
    /// The way out of the FE zone nearest to a point in the zone's cell
    /// ijk: the faces of that cell it crosses (bit d: direction d; 0 when
    /// none qualifies), the side of each (-1 lower, +1 upper face), the
    /// cell outside the zone it leads to and the squared distance.
    struct ZoneExit
    {
      unsigned int         faces = 0;
      std::array<int, dim> side{}, cell{};
      double               distance2 = std::numeric_limits<double>::infinity();
    };
    /// The nearest way out of the FE zone for a point at @p xp in the
    /// zone's cell @p ijk: across one face of the cell, or two or three at
    /// an edge or corner, the nearer face of each direction, each at most
    /// @p limit away, into a cell of the domain and of this rank's box
    /// outside the zone (the point came from there).
    ZoneExit
    nearest_zone_exit(const Point<dim>           &xp,
                      const std::array<int, dim> &ijk,
                      const double                limit) const;
    /// Puts point @p p, found at @p xp in the FE zone's cell @p ijk at most
    /// zone_face_tolerance inside the zone (nearest_zone_exit()), back on
    /// the face(s) it crossed, a millionth of a cell outside, and removes
    /// its velocity into the zone (the normal component of each face);
    /// @p ijk becomes the cell outside. Returns false, changing nothing,
    /// when the point lies deeper: the caller stops the run.
    bool
    hold_on_zone_face(const std::size_t     p,
                      Point<dim>           &xp,
                      std::array<int, dim> &ijk);
    /// Puts point @p p (at @p xp, outside the domain) back on the domain's
    /// faces and removes its outward velocity (melt-flow scenes).
    void
    hold_in_domain(const std::size_t p, Point<dim> &xp);

    /// P2G sums of the next step from the fused pass of update_stresses():
    /// mass, momentum (dim), force (dim) per node of the local box, zero
    /// outside the nodes written (next_nodes, the corners of the cells that
    /// hold points since the last gather(), marked in node_mark).
    std::array<std::vector<double>, 2 + 2 * dim> next;
    std::vector<std::uint32_t>                   next_nodes;
    std::vector<std::uint8_t>                    node_mark;
    std::vector<std::uint32_t>                   reached_cells;
    std::vector<std::uint8_t>                    cell_mark;
    bool           next_ready         = false; ///< next holds the next P2G
    bool           next_dirty         = false; ///< next is not all zero
    unsigned int   steps_since_gather = 0;
    bool           have_gravity       = false;
    Tensor<1, dim> p2g_gravity; ///< of the last p2g()

    /// The points p0 .. p0 + nl - 1 of a block of update_stresses() of
    /// which one left its cell, point by point: kinetic energy, momentum
    /// and the cell crossing (@p A: APIC).
    template <bool A>
    void
    finish_points(const std::size_t p0, const unsigned int nl);
    /// Marks the cell @p idx in reached_cells and its corners (first node
    /// @p n0) in next_nodes.
    void
    mark_cell_nodes(const std::size_t idx, const std::size_t n0);
    /// Zeroes next at next_nodes if it was written.
    void
    clear_next();
    /// Kinetic energy and gravity momentum by a loop over the points.
    void
    sum_energies();
  };
} // namespace femp

#endif
