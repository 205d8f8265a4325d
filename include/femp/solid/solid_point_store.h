// femp: SolidPointStore<dim>, the solid points of the material point method
// as flat arrays (structure of arrays), the store that SolidMPM's MUSL step
// (solid_mpm.h, paper eqs. 11-13) works on.
//
// Points of state 'solid' outside the finite-element zone take part (the
// members). Their state is copied from the ParticleHandler into flat arrays
// at the start of a solid advance and written back at its end, so that the
// hot loops touch no iterator; between two gathers the store keeps the
// arrays, or updates them only in the cells whose points changed, when the
// handler's layout allows it (the same result as a full copy). It finds the
// exchange with the melt since the last gather (points that melted,
// solidified, were lost to the FE zone or set aside in detached drops, with
// their kinetic energies) by particle id, and saves and restores the
// members for a checkpoint. No equation of the paper: the bookkeeping of
// which points the solid's equations act on.
#ifndef femp_solid_point_store_h
#define femp_solid_point_store_h

#include <deal.II/base/point.h>

#include <femp/grid/background_grid.h>
#include <femp/grid/material_points.h>
#include <femp/solid/constitutive.h>

#include <array>
#include <cstdint>
#include <vector>

namespace femp
{
  using namespace dealii;

  class StateWriter;
  class StateReader;

  template <int dim>
  class SolidPointStore
  {
  public:
    SolidPointStore(const BackgroundGrid<dim> &grid,
                    const SolidMaterial       &material,
                    MaterialPoints<dim>       &points);

    /// Cells (local indices, owned) whose solid points stay out of the
    /// solid: the detached drops of MetalBodies ('Heat
    /// transfer/Detached drops = sphere'), spatter of one or two cells
    /// with no metal face neighbour. A drop that solidifies in the gas is
    /// not part of the workpiece, and a body of a few points whose nodes
    /// carry a small share of a full node's mass has next to no
    /// stiffness on the grid: such points collapsed in the paper-scale
    /// track (doc/solid.md "Detached drops"). Their points are set aside:
    /// the next exchange_since_gather() counts members in these cells as
    /// set aside (with their kinetic energy), the next gather() leaves
    /// them out and zeroes their velocity, stress and plastic strain
    /// (they stay where they are, carry heat and count as metal), and a
    /// cell that leaves the list gives its solid points back to the solid
    /// at rest and stress-free (counted as solidified). An empty list (the
    /// default) sets nothing aside.
    void
    set_aside_cells(const std::vector<std::uint32_t> &cells);
    /// Points that the last gather() set aside while they moved (members
    /// that the solid carried into a cell of set_aside_cells(), on this
    /// rank or from the other one through resort()): their number and
    /// kinetic energy before they were stopped (this rank). A gather after
    /// exchange_since_gather() finds them there too; resort() has no
    /// exchange, and its caller books them from here.
    std::array<double, 2>
    set_aside_by_last_gather() const
    {
      return {{gather_aside_n, gather_aside_k}};
    }

    /// gather() calls that kept the arrays (see there), those that
    /// updated them only in the cells whose points changed, and all calls.
    std::array<unsigned long, 3>
    gather_counts() const
    {
      return {{gathers_kept, gathers_merged, gathers}};
    }
    /// With the melt flow running beside the solid: gather() leaves the
    /// velocity of fluid points alone (the flow owns it), and with
    /// @p affine (Melt flow/Velocity transfer = APIC) their affine
    /// velocity too.
    void
    set_flow_owns_fluid_points(const bool b, const bool affine = false)
    {
      flow_owns_fluid = b;
      flow_affine     = b && affine;
    }
    /// Write positions, velocities, stresses, plastic strains, volumes,
    /// viscous pressures and affine velocities back to the particles, and
    /// move points that changed cells to their new cells (collective).
    void
    scatter();
    /// Exchange with the melt since the last gather(), on this rank; call
    /// before gather(). Points that took part in the last gather and are no
    /// longer solid (melted) or lie in an excluded cell (entered the FE zone:
    /// lost), and solid points outside excluded cells that did not take part
    /// (solidified): their numbers and kinetic energies (inertial mass, APIC
    /// with the affine part), and the position of one lost point.
    struct Exchange
    {
      double n_melted = 0, n_solidified = 0, n_lost = 0;
      double k_melted = 0, k_solidified = 0;
      /// Members now in a cell of set_aside_cells().
      double n_set_aside = 0, k_set_aside = 0;
      /// Solid points that are not members and still move in a cell of
      /// set_aside_cells(): points that solidified in a detached drop with
      /// the melt flow's velocity. The next gather() must look at their
      /// cells (it stops them there), so that a later one does not count
      /// them as members the solid carried into the drop.
      double n_stopped = 0;
      /// The largest speed among the points that solidified, m/s (the
      /// velocity the flow last gave them).
      double     v_solidified = 0;
      Point<dim> lost_at;
    };
    Exchange
    exchange_since_gather() const;

    /// How many of the particle ids @p ids took part in the last gather()
    /// (members; this rank's ids, local count).
    std::size_t
    count_members(const std::vector<types::particle_index> &ids) const
    {
      std::size_t n = 0;
      for (const auto id : ids)
        n += is_member(id);
      return n;
    }

    /// Number of points taking part (this rank).
    std::size_t
    n_points() const
    {
      return true_mass.size();
    }
    /// Where an instability shows first: the member with the largest
    /// speed on this rank, {speed (m/s), its position (dim, m), the members
    /// in its cell, the sum of their true masses over rho h^dim (the cell's
    /// filling by the solid)}; speed -1 without members. Local.
    std::array<double, dim + 3>
    fastest_member() const;
    /// Checkpoint, between two advances of the solid (after scatter()):
    /// what is read before the next gather() rebuilds the flat arrays: the
    /// ids of the points of the last gather (state changes since), the
    /// mass scaling of that gather, and per point in the order of the
    /// arrays its global cell number, stress and plastic strain (cell
    /// fields and probes). Positions, velocities, masses, ... are in the
    /// particles and gathered again.
    void
    save_state(StateWriter &out) const;
    /// Restore it (after a gather() that set the zone mask): each rank
    /// keeps the points of its owned cells, in the saved order; on the
    /// saved number of ranks its own ids of the last gather, on another
    /// the ids of all ranks.
    void
    load_state(std::vector<StateReader> &parts);

  protected:
    /// The membership part of SolidMPM::gather(): copy the state of the solid
    /// points that lie in cells with
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
    gather_members(const std::vector<std::uint8_t> &excluded_cell,
                   const double                     mass_scaling,
                   const bool                       same_members);
    /// Write the flat arrays back to the particles (no re-sorting).
    void
    write_back();

    const BackgroundGrid<dim>    &grid;
    const SolidMaterial          &mat;
    MaterialPoints<dim>          &points;
    static constexpr unsigned int n_stress = 6; // xx yy zz xy xz yz
    bool                          apic;

    // Structure of arrays, one vector per component.
    std::array<std::vector<double>, dim>       x, v, corner;
    std::array<std::vector<double>, dim * dim> C; ///< APIC, row-major, 1/s
    std::vector<double>                        true_mass, volume;
    std::vector<double>                        visc; ///< viscous pressure q, Pa
    std::array<std::vector<double>, n_stress>  sigma;
    std::vector<double>                        eps_p;
    std::vector<std::uint32_t>                 cell, node0;
    /// Where each point lives in the handler's property pool (its local
    /// index), for write_back(), and its particle id.
    std::vector<types::particle_index> handle, member_id;
    /// Cells whose points exchange_since_gather() looks at: those outside
    /// the FE zone and the zone's layer next to them (members never lie
    /// deeper: a member that enters the zone stops the run in the step).
    std::vector<std::uint8_t> exchange_cell;
    /// The handler's layout at the last gather() (for keeping the arrays).
    typename MaterialPoints<dim>::LayoutMark gathered_layout;
    bool                                     gathered = false;
    unsigned long gathers = 0, gathers_kept = 0, gathers_merged = 0;
    /// Cells that points left in the steps since the gather (their cells in
    /// the handler, where scatter() has MaterialPoints look for moves).
    std::vector<std::uint32_t> left_cells;
    /// Array indices of the points that left for another rank since the
    /// last gather (merge_members() drops them).
    std::vector<std::size_t> left_rank_points;
    /// gather()'s copy: the members' pool handles, cells and state, cell
    /// by cell in increasing flat cell index (the order of the arrays).
    void
    copy_members();
    /// gather()'s update of the arrays of the last gather where only some
    /// cells changed: the members of the other cells stay as they are (the
    /// last scatter() wrote them back), those of the changed cells are
    /// read anew; the result equals copy_members().
    void
    merge_members();
    /// The points of local cell @p idx (occupied_cells()[@p c]) that take
    /// part: melted points cleared of their solid state on the way, the
    /// members' (pool handle, cell) appended to @p out.
    void
    find_members(const std::size_t                                    c,
                 std::vector<std::pair<unsigned int, std::uint32_t>> &out);
    /// Reads the state of member @p p (pool handle @p hp in local cell
    /// @p idx) from the pool into the arrays at index @p p.
    void
    read_member(const std::size_t   p,
                const unsigned int  hp,
                const std::uint32_t idx);
    /// (hp, cell) of the members found by find_members(), and the merge's
    /// source of each new entry (an old index, or ~j for found entry j).
    std::vector<std::pair<unsigned int, std::uint32_t>> found;
    std::vector<std::int64_t>                           merge_source;
    /// The merge's buffers (swapped with the arrays: their memory stays).
    std::vector<double>                merge_buffer_double;
    std::vector<std::uint32_t>         merge_buffer_u32;
    std::vector<types::particle_index> merge_buffer_index;
    /// exchange_cell from the mask.
    void
    set_exchange_cells();
    /// set_aside_cells(): the list, its mask per local cell (empty: none
    /// yet), and the cells whose flag changed since the last gather()
    /// (marked; the exchange looks at them, the gather copies anew).
    std::vector<std::uint32_t> aside_cells;
    double                     gather_aside_n = 0, gather_aside_k = 0;
    std::vector<std::uint8_t>  aside, aside_changed_mark;
    std::vector<std::uint32_t> aside_changed;
    bool
    set_aside(const std::size_t idx) const
    {
      return !aside.empty() && aside[idx];
    }
    /// The points of cell @p idx came, went or changed state, or the
    /// cell was set aside or given back, since the last gather().
    bool
    changed_since_gather(const std::size_t idx) const
    {
      return points.cell_changed_since(gathered_layout, idx) ||
             (!aside_changed.empty() && aside_changed_mark[idx]);
    }

    std::vector<std::uint8_t> excluded;    ///< copy of the FE-zone cell mask
    double                    scaling = 1; ///< inertial mass / true_mass
    /// A point changed cells since the last scatter() (set by the step).
    bool moved_cell = false;
    /// With the melt flow: see set_flow_owns_fluid_points().
    bool flow_owns_fluid = false;
    /// The flow owns the fluid points' affine velocity too.
    bool flow_affine = false;

    /// Particle ids of the points of the last gather(): bit id % 64 of
    /// word id / 64 is set (a membership test without a search).
    std::vector<std::uint64_t> member_bits;
    bool
    is_member(const types::particle_index id) const
    {
      const std::size_t w = id / 64;
      return w < member_bits.size() && (member_bits[w] >> (id % 64)) & 1u;
    }
  };
} // namespace femp

#endif
