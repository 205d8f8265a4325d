// femp: SolidFEM<dim>, explicit finite elements for the constant-solid zone
// (paper eqs. 6-10, doc/method.md, "Solid"): 8-node hexahedra (4-node
// quadrilaterals in 2D, plane strain), one-point quadrature,
// Flanagan-Belytschko hourglass control, lumped mass, central difference;
// transition nodes (eqs. 14-17).
//
// Mesh: its own parallel::distributed::Triangulation of the FE zone's
// bounding box (a box on grid lines), cells of the grid's size h, so that
// every element covers one background-grid cell and every FE node
// coincides with a grid node (N_Ii = 1 at transition nodes). The zone is a
// set of grid cells (fe_zone.h): a cell of the box outside it (an island
// of material points inside the zone, or beside a lower column) is no
// element; a node of no element carries no mass and stays at rest (its
// velocity is never read: the grid's nodes there are the MPM's). p4est
// partitions it independently of the background grid. A DoFHandler with
// FE_Q<dim>(1) defines the owned and ghost nodes of a rank (the
// Utilities::MPI::Partitioner); the hot loops use their own numbering: the
// local nodes are numbered lexicographically in the bounding box of their
// structured indices (x fastest), node data (velocity, force, inverse mass,
// fixed components) are one flat array per component over that box, and the
// elements are processed in lexicographic order, so that a block of simd_lanes
// elements of one x-row has its corners at simd_lanes consecutive nodes (vector
// loads; the forces of the block added as vectors, no two lanes on the same
// node). Nodal force sums over ranks copy the shared nodes (ghosts and owned
// nodes that are ghosts elsewhere) through a LinearAlgebra::distributed::Vector
// (compress(add), update_ghost_values); nothing is copied on one rank. Element
// data (corner box indices, stress state, temperatures) are flat arrays. The
// temperature of an element is that of its grid cell (eq. 2): the grid rank
// that owns the cell sends it, once per advance() (not per solid step), through
// a Utilities::MPI::NoncontiguousPartitioner keyed by the cell's lexicographic
// index in the zone.
//
// Element (undeformed cube of side h, small-displacement geometry; the
// Jaumann spin is still taken from the velocity gradient):
//   b_a = grad N_a(centre) = s_a / (2^(dim-1) h),  s_a in {-1, 1}^dim,
//   f_a^int = -V sigma b_a                                   (eq. 9)
// Hourglass (Flanagan-Belytschko, stiffness form): for a rectangular element
// the hourglass base vectors Gamma (xy, yz, xz, xyz products of s_a; one in
// 2D) are orthogonal to the linear field, so gamma = Gamma and
//   q_alpha,i = sum_a Gamma_alpha,a u_a,i,
//   f_a,i^HG = -k sum_alpha Gamma_alpha,a q_alpha,i,
//   k = kappa M(T) V (sum_a |b_a|^2) / 2^dim,  M = P-wave modulus,
// with the hourglass energy 1/2 k sum q^2 per element. All elements are the
// same cube, so b_a and Gamma are compile-time constants: one fused loop per
// element (gather velocities, L, constitutive update, stress work, viscous
// pressure, internal + hourglass forces of the next step added to the
// nodes) and one fused loop over the nodes (velocity update, zeroing the
// force for the next element loop, energies), both in SIMD; the element
// loop in
// SIMD blocks of simd_lanes elements (one per lane of simd_double, element
// state stored per block, update_stress_block of constitutive.h).
//
// Transition nodes (doc/method.md, "Solid"): nodes of elements that touch
// a grid cell of the domain outside the zone (for a box zone: the nodes on
// its faces that are not domain faces). They are
// numbered globally from geometry (every rank knows all of them); see
// solid_sub_cycle.h for the exchange of their sums.
#ifndef femp_solid_fem_h
#define femp_solid_fem_h

#include <deal.II/base/mpi_noncontiguous_partitioner.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/partitioner.h>
#include <deal.II/base/point.h>
#include <deal.II/distributed/tria.h>
#include <deal.II/dofs/dof_handler.h>
#include <deal.II/fe/fe_q.h>
#include <deal.II/lac/la_parallel_vector.h>

#include <femp/base/parameter_table.h>
#include <femp/grid/background_grid.h>
#include <femp/solid/constitutive.h>
#include <femp/solid/fe_zone.h>
#include <femp/solid/hourglass.h>

#include <array>
#include <limits>
#include <memory>
#include <vector>

namespace femp
{
  using namespace dealii;

  class StateWriter;
  class StateReader;

  template <int dim>
  class SolidFEM
  {
  public:
    struct Parameters
    {
      bool       enabled = false;
      Point<dim> lower_corner;
      Point<dim> upper_corner;
      double     hourglass_coefficient = 0;
      /// Largest hourglass distortion of an element's corners
      /// (hourglass_distortion()) before the run stops, -.
      double hourglass_distortion_limit = 0.1;
      /// 'Zone upper corner = auto': the driver places the top below the
      /// estimated melt depth (fe_zone_depth.h) before check().
      bool automatic_top = false;

      /// Declare (the members' values are the defaults) or read the

      /// entries, each listed once.

      void

      add_parameters(ParameterTable &table);

      static void
      declare_parameters(ParameterHandler &prm);
      void
      parse_parameters(ParameterHandler &prm);
      /// Zone corners on grid lines and inside the domain.
      void
      check(const typename BackgroundGrid<dim>::Parameters &grid) const;
      /// The zone of these parameters on a grid with origin @p origin and
      /// cell size @p h (no zone unless 'Use finite elements').
      FeZone<dim>
      zone(const Point<dim> &origin, const double h) const
      {
        return FeZone<dim>(enabled, lower_corner, upper_corner, origin, h);
      }
    };

    static constexpr unsigned int n_corners = 1u << dim;
    static constexpr unsigned int n_hg      = hourglass::n_modes<dim>;
    /// Doubles per transition node in the exchange buffer: grid mass, grid
    /// momentum (dim), force without hourglass (dim), hourglass force (dim).
    static constexpr unsigned int tr_width = 1 + 3 * dim;

    SolidFEM(const Parameters          &prm,
             const BackgroundGrid<dim> &grid,
             const SolidMaterial       &material);

    const Parameters &
    parameters() const
    {
      return prm;
    }

    /// Build the FE triangulation, node numbering, element arrays, lumped
    /// masses (times @p mass_scaling), the transition nodes and the initial
    /// forces. @p face_bits[f]: velocity components fixed on domain face f
    /// (x-, x+, y-, ...). @p T: grid cell temperatures at time 0.
    void
    setup(const double                             mass_scaling,
          const std::array<std::uint8_t, 2 * dim> &face_bits,
          const Tensor<1, dim>                    &gravity,
          const std::vector<double>               &T);

    /// 1 for cells of the grid's local box inside the FE zone.
    const std::vector<std::uint8_t> &
    zone_mask() const
    {
      return in_zone_cell;
    }
    /// The FE zone: a set of grid cells, a mask over its bounding box.
    const FeZone<dim> &
    fe_zone() const
    {
      return zone;
    }
    std::size_t
    n_elements() const
    {
      return conn.size() / n_corners;
    }
    /// Owned elements whose grid cell is not owned by this rank.
    std::size_t
    n_elements_off_rank() const
    {
      return off_rank;
    }

    /// Start of an advance(): the grid cell temperatures @p T at its end time
    /// become the elements' end temperatures (the old ones the start).
    /// Collective.
    void
    new_temperatures(const std::vector<double> &T);
    /// External nodal forces of the grid (partial sums of this rank over the
    /// nodes of its owned cells) at FE nodes that are not transition nodes
    /// go to the FE nodes; nullptr for none. Collective.
    void
    set_external_forces(const std::array<std::vector<double>, dim> *f);

    // ---- transition nodes ------------------------------------------------
    std::size_t
    n_transition() const
    {
      return tr_ijk.size();
    }
    /// Global structured node index of transition node @p t.
    const std::array<int, dim> &
    transition_node(const std::size_t t) const
    {
      return tr_ijk[t];
    }
    /// FE mass (scaled, all elements) and velocity of transition node @p t.
    double
    transition_mass(const std::size_t t) const
    {
      return tr_mass[t];
    }
    const double *
    transition_velocity(const std::size_t t) const
    {
      return &tr_vel[dim * t];
    }
    std::uint8_t
    transition_constraint(const std::size_t t) const
    {
      return tr_fix[t];
    }
    /// Displacement of transition node @p t since setup() or the last
    /// add_cells() (m, dim values): its velocity integrated over the solid
    /// steps since (the zone's top face has moved this far from the grid
    /// line; the hand-over's fill reads it, fe_zone_handover.h).
    const double *
    transition_displacement(const std::size_t t) const
    {
      return &tr_disp[dim * t];
    }
    /// Add this rank's FE partial sums (force without hourglass, hourglass
    /// force) at the transition nodes into @p buffer (tr_width per node).
    void
    add_transition_partials(std::vector<double> &buffer) const;
    /// From the global sums in @p buffer: the grid velocity v_I and
    /// acceleration a_I of each transition node (eqs. 14-16; written to
    /// @p v_grid and @p a_grid, dim per node), and the new FE velocity
    /// v_I + dt f^HG / m_i (eq. 17) kept for every transition node.
    void
    update_transition(const std::vector<double> &buffer,
                      const double               dt,
                      std::vector<double>       &v_grid,
                      std::vector<double>       &a_grid);

    /// Central-difference node update (eq. 10): sums of the element forces
    /// over ranks, new velocities of all local FE nodes
    /// (transition nodes from update_transition()). Returns {kinetic
    /// energy, external power, sum m v_old . dv, sum m dv . dv} of the
    /// owned nodes, dv = v_new - v_old (0 at the transition nodes, counted
    /// with the grid's), the last two for the leapfrog's half-step term
    /// (SolidEnergies::half_step).
    std::array<double, 4>
    update_nodes(const double dt);
    /// Fused element loop: stress update over the step @p dt with the
    /// temperature interpolated at weight @p w between the start and end
    /// temperatures of the advance() (eq. 5), then the element forces of
    /// the next step. Returns the stress work of this rank's elements.
    double
    update_elements(const double dt, const double w);

    /// From the next update_nodes() on, the nodes that it integrates (not
    /// the transition nodes) lose the fraction @p beta of their velocity
    /// after each update (quasi-static cooling, doc/solid.md); 0: none.
    void
    set_node_damping(const double beta)
    {
      node_damping = beta;
    }
    /// Kinetic energy of the owned nodes that the damping took out in the
    /// last update_nodes(), J (2D: J/m).
    double
    damped_energy() const
    {
      return damped;
    }
    /// Kinetic energy of the owned nodes (from the last update_nodes()).
    double
    kinetic_energy() const
    {
      return kinetic;
    }
    /// Multiply the velocities of the nodes that update_nodes() integrates
    /// (not the transition nodes) by @p f (quasi-static cooling: a raise
    /// of the factor from s to s_new at kept momentum, f = s / s_new,
    /// doc/solid.md). Returns the change of the kinetic energy of the
    /// owned nodes at the masses in use, J (2D: J/m).
    double
    scale_node_velocities(const double f);
    /// The zone's mass, kg (2D: kg/m): the lumped masses of the owned
    /// nodes over the mass-scaling factor in use, summed over the ranks.
    /// Each element carries the material's density over its cell, also
    /// one that a hand-over gave points of more or less mass (doc/builds.md,
    /// "Mass"). Collective.
    double
    mass() const;
    /// New mass-scaling factor @p s (adaptive mass scaling, between two
    /// solid steps): lumped and transition-node masses follow, velocities
    /// are kept (the kinetic energy follows the mass).
    void
    set_mass_scaling(const double s);
    /// Stored elastic energy sum V sigma : C(T)^-1 : sigma / 2 of this
    /// rank's elements, J (2D: J/m).
    double
    elastic_energy() const;
    /// Hourglass energy 1/2 k sum q^2 of this rank's elements, J: with the
    /// scene's kappa (entry 0) and, if @p with_reference, with the
    /// reference kappa = 0.05 (entry 1, a mode amplitude measure; else 0),
    /// in one pass over the elements.
    std::array<double, 2>
    hourglass_energy(const bool with_reference) const;

    /// sigma_xx (Pa) and temperature (K) of the owned element containing
    /// @p x, or false if none.
    bool
    probe(const Point<dim> &x, double &sigma_xx, double &T) const;
    /// sigma_xx, sigma_yy, sigma_zz, von Mises stress and equivalent
    /// plastic strain (@p f[0..4]) of the zone cells of the grid's local box
    /// (at owned cells; other entries untouched). Collective.
    void
    cell_fields(std::vector<std::vector<double>> &f) const;
    bool
    find_non_finite(Point<dim> &where) const;
    /// True if after the last update_elements() an element is inverted
    /// (its lowest corner Jacobian ratio, jacobian_low(), is zero or below)
    /// or its hourglass modes distort its corners by more than 'Hourglass
    /// distortion limit'.
    bool
    element_failed() const
    {
      return !(min_jacobian > 0) ||
             !(max_distortion <= prm.hourglass_distortion_limit);
    }
    /// Centre of the first failed element (see element_failed()), its
    /// lowest corner Jacobian ratio in @p J if it is inverted, else its
    /// hourglass distortion in @p J and @p distorted set; false if none.
    bool
    find_failed(Point<dim> &where, double &J, bool &distorted) const;
    /// Largest hourglass distortion of an element since setup (or the
    /// resume), over all ranks. Collective.
    double
    largest_distortion() const;

    /// Add the grid cells @p cells (structured indices inside the grid,
    /// none in the zone, the same list on every rank) to the zone, between
    /// two solid steps: the FE triangulation of the new bounding box, its
    /// nodes, masses and transition nodes are built anew (the setup's
    /// arithmetic, at the mass-scaling factor in use), the old elements
    /// keep their whole state (stress, plastic strain, viscous pressure,
    /// temperatures, hourglass amplitudes, volume change) and the old
    /// nodes their velocity (an old transition node takes its transition
    /// velocity, every transition node a displacement of 0: the zone's
    /// faces are the grid lines); a new element takes from @p new_cells
    /// (this rank's entries: the cell's lexicographic index in the grid
    /// (x fastest), stress {xx, yy, zz, xy, xz, yz}, plastic strain) its
    /// stress and plastic strain and the cell temperature of @p T, at rest
    /// and without hourglass amplitudes; the new nodes start at rest.
    /// Every new element must be in @p new_cells of some rank. Collective
    /// (all-gathers the zone's state: once per hand-over). Returns the
    /// elements added (global).
    std::uint64_t
    add_cells(const std::vector<std::array<int, dim>> &cells,
              const std::vector<std::pair<std::uint64_t, std::array<double, 7>>>
                                        &new_cells,
              const std::vector<double> &T);

    /// The top of the zone's bounding box, m: 'Zone upper corner', or the
    /// grid line a hand-over raised it to (add_cells(), set_top()).
    double
    top() const
    {
      return prm.upper_corner[dim - 1];
    }
    /// The mass-scaling factor the zone's lumped masses were built at (by
    /// setup() or add_cells()); every later factor scales those masses.
    double
    setup_mass_scaling() const
    {
      return mass_scale_setup != 0 ? mass_scale_setup : mass_scale;
    }
    /// Before setup(): build the zone up to the grid line @p new_top (m,
    /// above the zone's bottom, inside the domain) instead of 'Zone upper
    /// corner' (the zone of a checkpoint that a hand-over raised).
    void
    set_top(const double new_top);
    /// Before setup(): build the zone @p zone (cells of the grid, the same
    /// on every rank; e.g. a checkpoint's zone, or a zone that is not a
    /// box) instead of the box of 'Zone lower corner' and 'Zone upper
    /// corner'.
    void
    set_cells(const FeZone<dim> &zone);

    /// Checkpoint, between two solid steps: per owned element, keyed by its
    /// zone index, the stress, plastic strain, viscous pressure,
    /// temperature of the last step, hourglass mode amplitudes and end
    /// temperature of the advance; per owned node, keyed by its zone node
    /// index, the velocity; the transition-node velocities and
    /// displacements.
    void
    save_state(StateWriter &out) const;
    /// Restore it after setup() (any number of saved ranks; every rank
    /// takes its owned elements and local nodes) and recompute the element
    /// forces of the next step from the restored elements (the same
    /// arithmetic as at the end of update_elements()). Refuses (collective)
    /// a checkpoint with an element that is none of this zone's, one that
    /// lacks an element or node of this zone, or another number of
    /// transition nodes.
    void
    load_state(std::vector<StateReader> &parts);
    /// The checkpoint section of an FE zone that is off (SolidSubCycle then
    /// holds no SolidFEM): the layout of save_state() without elements,
    /// nodes or transition nodes, so that the solid's section keeps one
    /// format.
    static void
    save_no_zone(StateWriter &out);
    /// Read that section from each of @p parts; like load_state() on an
    /// empty zone, a checkpoint with transition nodes is refused.
    static void
    load_no_zone(std::vector<StateReader> &parts);

  private:
    Parameters                 prm;
    const BackgroundGrid<dim> &grid;
    const SolidMaterial       &mat;
    MPI_Comm                   comm;

    parallel::distributed::Triangulation<dim> tria;
    FE_Q<dim>                                 fe;
    /// Made anew with the mesh (add_cells() clears the triangulation,
    /// which no DoFHandler may then hold).
    std::unique_ptr<DoFHandler<dim>>                   dof_handler;
    std::shared_ptr<const Utilities::MPI::Partitioner> node_partitioner;
    LinearAlgebra::distributed::Vector<double>         force; ///< dim per node

    /// The zone (fe_zone.h); zlo, zn: the first cell index and cells per
    /// direction of its bounding box, for the index arithmetic of the mesh
    /// (the mesh covers the bounding box; its cells outside the zone are
    /// no elements). zone_given: the zone was set by set_cells() or grown
    /// by a hand-over (else setup() takes the parameters' box).
    FeZone<dim>          zone;
    bool                 zone_given = false;
    std::array<int, dim> zlo, zn;
    double               V = 0, bb = 0, mass_scale = 1;
    Tensor<1, dim>       g;
    /// Fixed velocity components per domain face (setup()).
    std::array<std::uint8_t, 2 * dim> face_fix{};

    // Node box: the local nodes (owned and ghost) are numbered
    // lexicographically in the bounding box of their structured indices
    // (x fastest), box index n = sum_d (ijk_d - box_lo_d) box_stride_d;
    // node data are flat arrays per component over the box (padded to a
    // multiple of simd_lanes; slots without a local node stay zero). An
    // x-row of elements then has its corner nodes at consecutive indices.
    std::array<int, dim>         box_lo, box_n;
    std::array<std::size_t, dim> box_stride;
    std::size_t                  n_box      = 0; ///< padded box size
    bool                         multi_rank = false;

    // Elements, in lexicographic order of their zone index (x fastest).
    std::vector<std::uint32_t> conn; ///< n_corners box node indices each
    /// Per block: box index of corner 0 of its first element if its
    /// simd_lanes elements are consecutive in one x-row (their corners are
    /// then simd_lanes consecutive nodes from there, loaded as vectors),
    /// else -1 (corners gathered one by one through conn).
    std::vector<std::int64_t> block_row;
    /// State of simd_lanes consecutive elements (lane l: element
    /// simd_lanes * block + l), so that the element loop loads and stores
    /// whole SIMD registers; the lanes of the last block beyond the last
    /// element are padding (they repeat the last element's data).
    struct ElementBlock
    {
      simd_double s[6];  ///< Cauchy stress {xx, yy, zz, xy, xz, yz}, Pa
      simd_double eps_p; ///< equivalent plastic strain, -
      simd_double visc;  ///< viscous pressure q, Pa
      simd_double T;     ///< temperature of the last step, K
      /// Hourglass mode amplitudes q_alpha,i = sum_a Gamma_alpha,a u_a,i,
      /// advanced with the element's velocities.
      simd_double q[n_hg][dim];
      /// J - 1: volume change of the element centre, J the product of
      /// (1 + tr L dt) over the steps (the one-point element's Jacobian
      /// ratio; small-displacement forces keep the reference volume).
      simd_double dJ;
    };
    std::vector<ElementBlock> blocks;
    std::vector<double>       T_start, T_end;
    /// Stress tensor of element @p e.
    SymmetricTensor<2, 3>
    element_stress(const std::size_t e) const
    {
      SymmetricTensor<2, 3> s;
      for (unsigned int c = 0; c < 6; ++c)
        s.access_raw_entry(c) = blocks[e / simd_lanes].s[c][e % simd_lanes];
      return s;
    }
    double
    element_T(const std::size_t e) const
    {
      return blocks[e / simd_lanes].T[e % simd_lanes];
    }
    std::vector<std::uint64_t> element_id; ///< lexicographic in the zone
    std::vector<std::pair<std::uint64_t, std::uint32_t>> element_by_id;
    std::size_t                                          off_rank = 0;
    Utilities::MPI::NoncontiguousPartitioner T_exchange; ///< grid -> FE
    std::vector<std::uint32_t> grid_zone_cells;          ///< owned zone cells
    std::vector<double>        T_send;

    // Nodes (box numbering, see above).
    std::size_t                n_owned = 0, n_local = 0; ///< DoFHandler's
    std::vector<std::uint32_t> box_of; ///< box index of local node ln
    /// Local nodes whose force sums go over ranks: ghosts and owned nodes
    /// that are ghosts elsewhere (empty on one rank).
    std::vector<std::uint32_t>           shared_nodes;
    std::array<std::vector<double>, dim> vel; ///< velocity, m/s
    std::array<std::vector<double>, dim> frc; ///< nodal force, N
    std::array<std::vector<double>, dim> ext; ///< external force, N
    /// Bit d set: velocity component d fixed (zero); all bits at slots
    /// without a local node. Clear at transition nodes (their velocity
    /// comes from update_transition(), fixed components zero there).
    std::vector<std::uint8_t> fix;
    std::vector<double>       inv_mass;   ///< 0 at transition nodes
    std::vector<double>       owned_mass; ///< lumped mass at owned nodes
    /// The masses of the setup's factor, kept from the first change of the
    /// factor on, so that every later factor scales them once (a resumed
    /// run then has the same masses bit for bit as the run that went on).
    std::vector<double>        inv_mass_setup, owned_mass_setup, tr_mass_setup;
    double                     mass_scale_setup = 0;
    std::vector<std::uint64_t> node_zone_id; ///< zone node index, per box
    std::vector<std::uint32_t> ext_nodes;    ///< box indices
    double                     kinetic = 0;
    /// set_node_damping() and damped_energy().
    double node_damping = 0, damped = 0;
    /// Smallest jacobian_low() of the elements after the last
    /// update_elements() (infinite without elements).
    double min_jacobian = std::numeric_limits<double>::infinity();
    /// Largest hourglass_distortion() after the last update_elements(), and
    /// since setup (this rank's elements).
    double max_distortion = 0, max_distortion_seen = 0;
    /// After load_state() or add_cells() set the elements and nodes: the
    /// spare lanes of the last block repeat the last element, the end
    /// temperatures become the start ones, and the element forces of the
    /// next step are computed from the state (the arithmetic of the end of
    /// update_elements()).
    void
    forces_of_restored_state();
    /// Sums of the force components (@p f) of the shared nodes over ranks
    /// (compress(add), update_ghost_values of the vector @p force).
    void
    sum_shared(std::array<std::vector<double>, dim> &f);

    // Transition nodes (global, every rank).
    std::vector<std::array<int, dim>> tr_ijk;
    std::vector<double>               tr_mass, tr_vel;
    /// Displacement since setup() or the last add_cells() (dim per node).
    std::vector<double>       tr_disp;
    std::vector<std::uint8_t> tr_fix;
    /// (element, corner, transition index) of this rank's elements.
    std::vector<std::array<std::uint32_t, 3>> tr_corners;
    /// (box index, transition index) of the local transition nodes.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> tr_local;
    std::vector<double> tr_hg; ///< partial f^HG

    std::vector<std::uint8_t> in_zone_cell;

    /// The parts of setup(): the zone (zone, zlo, zn, in_zone_cell); the FE
    /// triangulation, its dofs and the node partitioner; the owned
    /// elements sorted by zone index, with the structured index of each
    /// local node; the node box; the element arrays and SIMD blocks; the
    /// node arrays; the lumped masses (summed over ranks); the transition
    /// nodes; the temperature exchange with the grid.
    void
    set_zone();
    void
    create_mesh();
    std::vector<
      std::pair<std::uint64_t, std::array<std::uint32_t, (1u << dim)>>>
    local_elements(std::vector<std::array<int, dim>> &node_ijk);
    void
    set_node_box(const std::vector<std::array<int, dim>> &node_ijk);
    void
    set_elements(
      const std::vector<
        std::pair<std::uint64_t, std::array<std::uint32_t, (1u << dim)>>>
        &cells);
    void
    allocate_node_arrays();
    std::vector<double>
    lumped_masses(const double m_el);
    void
    set_transition_nodes(const std::array<std::uint8_t, 2 * dim> &face_bits,
                         const double                             m_el,
                         const std::vector<double>               &mass,
                         const std::vector<std::array<int, dim>> &node_ijk);
    void
    set_temperature_exchange(const std::vector<double> &T);
    /// Zone geometry: lexicographic zone index of a cell and of a node; a
    /// zone node on a zone face that is not a domain face; the fixed
    /// components of a node on the domain faces.
    std::uint64_t
    zone_cell_id(const std::array<int, dim> &ijk) const;
    std::uint64_t
    zone_node_id(const std::array<int, dim> &ijk) const;
    bool
    is_transition(const std::array<int, dim> &ijk) const;
    /// Of the 2^dim cells around the node @p ijk inside the domain: how
    /// many lie in the zone (entry 0) and how many do not (entry 1).
    std::array<unsigned int, 2>
    cells_around(const std::array<int, dim> &ijk) const;
    /// The zone becomes @p larger (which holds it): add_cells() after its
    /// checks.
    std::uint64_t
    grow(const FeZone<dim> &larger,
         const std::vector<std::pair<std::uint64_t, std::array<double, 7>>>
                                   &new_cells,
         const std::vector<double> &T);
    std::uint8_t
    fix_bits(const std::array<int, dim>              &ijk,
             const std::array<std::uint8_t, 2 * dim> &face_bits) const;

    /// Constants of one element loop over the step dt: B dt, V B, the
    /// hourglass stiffness per unit E, the factor of the viscous pressure
    /// and the gravity force per corner.
    struct LoopConstants
    {
      double Bdt, VB, kfac, vfac;
      /// B: the corner check (with hourglass control on or off).
      double hgB;
      double mg[dim];
    };
    LoopConstants
    loop_constants(const double dt) const;
    /// Lowest corner Jacobian ratio det(dx/dX) of the elements of @p eb,
    /// to first order in the displacement: 1 + dJ - @p distortion, the
    /// distortion (hourglass_distortion()) being hgB times the sum over the
    /// hourglass modes alpha and the directions i of alpha of |q_alpha,i|
    /// (the hourglass displacement gradient at a corner is B q_alpha,i
    /// times a sign; exact minimum over the corners in 2D, a lower bound
    /// in 3D). The hourglass displacements q are integrated with control
    /// off as well, so that a mode growing without stiffness stops the run
    /// when it inverts a corner.
    simd_double
    jacobian_low(const ElementBlock &eb, const simd_double &distortion) const;
    /// The hourglass part of jacobian_low(): hgB sum |q_alpha,i|, the
    /// largest change of a corner's volume ratio that the hourglass modes
    /// make (first order; 1 inverts a corner of an unstrained element).
    simd_double
    hourglass_distortion(const ElementBlock &eb, const double hgB) const;
    /// Box offset of corner @p a from corner 0 of an element.
    std::size_t
    corner_row_offset(const unsigned int a) const;
    /// The passes of element_loop() over one block of simd_lanes elements
    /// (lanes @p el, @p nl of them real; see solid_fem.cc): the corner
    /// velocities as transform coefficients; the constitutive update
    /// (returns the stress work per lane); the forces of the next step
    /// added to the nodes; after all blocks, the hourglass forces at the
    /// transition nodes.
    void
    gather_velocities(const std::size_t b,
                      const std::size_t (&el)[simd_lanes],
                      const double *const (&vl)[dim],
                      simd_double (&Vc)[n_corners][dim]) const;
    simd_double
    update_block(ElementBlock &eb,
                 const std::size_t (&el)[simd_lanes],
                 const unsigned int nl,
                 const simd_double (&Vc)[n_corners][dim],
                 const double         dt,
                 const double         w,
                 const LoopConstants &c,
                 StressBlock         &sb,
                 simd_double         &E) const;
    void
    scatter_forces(const std::size_t  b,
                   const unsigned int nl,
                   const simd_double (&s)[6],
                   const simd_double    E,
                   const LoopConstants &c,
                   double *const (&F)[dim]);
    void
    transition_hourglass_forces(const double kfac);
    template <bool update>
    double
    element_loop(const double dt, const double w);
    template <bool with_ext, bool damp>
    std::array<double, 4>
    node_loop(const double dt);
    double
    hourglass_stiffness(const double T, const double kappa) const;
  };
} // namespace femp

#endif
