// femp: explicit finite elements of the constant-solid zone (paper eqs.
// 6-10) on their own parallel::distributed::Triangulation: one-point
// hexahedra/quadrilaterals with Flanagan-Belytschko hourglass forces, lumped
// mass, central difference, transition nodes (eqs. 14-17); see solid_fem.h.
#include <deal.II/base/mpi.h>
#include <deal.II/base/mpi_noncontiguous_partitioner.templates.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/grid/grid_generator.h>

#include <femp/base/input_checks.h>
#include <femp/base/parameter_table.h>
#include <femp/base/state_stream.h>
#include <femp/solid/hourglass.h>
#include <femp/solid/solid_fem.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>
#include <type_traits>
#include <unordered_map>

namespace femp
{
  template <int dim>
  void
  SolidFEM<dim>::Parameters::add_parameters(ParameterTable &table)
  {
    ParameterHandler &prm = table.handler();
    table.enter_subsection("Solid FEM");
    table.add("Use finite elements",
              enabled,
              "Discretize the constant-solid zone below by finite "
              "elements (FEMP). If false, all solid is material "
              "points (all-MPM).");
    if (table.declaring())
      prm.declare_entry(
        "Zone lower corner",
        "0, 0, 0",
        Patterns::Anything(),
        "Lower corner of the box of the finite-element zone, m "
        "(dim coordinates). It must lie on grid lines inside the "
        "domain. Points inside the zone carry temperature only.");
    if (table.declaring())
      prm.declare_entry(
        "Zone upper corner",
        "0, 0, 0",
        Patterns::Anything(),
        "Upper corner of the finite-element zone, m (dim "
        "coordinates); on grid lines, inside the domain, above "
        "the lower corner in every direction. Or 'auto' (3D): "
        "the zone spans the domain horizontally and its top is "
        "the highest grid line at or below 'Material "
        "points/Substrate top' - (1.1 d + 2 cells), d a "
        "conservative melt depth from Rosenthal's moving point "
        "source and its line-source limit sqrt(2 A P / (pi e "
        "rho c_min v (T_s - T0))) for the laser's largest power "
        "P, absorptivity A and speed v, the material's density, "
        "smallest specific heat and conductivity table, solidus "
        "T_s and 'Heat transfer/Initial temperature' T0 "
        "(doc/cases.md). With either choice the run stops if a "
        "finite element reaches the solidus.");
    table.add("Hourglass coefficient",
              hourglass_coefficient,
              Patterns::Double(),
              "kappa of the Flanagan-Belytschko hourglass stiffness "
              "k = kappa M V sum|b_a|^2 / 2^dim, -; range [0, 1]; 0 "
              "(the default) switches hourglass control off. The "
              "stiffness also resists the bending that a track's "
              "thermal expansion imposes on the zone and moves the "
              "stresses near a track away from all-MPM's "
              "(doc/solid.md \"Hourglass control and the thermal "
              "stress\"). With or without control the elements' "
              "corners are checked: a mode that inverts one stops "
              "the run. Use 0.01-0.1 for elements under loads that "
              "drive the zero-energy modes (point or alternating "
              "nodal loads).");
    table.add("Hourglass distortion limit",
              hourglass_distortion_limit,
              Patterns::Double(),
              "Largest change of an element corner's volume ratio "
              "det(dx/dX) that the hourglass modes may make, -; "
              "range (0, 1]. Measured per element at every solid "
              "step as B sum |q| (B = 1 / (2^(dim-1) h), q the "
              "hourglass mode amplitudes, first order); above the "
              "limit the run stops with the element's position. "
              "The modes carry no strain at the element centre, so "
              "they do not show in the stresses or the energies, "
              "but their corner displacements move the zone's "
              "nodes and the points near it. femp's solid is a "
              "small-strain model; the largest value of a run is in "
              "the end report (doc/stability.md). 1 leaves only the "
              "inverted-corner check.");
    table.leave_subsection();
  }

  template <int dim>
  void
  SolidFEM<dim>::Parameters::declare_parameters(ParameterHandler &prm)
  {
    Parameters     defaults;
    ParameterTable table(prm, ParameterTable::Mode::declare);
    defaults.add_parameters(table);
  }

  template <int dim>
  void
  SolidFEM<dim>::Parameters::parse_parameters(ParameterHandler &prm)
  {
    ParameterTable table(prm, ParameterTable::Mode::parse);
    add_parameters(table);
    prm.enter_subsection("Solid FEM");
    if (enabled)
      {
        lower_corner  = parse_point<dim>(prm.get("Zone lower corner"),
                                        "Solid FEM/Zone lower corner");
        automatic_top = Utilities::trim(prm.get("Zone upper corner")) == "auto";
        if (!automatic_top)
          upper_corner = parse_point<dim>(prm.get("Zone upper corner"),
                                          "Solid FEM/Zone upper corner");
      }
    prm.leave_subsection();
    require(hourglass_coefficient >= 0 && hourglass_coefficient <= 1,
            "Solid FEM/Hourglass coefficient",
            hourglass_coefficient,
            "it must lie in [0, 1]");
    require(hourglass_distortion_limit > 0 && hourglass_distortion_limit <= 1,
            "Solid FEM/Hourglass distortion limit",
            hourglass_distortion_limit,
            "it must lie in (0, 1]");
  }

  template <int dim>
  void
  SolidFEM<dim>::Parameters::check(
    const typename BackgroundGrid<dim>::Parameters &g) const
  {
    if (!enabled)
      return;
    require(!automatic_top || upper_corner[dim - 1] > lower_corner[dim - 1],
            "Solid FEM/Zone upper corner",
            "auto",
            "the estimated melt depth leaves no finite element above the "
            "zone's lower corner: use a deeper substrate, or all-MPM "
            "(Use finite elements = false)");
    for (int d = 0; d < dim; ++d)
      {
        for (int c = 0; c < 2; ++c)
          {
            const double      x    = c == 0 ? lower_corner[d] : upper_corner[d];
            const double      r    = (x - g.lower_corner[d]) / g.cell_size;
            const std::string name = std::string("Solid FEM/Zone ") +
                                     (c == 0 ? "lower" : "upper") + " corner";
            require(std::abs(r - std::round(r)) < 1e-6,
                    name,
                    x,
                    "every coordinate must lie on a grid line (lower corner "
                    "of the domain plus a whole number of cells)");
            require(x >= g.lower_corner[d] - 1e-12 * g.cell_size &&
                      x <= g.upper_corner[d] + 1e-12 * g.cell_size,
                    name,
                    x,
                    "it must lie inside the domain");
          }
        require(upper_corner[d] > lower_corner[d],
                "Solid FEM/Zone upper corner",
                upper_corner[d],
                "it must exceed the lower corner in every direction");
      }
  }

  namespace
  {
    using hourglass::mode_mask;

    /// In-place Walsh-Hadamard transform over the 2^dim corners (bit d of
    /// the corner index: upper side in direction d): x_m <- sum_a H_ma x_a
    /// with H_ma = prod_{d in m} s_a,d. Per stage (lo, hi) -> (lo + hi,
    /// hi - lo).
    template <int dim, typename Number>
    inline void
    fwht(Number (&x)[1u << dim][dim])
    {
#pragma GCC unroll 4
      for (int d = 0; d < dim; ++d)
#pragma GCC unroll 8
        for (unsigned int a = 0; a < (1u << dim); ++a)
          if (!((a >> d) & 1u))
            for (int i = 0; i < dim; ++i)
              {
                const Number lo = x[a][i], hi = x[a | (1u << d)][i];
                x[a][i]             = lo + hi;
                x[a | (1u << d)][i] = hi - lo;
              }
    }
    /// Transposed transform: f_a = sum_m H_ma C_m; per stage (lo, hi) ->
    /// (lo - hi, lo + hi).
    template <int dim, typename Number>
    inline void
    fwht_transpose(Number (&x)[1u << dim][dim])
    {
#pragma GCC unroll 4
      for (int d = 0; d < dim; ++d)
#pragma GCC unroll 8
        for (unsigned int a = 0; a < (1u << dim); ++a)
          if (!((a >> d) & 1u))
            for (int i = 0; i < dim; ++i)
              {
                const Number lo = x[a][i], hi = x[a | (1u << d)][i];
                x[a][i]             = lo - hi;
                x[a | (1u << d)][i] = lo + hi;
              }
    }

    /// Index of stress component (i, j) in {xx, yy, zz, xy, xz, yz}.
    constexpr unsigned int
    sidx(const unsigned int i, const unsigned int j)
    {
      return i == j ? i : 2 + i + j; // xy -> 3, xz -> 4, yz -> 5
    }
  } // namespace

  template <int dim>
  SolidFEM<dim>::SolidFEM(const Parameters          &prm,
                          const BackgroundGrid<dim> &grid,
                          const SolidMaterial       &material)
      : prm(prm)
      , grid(grid)
      , mat(material)
      , comm(grid.communicator())
      , tria(grid.communicator())
      , fe(1)
  {
    Assert(prm.enabled,
           ExcMessage("SolidFEM is built only for an FE zone "
                      "that is switched on"));
  }

  template <int dim>
  void
  SolidFEM<dim>::setup(const double                             mass_scaling,
                       const std::array<std::uint8_t, 2 * dim> &face_bits,
                       const Tensor<1, dim>                    &gravity,
                       const std::vector<double>               &T)
  {
    mass_scale     = mass_scaling;
    g              = gravity;
    face_fix       = face_bits;
    const double h = grid.h();
    V              = std::pow(h, dim);
    const double b = 1. / (std::pow(2., dim - 1) * h);
    bb             = n_corners * dim * b * b;
    in_zone_cell.assign(grid.n_local(), 0);
    set_zone();
    create_mesh();
    const double m_el = mat.density() * V * mass_scaling / n_corners;
    std::vector<std::array<int, dim>> node_ijk(n_local);
    const auto                        cells = local_elements(node_ijk);
    set_node_box(node_ijk);
    set_elements(cells);
    allocate_node_arrays();
    const auto mass = lumped_masses(m_el);
    set_transition_nodes(face_bits, m_el, mass, node_ijk);
    set_temperature_exchange(T);
    element_loop<false>(0, 1);
  }

  template <int dim>
  std::uint64_t
  SolidFEM<dim>::zone_cell_id(const std::array<int, dim> &ijk) const
  {
    std::uint64_t id = 0;
    for (int d = dim - 1; d >= 0; --d)
      id = id * zn[d] + (ijk[d] - zlo[d]);
    return id;
  }

  template <int dim>
  std::uint64_t
  SolidFEM<dim>::zone_node_id(const std::array<int, dim> &ijk) const
  {
    std::uint64_t id = 0;
    for (int d = dim - 1; d >= 0; --d)
      id = id * (zn[d] + 1) + (ijk[d] - zlo[d]);
    return id;
  }

  template <int dim>
  std::array<unsigned int, 2>
  SolidFEM<dim>::cells_around(const std::array<int, dim> &ijk) const
  {
    // The 2^dim cells that share the node, those inside the domain: in the
    // zone, and not.
    const auto                 &N = grid.n_cells();
    std::array<unsigned int, 2> count{{0, 0}};
    for (unsigned int a = 0; a < n_corners; ++a)
      {
        std::array<int, dim> c;
        bool                 inside = true;
        for (int d = 0; d < dim; ++d)
          {
            c[d]   = ijk[d] - 1 + int((a >> d) & 1u);
            inside = inside && c[d] >= 0 && c[d] < int(N[d]);
          }
        if (inside)
          ++count[zone.contains_cell(c) ? 0 : 1];
      }
    return count;
  }

  template <int dim>
  bool
  SolidFEM<dim>::is_transition(const std::array<int, dim> &ijk) const
  {
    // A node of an element that touches a cell of the domain outside the
    // zone (for a box: a zone node on a zone face that is not a domain
    // face).
    const auto n = cells_around(ijk);
    return n[0] > 0 && n[1] > 0;
  }

  template <int dim>
  std::uint8_t
  SolidFEM<dim>::fix_bits(
    const std::array<int, dim>              &ijk,
    const std::array<std::uint8_t, 2 * dim> &face_bits) const
  {
    const auto  &N = grid.n_cells();
    std::uint8_t f = 0;
    for (int d = 0; d < dim; ++d)
      {
        if (ijk[d] == 0)
          f |= face_bits[2 * d];
        if (ijk[d] == int(N[d]))
          f |= face_bits[2 * d + 1];
      }
    return f;
  }

  template <int dim>
  void
  SolidFEM<dim>::set_zone()
  {
    if (!zone_given)
      zone = FeZone<dim>(
        true, prm.lower_corner, prm.upper_corner, grid.origin(), grid.h());
    zlo = zone.first_cell();
    zn  = zone.n_cells();
    for (std::size_t idx = 0; idx < grid.n_local(); ++idx)
      if (grid.cell_status()[idx] != BackgroundGrid<dim>::outside)
        in_zone_cell[idx] = zone.contains_cell(grid.global_index(idx));
  }

  template <int dim>
  void
  SolidFEM<dim>::create_mesh()
  {
    // The FE triangulation: coarse blocks of 2^r cells (largest r <= 3 that
    // divides every cell count), refined r times; p4est partitions it.
    unsigned int r = 3;
    for (; r > 0; --r)
      {
        bool ok = true;
        for (int d = 0; d < dim; ++d)
          ok = ok && zn[d] % (1 << r) == 0;
        if (ok)
          break;
      }
    std::vector<unsigned int> reps(dim);
    for (int d = 0; d < dim; ++d)
      reps[d] = zn[d] >> r;
    dof_handler.reset();
    tria.clear();
    GridGenerator::subdivided_hyper_rectangle(tria,
                                              reps,
                                              prm.lower_corner,
                                              prm.upper_corner);
    tria.refine_global(r);
    dof_handler = std::make_unique<DoFHandler<dim>>(tria);
    dof_handler->distribute_dofs(fe);
    const IndexSet &owned = dof_handler->locally_owned_dofs();
    IndexSet        ghosts;
    DoFTools::extract_locally_active_dofs(*dof_handler, ghosts);
    ghosts.subtract_set(owned);
    node_partitioner =
      std::make_shared<Utilities::MPI::Partitioner>(owned, ghosts, comm);
    n_owned = owned.n_elements();
    n_local = n_owned + ghosts.n_elements();
    {
      IndexSet vo(dim * dof_handler->n_dofs()), vg(dim * dof_handler->n_dofs());
      if (n_owned > 0)
        vo.add_range(dim * owned.nth_index_in_set(0),
                     dim * (owned.nth_index_in_set(n_owned - 1) + 1));
      for (const auto i : ghosts)
        vg.add_range(dim * i, dim * i + dim);
      force.reinit(std::make_shared<Utilities::MPI::Partitioner>(vo, vg, comm));
    }
  }

  // Elements in lexicographic order of their zone index (x fastest), and
  // the structured index of each local node.
  template <int dim>
  std::vector<std::pair<std::uint64_t, std::array<std::uint32_t, (1u << dim)>>>
  SolidFEM<dim>::local_elements(std::vector<std::array<int, dim>> &node_ijk)
  {
    std::vector<std::pair<std::uint64_t, std::array<std::uint32_t, n_corners>>>
                                         cells;
    std::vector<types::global_dof_index> dofs(n_corners);
    off_rank = 0;
    for (const auto &cell : dof_handler->active_cell_iterators())
      if (cell->is_locally_owned())
        {
          const auto ijk = grid.cell_of(cell->center());
          cell->get_dof_indices(dofs);
          std::array<std::uint32_t, n_corners> c;
          for (unsigned int a = 0; a < n_corners; ++a)
            {
              c[a] = node_partitioner->global_to_local(dofs[a]);
              for (int d = 0; d < dim; ++d)
                node_ijk[c[a]][d] = ijk[d] + ((a >> d) & 1u);
            }
          // A cell of the bounding box outside the zone is no element (its
          // nodes stay in the node box; without an element they carry no
          // mass and no velocity).
          if (!zone.contains_cell(ijk))
            continue;
          if (!grid.in_box(ijk) || grid.cell_status()[grid.local_index(ijk)] !=
                                     BackgroundGrid<dim>::owned)
            ++off_rank;
          cells.emplace_back(zone_cell_id(ijk), c);
        }
    std::sort(cells.begin(), cells.end(), [](const auto &a, const auto &b) {
      return a.first < b.first;
    });
    return cells;
  }

  template <int dim>
  void
  SolidFEM<dim>::set_node_box(const std::vector<std::array<int, dim>> &node_ijk)
  {
    // The node box: bounding box of the local nodes' structured indices.
    multi_rank = Utilities::MPI::n_mpi_processes(comm) > 1;
    for (int d = 0; d < dim; ++d)
      {
        int lo = std::numeric_limits<int>::max(), hi = -1;
        for (const auto &ijk : node_ijk)
          lo = std::min(lo, ijk[d]), hi = std::max(hi, ijk[d]);
        box_lo[d] = n_local > 0 ? lo : 0;
        box_n[d]  = n_local > 0 ? hi - lo + 1 : 0;
      }
    std::size_t n_slots = 1;
    for (int d = 0; d < dim; ++d)
      box_stride[d] = n_slots, n_slots *= box_n[d];
    n_box          = (n_slots + simd_lanes - 1) / simd_lanes * simd_lanes;
    auto box_index = [&](const std::array<int, dim> &ijk) {
      std::size_t n = 0;
      for (int d = 0; d < dim; ++d)
        n += (ijk[d] - box_lo[d]) * box_stride[d];
      return std::uint32_t(n);
    };
    box_of.resize(n_local);
    for (std::size_t ln = 0; ln < n_local; ++ln)
      box_of[ln] = box_index(node_ijk[ln]);
    AssertThrow(n_box < std::numeric_limits<std::uint32_t>::max(),
                ExcMessage("FE node box too large for 32-bit node indices"));
  }

  template <int dim>
  void
  SolidFEM<dim>::set_elements(
    const std::vector<
      std::pair<std::uint64_t, std::array<std::uint32_t, (1u << dim)>>> &cells)
  {
    const std::size_t n_el = cells.size();
    conn.resize(n_corners * n_el);
    element_id.resize(n_el);
    for (std::size_t e = 0; e < n_el; ++e)
      {
        element_id[e] = cells[e].first;
        for (unsigned int a = 0; a < n_corners; ++a)
          conn[n_corners * e + a] = box_of[cells[e].second[a]];
      }
    element_by_id.clear();
    for (std::size_t e = 0; e < n_el; ++e)
      element_by_id.emplace_back(element_id[e], e);
    blocks.assign((n_el + simd_lanes - 1) / simd_lanes, ElementBlock());
    // Blocks of simd_lanes elements of one x-row: consecutive zone indices
    // that do not wrap to the next row.
    block_row.assign(blocks.size(), -1);
    for (std::size_t b = 0; b < blocks.size(); ++b)
      {
        const std::size_t e0 = simd_lanes * b;
        if (e0 + simd_lanes > n_el)
          continue;
        const std::uint64_t id0 = element_id[e0];
        if (element_id[e0 + simd_lanes - 1] == id0 + simd_lanes - 1 &&
            id0 % zn[0] + simd_lanes <= std::uint64_t(zn[0]))
          block_row[b] = conn[n_corners * e0];
      }
  }

  template <int dim>
  void
  SolidFEM<dim>::allocate_node_arrays()
  {
    // Node arrays over the box.
    for (int d = 0; d < dim; ++d)
      {
        vel[d].assign(n_box, 0.);
        frc[d].assign(n_box, 0.);
        ext[d].assign(n_box, 0.);
      }
    fix.assign(n_box, 0xff);
    inv_mass.assign(n_box, 0.);
    owned_mass.assign(n_box, 0.);
    node_zone_id.assign(n_box, std::numeric_limits<std::uint64_t>::max());
    ext_nodes.clear();
    kinetic = 0;
    if (multi_rank)
      {
        std::vector<std::uint32_t> s;
        for (const auto &range : node_partitioner->import_indices())
          for (unsigned int i = range.first; i < range.second; ++i)
            s.push_back(i);
        for (std::size_t ln = n_owned; ln < n_local; ++ln)
          s.push_back(ln);
        std::sort(s.begin(), s.end());
        s.erase(std::unique(s.begin(), s.end()), s.end());
        shared_nodes = s;
      }
    else
      shared_nodes.clear();
  }

  template <int dim>
  std::vector<double>
  SolidFEM<dim>::lumped_masses(const double m_el)
  {
    // Lumped masses: element shares summed over ranks.
    for (const auto n : conn)
      for (int d = 0; d < dim; ++d)
        frc[d][n] += m_el;
    sum_shared(frc);
    std::vector<double> mass(n_box, 0.);
    for (std::size_t ln = 0; ln < n_local; ++ln)
      mass[box_of[ln]] = frc[0][box_of[ln]];
    for (int d = 0; d < dim; ++d)
      std::fill(frc[d].begin(), frc[d].end(), 0.);
    return mass;
  }

  template <int dim>
  void
  SolidFEM<dim>::set_transition_nodes(
    const std::array<std::uint8_t, 2 * dim> &face_bits,
    const double                             m_el,
    const std::vector<double>               &mass,
    const std::vector<std::array<int, dim>> &node_ijk)
  {
    const std::size_t n_el = element_id.size();
    // Transition nodes, numbered on every rank in lexicographic order of
    // the zone's nodes.
    std::vector<std::uint64_t> tr_id;
    tr_ijk.clear(), tr_mass.clear(), tr_fix.clear();
    {
      std::array<int, dim> ijk;
      std::uint64_t        n_nodes = 1;
      for (int d = 0; d < dim; ++d)
        n_nodes *= zn[d] + 1;
      for (std::uint64_t id = 0; id < n_nodes; ++id)
        {
          std::uint64_t r = id;
          for (int d = 0; d < dim; ++d)
            {
              ijk[d] = zlo[d] + int(r % (zn[d] + 1));
              r /= zn[d] + 1;
            }
          if (!is_transition(ijk))
            continue;
          tr_id.push_back(id);
          tr_ijk.push_back(ijk);
          tr_fix.push_back(fix_bits(ijk, face_bits));
          tr_mass.push_back(cells_around(ijk)[0] * m_el); // its elements
        }
    }
    tr_vel.assign(dim * tr_ijk.size(), 0.);
    tr_disp.assign(dim * tr_ijk.size(), 0.);
    tr_hg.assign(dim * tr_ijk.size(), 0.);
    tr_local.clear();
    for (std::size_t ln = 0; ln < n_local; ++ln)
      {
        const std::uint32_t n = box_of[ln];
        node_zone_id[n]       = zone_node_id(node_ijk[ln]);
        const auto it =
          std::lower_bound(tr_id.begin(), tr_id.end(), node_zone_id[n]);
        const bool tr = it != tr_id.end() && *it == node_zone_id[n];
        if (tr)
          tr_local.emplace_back(n, it - tr_id.begin());
        if (ln < n_owned)
          owned_mass[n] = mass[n];
        // Transition nodes take their velocity from update_transition():
        // zero inverse mass, all components free (fixed ones are zero there).
        // A node of no element (cells of the bounding box outside the zone
        // only) has no mass: zero inverse mass, all components fixed.
        const bool massless = !tr && !(mass[n] > 0);
        inv_mass[n]         = tr || massless ? 0. : 1. / mass[n];
        fix[n] = tr ? 0 : massless ? 0xff : fix_bits(node_ijk[ln], face_bits);
      }
    std::sort(tr_local.begin(), tr_local.end());
    std::vector<int> box_tr(n_box, -1);
    for (const auto &[n, t] : tr_local)
      box_tr[n] = t;
    tr_corners.clear();
    for (std::size_t e = 0; e < n_el; ++e)
      for (unsigned int a = 0; a < n_corners; ++a)
        if (box_tr[conn[n_corners * e + a]] >= 0)
          tr_corners.push_back(
            {{std::uint32_t(e),
              a,
              std::uint32_t(box_tr[conn[n_corners * e + a]])}});
  }

  template <int dim>
  void
  SolidFEM<dim>::set_temperature_exchange(const std::vector<double> &T)
  {
    const std::size_t n_el = element_id.size();
    // Temperatures: the grid rank owning a zone cell sends it (eq. 2).
    grid_zone_cells.clear();
    std::vector<types::global_dof_index> send_ids,
      recv_ids(element_id.begin(), element_id.end());
    for (const auto c : grid.owned_cells())
      if (in_zone_cell[c])
        {
          grid_zone_cells.push_back(c);
          send_ids.push_back(zone_cell_id(grid.global_index(c)));
        }
    T_exchange.reinit(send_ids, recv_ids, comm);
    T_send.resize(grid_zone_cells.size());
    T_end.assign(n_el, 0.);
    new_temperatures(T);
    T_start = T_end;
    for (std::size_t b = 0; b < blocks.size(); ++b)
      for (unsigned int l = 0; l < simd_lanes; ++l)
        blocks[b].T[l] = T_end[std::min(simd_lanes * b + l, n_el - 1)];
  }

  template <int dim>
  void
  SolidFEM<dim>::new_temperatures(const std::vector<double> &T)
  {
    T_start = T_end;
    for (std::size_t i = 0; i < grid_zone_cells.size(); ++i)
      T_send[i] = T[grid_zone_cells[i]];
    T_exchange.export_to_ghosted_array(ArrayView<const double>(T_send),
                                       ArrayView<double>(T_end));
  }

  template <int dim>
  void
  SolidFEM<dim>::set_external_forces(
    const std::array<std::vector<double>, dim> *f)
  {
    if (f == nullptr && ext_nodes.empty())
      return;
    for (const auto n : ext_nodes)
      for (int d = 0; d < dim; ++d)
        ext[d][n] = 0;
    ext_nodes.clear();
    if (f == nullptr)
      return;
    // Grid nodes of owned cells inside the zone, not transition nodes (those
    // get the grid's forces through the grid): (zone node id, force).
    std::vector<double> mine;
    const auto         &lo = grid.box_lower();
    const auto         &ns = grid.node_strides();
    for (const auto n : grid.owned_cell_nodes())
      {
        std::array<int, dim> ijk;
        std::size_t          r = n;
        for (int d = dim - 1; d >= 0; --d)
          {
            ijk[d] = lo[d] + static_cast<int>(r / ns[d]);
            r %= ns[d];
          }
        bool          in = true, nonzero = false;
        std::uint64_t id = 0;
        for (int d = dim - 1; d >= 0; --d)
          {
            in = in && ijk[d] >= zlo[d] && ijk[d] <= zlo[d] + zn[d];
            id = id * (zn[d] + 1) + (ijk[d] - zlo[d]);
          }
        for (int d = 0; d < dim; ++d)
          nonzero = nonzero || (*f)[d][n] != 0;
        if (!in || !nonzero)
          continue;
        const auto around = cells_around(ijk);
        if (around[0] == 0 || around[1] > 0) // no element, or transition
          continue;
        mine.push_back(double(id));
        for (int d = 0; d < dim; ++d)
          mine.push_back((*f)[d][n]);
      }
    const auto all = Utilities::MPI::all_gather(comm, mine);
    // Local FE nodes (owned and ghost: every rank that updates a node adds
    // the same external force after the sum over ranks) by zone node id.
    std::vector<std::pair<std::uint64_t, std::uint32_t>> ids;
    for (std::size_t ln = 0; ln < n_local; ++ln)
      ids.emplace_back(node_zone_id[box_of[ln]], box_of[ln]);
    std::sort(ids.begin(), ids.end());
    for (const auto &v : all)
      for (std::size_t i = 0; i < v.size(); i += dim + 1)
        {
          const auto id = std::uint64_t(v[i]);
          const auto it =
            std::lower_bound(ids.begin(),
                             ids.end(),
                             std::make_pair(id, std::uint32_t(0)));
          if (it == ids.end() || it->first != id)
            continue;
          ext_nodes.push_back(it->second);
          for (int d = 0; d < dim; ++d)
            ext[d][it->second] += v[i + 1 + d];
        }
    std::sort(ext_nodes.begin(), ext_nodes.end());
    ext_nodes.erase(std::unique(ext_nodes.begin(), ext_nodes.end()),
                    ext_nodes.end());
  }

  template <int dim>
  void
  SolidFEM<dim>::sum_shared(std::array<std::vector<double>, dim> &f)
  {
    if (!multi_rank)
      return;
    double *F = force.begin();
    for (const auto ln : shared_nodes)
      for (int d = 0; d < dim; ++d)
        F[dim * ln + d] = f[d][box_of[ln]];
    force.compress(VectorOperation::add);
    force.update_ghost_values();
    for (const auto ln : shared_nodes)
      for (int d = 0; d < dim; ++d)
        f[d][box_of[ln]] = F[dim * ln + d];
  }

  template <int dim>
  void
  SolidFEM<dim>::add_transition_partials(std::vector<double> &buf) const
  {
    for (const auto &[n, t] : tr_local)
      for (int d = 0; d < dim; ++d)
        buf[tr_width * t + 1 + dim + d] += frc[d][n] - tr_hg[dim * t + d];
    for (std::size_t t = 0; t < tr_ijk.size(); ++t)
      for (int d = 0; d < dim; ++d)
        buf[tr_width * t + 1 + 2 * dim + d] += tr_hg[dim * t + d];
  }

  template <int dim>
  void
  SolidFEM<dim>::update_transition(const std::vector<double> &buf,
                                   const double               dt,
                                   std::vector<double>       &v_grid,
                                   std::vector<double>       &a_grid)
  {
    v_grid.resize(dim * tr_ijk.size());
    a_grid.resize(dim * tr_ijk.size());
    for (std::size_t t = 0; t < tr_ijk.size(); ++t)
      {
        const double *b = &buf[tr_width * t];
        const double  m = b[0] + tr_mass[t];
        for (int d = 0; d < dim; ++d)
          {
            double &v = tr_vel[dim * t + d];
            if (tr_fix[t] & (1u << d))
              {
                v_grid[dim * t + d] = a_grid[dim * t + d] = v = 0;
                continue;
              }
            const double f      = b[1 + dim + d];
            const double p      = b[1 + d] + tr_mass[t] * v + dt * f;
            a_grid[dim * t + d] = f / m;
            v_grid[dim * t + d] = p / m;
            v                   = p / m + dt * b[1 + 2 * dim + d] / tr_mass[t];
            tr_disp[dim * t + d] += dt * v;
          }
      }
  }

  template <int dim>
  std::array<double, 4>
  SolidFEM<dim>::update_nodes(const double dt)
  {
    // Element forces summed over ranks; velocities of the transition
    // nodes (zero inverse mass below keeps them).
    sum_shared(frc);
    for (const auto &[n, t] : tr_local)
      for (int d = 0; d < dim; ++d)
        vel[d][n] = tr_vel[dim * t + d];
    damped = 0;
    if (node_damping > 0)
      return ext_nodes.empty() ? node_loop<false, true>(dt) :
                                 node_loop<true, true>(dt);
    return ext_nodes.empty() ? node_loop<false, false>(dt) :
                               node_loop<true, false>(dt);
  }

  /// The node update over the box in SIMD: v <- v + dt (f + f_ext) / m
  /// masked to zero in fixed components (eq. 10), the force zeroed for the
  /// next element loop, kinetic energy, external power (gravity on the
  /// unscaled mass, external forces) of the owned nodes, and their sums
  /// m v_old . dv and m dv . dv (dv = v_new - v_old) for the leapfrog's
  /// half-step term (SolidEnergies::half_step). With @p damp the nodes of
  /// nonzero inverse mass then lose node_damping of their velocity (the
  /// half-step sums stay those of the force), the kinetic energy taken out
  /// summed into `damped`.
  template <int dim>
  template <bool with_ext, bool damp>
  std::array<double, 4>
  SolidFEM<dim>::node_loop(const double dt)
  {
    using VD = simd_double;
    typedef std::int64_t   VI __attribute__((vector_size(sizeof(VD))));
    typedef std::uint8_t   VB __attribute__((vector_size(simd_lanes)));
    constexpr unsigned int W    = simd_lanes;
    auto                   load = [](const auto *p) {
      std::conditional_t<std::is_same_v<std::decay_t<decltype(*p)>, double>,
                         VD,
                         VI>
        v;
      std::memcpy(&v, p, sizeof v);
      return v;
    };
    VD       k = {}, p = {}, hx = {}, hy = {}, kd = {};
    const VD zero = {}, beta = zero + node_damping;
    for (std::size_t n = 0; n < n_box; n += W)
      {
        const VD im = dt * load(&inv_mass[n]);
        VD       b = {}, rd = {};
        if constexpr (damp)
          b = VD(VI(beta) & (im > zero));
        VB fb;
        std::memcpy(&fb, &fix[n], sizeof fb);
        const VI fi = __builtin_convertvector(fb, VI);
        VD       v[dim], xv = {}, yv = {};
        for (int d = 0; d < dim; ++d)
          {
            VD f = load(&frc[d][n]);
            if constexpr (with_ext)
              f += load(&ext[d][n]);
            const VI free = (fi & (1 << d)) == 0;
            const VD vo   = load(&vel[d][n]);
            v[d]          = VD(VI(vo + im * f) & free);
            xv += vo * (v[d] - vo);
            yv += (v[d] - vo) * (v[d] - vo);
            if constexpr (damp)
              {
                const VD vd = b * v[d];
                rd += vd * (2 * v[d] - vd);
                v[d] -= vd;
              }
            std::memcpy(&vel[d][n], &v[d], sizeof(VD));
            std::memcpy(&frc[d][n], &zero, sizeof(VD));
          }
        VD v2 = {}, gv = {}, fv = {};
        for (int d = 0; d < dim; ++d)
          {
            v2 += v[d] * v[d];
            gv += g[d] * v[d];
            if constexpr (with_ext)
              fv += load(&ext[d][n]) * v[d];
          }
        const VD m = load(&owned_mass[n]);
        k += 0.5 * m * v2;
        if constexpr (damp)
          kd += 0.5 * m * rd;
        hx += m * xv;
        hy += m * yv;
        if constexpr (with_ext)
          p += m / mass_scale * gv + (m > 0 ? fv : zero);
        else
          p += m / mass_scale * gv;
      }
    double ks = 0, ps = 0, xs = 0, ys = 0;
    for (unsigned int l = 0; l < W; ++l)
      ks += k[l], ps += p[l], xs += hx[l], ys += hy[l], damped += kd[l];
    kinetic = ks;
    return {{ks, ps, xs, ys}};
  }

  template <int dim>
  double
  SolidFEM<dim>::update_elements(const double dt, const double w)
  {
    return element_loop<true>(dt, w);
  }

  template <int dim>
  typename SolidFEM<dim>::LoopConstants
  SolidFEM<dim>::loop_constants(const double dt) const
  {
    const double  h    = grid.h();
    const double  B    = 1. / (std::pow(2., dim - 1) * h);
    const double  nu   = mat.poisson_ratio;
    const double  mfac = (1 - nu) / ((1 + nu) * (1 - 2 * nu));
    LoopConstants c;
    c.Bdt  = B * dt;
    c.hgB  = B;
    c.VB   = V * B;
    c.kfac = prm.hourglass_coefficient * mfac * V * bb / n_corners;
    c.vfac = mat.bulk_viscosity * h *
             std::sqrt(mfac * mat.density() * mass_scale) / (dt > 0 ? dt : 1.);
    for (int d = 0; d < dim; ++d)
      c.mg[d] = mat.density() * V / n_corners * g[d];
    return c;
  }

  template <int dim>
  std::size_t
  SolidFEM<dim>::corner_row_offset(const unsigned int a) const
  {
    // Box offset of corner a (bit d: upper side in direction d) from
    // corner 0, in the directions other than x.
    std::size_t o = 0;
    for (int d = 1; d < dim; ++d)
      o += ((a >> d) & 1u) * box_stride[d];
    return o;
  }

  // Gather pass: the velocities of the corners of block b (lanes el) as
  // coefficients of the Walsh-Hadamard transform over the corners:
  // coefficient m of x is sum_a (prod_{d in m} s_a,d) x_a, so the one-bit
  // coefficients give the velocity gradient (b_a = s_a B) and the
  // coefficients with two or more bits the hourglass modes (Gamma =
  // products of s).
  template <int dim>
  [[gnu::always_inline]] inline void
  SolidFEM<dim>::gather_velocities(const std::size_t b,
                                   const std::size_t (&el)[simd_lanes],
                                   const double *const (&vl)[dim],
                                   simd_double (&Vc)[n_corners][dim]) const
  {
    using VD                  = simd_double;
    constexpr unsigned int nc = n_corners;
    static_assert(simd_lanes == 4, "the gathers below are written for 4 lanes");
    if (block_row[b] >= 0)
    // One x-row: corner a (x-lower, bit 0 clear) of lane l is node
    // row(a) + l, corner a + 1 node row(a) + l + 1.
#pragma GCC unroll 4
      for (unsigned int a = 0; a < nc; a += 2)
        {
          const std::size_t r = block_row[b] + corner_row_offset(a);
          for (int i = 0; i < dim; ++i)
            {
              std::memcpy(&Vc[a][i], vl[i] + r, sizeof(VD));
              std::memcpy(&Vc[a + 1][i], vl[i] + r + 1, sizeof(VD));
            }
        }
    else
      {
        const std::uint32_t *c0 = &conn[nc * el[0]], *c1 = &conn[nc * el[1]],
                            *c2 = &conn[nc * el[2]], *c3 = &conn[nc * el[3]];
#pragma GCC unroll 8
        for (unsigned int a = 0; a < nc; ++a)
          for (int i = 0; i < dim; ++i)
            Vc[a][i] =
              VD{vl[i][c0[a]], vl[i][c1[a]], vl[i][c2[a]], vl[i][c3[a]]};
      }
    fwht<dim>(Vc);
  }

  // Constitutive pass of block @p eb over the step dt: hourglass mode
  // amplitudes q_alpha += dt Gamma_alpha . v (kept per element), the
  // temperature at weight w of the advance, E(T_new) read once (for the
  // constitutive kernel, the hourglass stiffness and the viscous pressure:
  // returned in E), the velocity gradient, the stress update (eq. 5), the
  // new viscous pressure; sb holds the new stress. Returns the stress work
  // of each lane, (sigma_old + sigma_new)/2 : L V plus the viscous work.
  template <int dim>
  [[gnu::always_inline]] inline simd_double
  SolidFEM<dim>::update_block(ElementBlock &eb,
                              const std::size_t (&el)[simd_lanes],
                              const unsigned int nl,
                              const simd_double (&Vc)[n_corners][dim],
                              const double         dt,
                              const double         w,
                              const LoopConstants &c,
                              StressBlock         &sb,
                              simd_double         &E) const
  {
    using VD                 = simd_double;
    constexpr unsigned int W = simd_lanes;
    for (unsigned int al = 0; al < n_hg; ++al)
      for (int i = 0; i < dim; ++i)
        eb.q[al][i] += dt * Vc[mode_mask<dim>(al)][i];
    VD Ts, Te;
    if (nl == W)
      {
        std::memcpy(&Ts, &T_start[el[0]], sizeof(VD));
        std::memcpy(&Te, &T_end[el[0]], sizeof(VD));
      }
    else
      {
        Ts = VD{T_start[el[0]], T_start[el[1]], T_start[el[2]], T_start[el[3]]};
        Te = VD{T_end[el[0]], T_end[el[1]], T_end[el[2]], T_end[el[3]]};
      }
    sb.T_old = eb.T;
    sb.T_new = Ts + w * (Te - Ts);
    auto Ef  = [&](const unsigned int l) {
      return mat.youngs_modulus.value(sb.T_new[l]);
    };
    sb.E = E = VD{Ef(0), Ef(1), Ef(2), Ef(3)};
    auto Eo  = [&](const unsigned int l) {
      return mat.youngs_modulus.value(sb.T_old[l]);
    };
    sb.E_old = VD{Eo(0), Eo(1), Eo(2), Eo(3)};
    sb.eps_p = eb.eps_p;
    VD trL   = {};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        sb.L[i][j] = i < dim && j < dim ? c.Bdt * Vc[1u << j][i] : VD{};
    for (int i = 0; i < dim; ++i)
      trL += sb.L[i][i];
    update_stress_block(mat, sb);
    // Stress work (sigma_old + sigma_new)/2 : L, symmetric parts summed in
    // two independent chains; the new viscous pressure.
    VD sd = {}, so = {};
    for (int i = 0; i < dim; ++i)
      {
        sd += (eb.s[i] + sb.s[i]) * sb.L[i][i];
        for (int j = i + 1; j < dim; ++j)
          so +=
            (eb.s[sidx(i, j)] + sb.s[sidx(i, j)]) * (sb.L[i][j] + sb.L[j][i]);
      }
    const VD sw = sd + so;
    const VD wk = 0.5 * V * sw + V * eb.visc * trL;
    if (mat.bulk_viscosity > 0)
      eb.visc = c.vfac * simd_sqrt(E) * trL;
    eb.dJ += trL + eb.dJ * trL; // J <- J (1 + tr L dt)
    for (unsigned int k = 0; k < 6; ++k)
      eb.s[k] = sb.s[k];
    eb.eps_p = sb.eps_p;
    eb.T     = sb.T_new;
    return wk;
  }

  // Force and scatter pass: the corner forces of the next step of block b
  // (stress @p s, Young's modulus @p E, viscous pressure and hourglass
  // amplitudes of the block) as coefficients of the same transform:
  // gravity (m = 0), internal force -V sigma b_a with the viscous pressure
  // (one-bit m, eq. 9), hourglass -k Gamma q (the others); the transposed
  // transform gives the corner forces, added to the nodes.
  template <int dim>
  [[gnu::always_inline]] inline void
  SolidFEM<dim>::scatter_forces(const std::size_t  b,
                                const unsigned int nl,
                                const simd_double (&s)[6],
                                const simd_double    E,
                                const LoopConstants &c,
                                double *const (&F)[dim])
  {
    using VD                  = simd_double;
    constexpr unsigned int W  = simd_lanes;
    constexpr unsigned int nc = n_corners;
    const ElementBlock    &eb = blocks[b];
    const VD               k  = c.kfac * E;
    VD                     C[nc][dim];
    for (unsigned int al = 0; al < n_hg; ++al)
      for (int i = 0; i < dim; ++i)
        C[mode_mask<dim>(al)][i] = -k * eb.q[al][i];
    for (int i = 0; i < dim; ++i)
      {
        C[0][i] = VD{} + c.mg[i];
        for (int j = 0; j < dim; ++j)
          C[1u << j][i] = -c.VB * (s[sidx(i, j)] + (i == j ? eb.visc : VD{}));
      }
    fwht_transpose<dim>(C);
    if (block_row[b] >= 0)
    // One x-row: the nodes row(a) + 0..W of a corner pair (a, a + 1) get
    // C_a from lane l at node l and C_a+1 at node l + 1, added as one
    // vector (no two lanes write the same node) and the last one.
#pragma GCC unroll 4
      for (unsigned int a = 0; a < nc; a += 2)
        {
          const std::size_t r = block_row[b] + corner_row_offset(a);
          for (int i = 0; i < dim; ++i)
            {
              const VD hi = C[a + 1][i];
              const VD sh = __builtin_shufflevector(hi, VD{}, 4, 0, 1, 2);
              VD       f;
              std::memcpy(&f, F[i] + r, sizeof(VD));
              f += C[a][i] + sh;
              std::memcpy(F[i] + r, &f, sizeof(VD));
              F[i][r + W] += hi[W - 1];
            }
        }
    else
      for (unsigned int l = 0; l < nl; ++l)
        {
          const std::uint32_t *cn = &conn[nc * (W * b + l)];
#pragma GCC unroll 8
          for (unsigned int a = 0; a < nc; ++a)
            for (int i = 0; i < dim; ++i)
              F[i][cn[a]] += C[a][i][l];
        }
  }

  template <int dim>
  [[gnu::always_inline]] inline simd_double
  SolidFEM<dim>::hourglass_distortion(const ElementBlock &eb,
                                      const double        hgB) const
  {
    return hourglass::distortion<dim>(eb.q, hgB);
  }

  template <int dim>
  simd_double
  SolidFEM<dim>::jacobian_low(const ElementBlock &eb,
                              const simd_double  &distortion) const
  {
    return 1. + eb.dJ - distortion;
  }

  template <int dim>
  template <bool update>
  double
  SolidFEM<dim>::element_loop(const double dt, const double w)
  {
    // Blocks of simd_lanes elements, one element per lane of simd_double
    // (GCC vector extension, see constitutive.h); a partial last block
    // repeats its last element in the spare lanes and stores nothing from
    // them. Per element the arithmetic is that of the scalar formulation,
    // and the work is summed in element order. The nodal force sums are in
    // lexicographic element order, the two elements of a block that share a
    // node summed first (round-off against other orders). The node forces
    // are zero here (zeroed by the node update, or at setup); the elements
    // add theirs. The passes of a block (gather, constitutive update,
    // forces and scatter) run one after the other on the block, fused, so
    // that its data stay in registers.
    using VD                 = simd_double;
    constexpr unsigned int W = simd_lanes;
    const LoopConstants    c = loop_constants(dt);
    double                *F[dim];
    const double          *vl[dim];
    for (int d = 0; d < dim; ++d)
      F[d] = frc[d].data(), vl[d] = vel[d].data();
    double            work = 0;
    const std::size_t n_el = element_id.size();
    // Smallest corner Jacobian ratio and largest hourglass distortion
    // (spare lanes repeat an element).
    VD jmin = VD{} + std::numeric_limits<double>::infinity();
    VD dmax = {};
    for (std::size_t b = 0; b < blocks.size(); ++b)
      {
        const std::size_t  e0 = W * b;
        const unsigned int nl = std::min<std::size_t>(W, n_el - e0);
        std::size_t        el[W];
        for (unsigned int l = 0; l < W; ++l)
          el[l] = e0 + std::min(l, nl - 1);
        ElementBlock &eb = blocks[b];
        VD            E;
        StressBlock   sb;
        for (unsigned int k = 0; k < 6; ++k)
          sb.s[k] = eb.s[k];
        if constexpr (update)
          {
            VD Vc[n_corners][dim];
            gather_velocities(b, el, vl, Vc);
            const VD wk = update_block(eb, el, nl, Vc, dt, w, c, sb, E);
            for (unsigned int l = 0; l < nl; ++l)
              work += wk[l];
            const VD hd = hourglass_distortion(eb, c.hgB);
            const VD j  = jacobian_low(eb, hd);
            jmin        = j < jmin ? j : jmin;
            dmax        = hd > dmax ? hd : dmax;
          }
        else
          {
            auto Ef = [&](const unsigned int l) {
              return mat.youngs_modulus.value(eb.T[l]);
            };
            E = VD{Ef(0), Ef(1), Ef(2), Ef(3)};
          }
        scatter_forces(b, nl, sb.s, E, c, F);
      }
    transition_hourglass_forces(c.kfac);
    if constexpr (update)
      {
        min_jacobian   = std::numeric_limits<double>::infinity();
        max_distortion = 0;
        for (unsigned int l = 0; l < W; ++l)
          {
            min_jacobian = std::min(min_jacobian, jmin[l]);
            // Written so that a NaN is kept (and fails element_failed()).
            max_distortion = dmax[l] > max_distortion  ? dmax[l] :
                             dmax[l] <= max_distortion ? max_distortion :
                                                         dmax[l];
          }
        max_distortion_seen = std::max(max_distortion_seen, max_distortion);
      }
    return work;
  }

  template <int dim>
  bool
  SolidFEM<dim>::probe(const Point<dim> &x, double &sxx, double &T) const
  {
    const auto ijk = grid.cell_of(x);
    if (!zone.contains_cell(ijk))
      return false;
    std::uint64_t id = 0;
    for (int d = dim - 1; d >= 0; --d)
      id = id * zn[d] + (ijk[d] - zlo[d]);
    const auto it = std::lower_bound(element_by_id.begin(),
                                     element_by_id.end(),
                                     std::make_pair(id, std::uint32_t(0)));
    if (it == element_by_id.end() || it->first != id)
      return false;
    sxx = element_stress(it->second)[0][0];
    T   = element_T(it->second);
    return true;
  }

  template <int dim>
  void
  SolidFEM<dim>::cell_fields(std::vector<std::vector<double>> &f) const
  {
    // Element values to the grid ranks owning their cells.
    std::vector<types::global_dof_index> have(element_id.begin(),
                                              element_id.end()),
      want;
    for (const auto c : grid_zone_cells)
      {
        const auto    ijk = grid.global_index(c);
        std::uint64_t id  = 0;
        for (int d = dim - 1; d >= 0; --d)
          id = id * zn[d] + (ijk[d] - zlo[d]);
        want.push_back(id);
      }
    Utilities::MPI::NoncontiguousPartitioner back(have, want, comm);
    std::vector<double> a(element_id.size()), r(want.size());
    for (unsigned int k = 0; k < 5; ++k)
      {
        for (std::size_t e = 0; e < element_id.size(); ++e)
          {
            const SymmetricTensor<2, 3> s = element_stress(e);
            a[e]                          = k < 3  ? s[k][k] :
                                            k == 3 ? von_mises(s) :
                                                     blocks[e / simd_lanes].eps_p[e % simd_lanes];
          }
        back.export_to_ghosted_array(ArrayView<const double>(a),
                                     ArrayView<double>(r));
        for (std::size_t i = 0; i < want.size(); ++i)
          f[k][grid_zone_cells[i]] = r[i];
      }
  }

  template <int dim>
  void
  SolidFEM<dim>::set_mass_scaling(const double s)
  {
    const double old = mass_scale, r = s / old;
    mass_scale = s;
    if (mass_scale_setup == 0)
      {
        mass_scale_setup = old;
        inv_mass_setup   = inv_mass;
        owned_mass_setup = owned_mass;
        tr_mass_setup    = tr_mass;
      }
    const double f = s / mass_scale_setup;
    for (std::size_t i = 0; i < owned_mass.size(); ++i)
      owned_mass[i] = owned_mass_setup[i] * f;
    for (std::size_t i = 0; i < inv_mass.size(); ++i) // 0 at transition nodes
      inv_mass[i] = inv_mass_setup[i] / f;
    for (std::size_t i = 0; i < tr_mass.size(); ++i)
      tr_mass[i] = tr_mass_setup[i] * f;
    kinetic *= r;
  }

  template <int dim>
  double
  SolidFEM<dim>::scale_node_velocities(const double f)
  {
    // Nodes of nonzero inverse mass: those that update_nodes() integrates
    // (transition nodes and nodes of no element have 0).
    double k_old = 0, k_new = 0;
    for (std::size_t n = 0; n < n_box; ++n)
      if (inv_mass[n] > 0)
        {
          double v2 = 0;
          for (int d = 0; d < dim; ++d)
            {
              v2 += vel[d][n] * vel[d][n];
              vel[d][n] *= f;
            }
          k_old += 0.5 * owned_mass[n] * v2;
          k_new += 0.5 * owned_mass[n] * f * f * v2;
        }
    kinetic += k_new - k_old;
    return k_new - k_old;
  }

  template <int dim>
  double
  SolidFEM<dim>::mass() const
  {
    double m = 0;
    for (const double x : owned_mass)
      m += x;
    return Utilities::MPI::sum(m, comm) / mass_scale;
  }

  template <int dim>
  double
  SolidFEM<dim>::elastic_energy() const
  {
    double u = 0;
    double s[6];
    for (std::size_t e = 0; e < element_id.size(); ++e)
      {
        for (unsigned int c = 0; c < 6; ++c)
          s[c] = blocks[e / simd_lanes].s[c][e % simd_lanes];
        u += V * elastic_energy_density(mat, s, element_T(e));
      }
    return u;
  }

  template <int dim>
  bool
  SolidFEM<dim>::find_non_finite(Point<dim> &where) const
  {
    for (std::size_t e = 0; e < element_id.size(); ++e)
      if (!std::isfinite(element_stress(e).norm()))
        {
          std::uint64_t r = element_id[e];
          for (int d = 0; d < dim; ++d)
            {
              where[d] = grid.origin()[d] +
                         (zlo[d] + double(r % zn[d]) + 0.5) * grid.h();
              r /= zn[d];
            }
          return true;
        }
    return false;
  }

  template <int dim>
  bool
  SolidFEM<dim>::find_failed(Point<dim> &where,
                             double     &J,
                             bool       &distorted) const
  {
    const double hgB = loop_constants(1.).hgB;
    for (std::size_t e = 0; e < element_id.size(); ++e)
      {
        const ElementBlock &eb  = blocks[e / simd_lanes];
        const simd_double   hdb = hourglass_distortion(eb, hgB);
        const double        j   = jacobian_low(eb, hdb)[e % simd_lanes];
        const double        hd  = hdb[e % simd_lanes];
        distorted = j > 0 && !(hd <= prm.hourglass_distortion_limit);
        if (!(j > 0) || distorted)
          {
            std::uint64_t r = element_id[e];
            for (int d = 0; d < dim; ++d)
              {
                where[d] = grid.origin()[d] +
                           (zlo[d] + double(r % zn[d]) + 0.5) * grid.h();
                r /= zn[d];
              }
            J = distorted ? hd : j;
            return true;
          }
      }
    return false;
  }

  template <int dim>
  double
  SolidFEM<dim>::largest_distortion() const
  {
    return Utilities::MPI::max(max_distortion_seen, comm);
  }

  template <int dim>
  std::uint64_t
  SolidFEM<dim>::add_cells(
    const std::vector<std::array<int, dim>> &cells,
    const std::vector<std::pair<std::uint64_t, std::array<double, 7>>>
                              &new_cells,
    const std::vector<double> &T)
  {
    const auto &N = grid.n_cells();
    for (const auto &c : cells)
      {
        for (int d = 0; d < dim; ++d)
          AssertThrow(c[d] >= 0 && c[d] < int(N[d]),
                      ExcMessage("FE zone hand-over: a new cell lies outside "
                                 "the grid"));
        AssertThrow(!zone.contains_cell(c),
                    ExcMessage("FE zone hand-over: a new cell lies in the "
                               "zone"));
      }
    const FeZone<dim> larger = zone.with_cells(cells);
    // The mesh's corners follow the bounding box where it grew.
    const Point<dim> a = larger.lower_corner(), b = larger.upper_corner();
    for (int d = 0; d < dim; ++d)
      {
        if (larger.first_cell()[d] != zlo[d])
          prm.lower_corner[d] = a[d];
        if (larger.first_cell()[d] + larger.n_cells()[d] != zlo[d] + zn[d])
          prm.upper_corner[d] = b[d];
      }
    return grow(larger, new_cells, T);
  }

  template <int dim>
  std::uint64_t
  SolidFEM<dim>::grow(
    const FeZone<dim> &larger,
    const std::vector<std::pair<std::uint64_t, std::array<double, 7>>>
                              &new_cells,
    const std::vector<double> &T)
  {
    constexpr unsigned int n_values = 6 + 3 + n_hg * dim + 2;
    const auto            &N        = grid.n_cells();
    // Keys independent of the zone's size: lexicographic indices of cells
    // and nodes in the whole grid.
    auto cell_key = [&](const std::array<int, dim> &ijk) {
      std::uint64_t id = 0;
      for (int d = dim - 1; d >= 0; --d)
        id = id * N[d] + ijk[d];
      return id;
    };
    auto node_key = [&](const std::array<int, dim> &ijk) {
      std::uint64_t id = 0;
      for (int d = dim - 1; d >= 0; --d)
        id = id * (N[d] + 1) + ijk[d];
      return id;
    };
    auto element_cell = [&](std::uint64_t r) {
      std::array<int, dim> ijk;
      for (int d = 0; d < dim; ++d)
        ijk[d] = zlo[d] + int(r % zn[d]), r /= zn[d];
      return ijk;
    };
    auto zone_node = [&](std::uint64_t r) {
      std::array<int, dim> ijk;
      for (int d = 0; d < dim; ++d)
        ijk[d] = zlo[d] + int(r % (zn[d] + 1)), r /= zn[d] + 1;
      return ijk;
    };

    // This rank's state under those keys (the values of save_state()).
    const std::size_t          n_old = element_id.size();
    std::vector<std::uint64_t> el_keys(n_old);
    std::vector<double>        el_vals(n_values * n_old);
    for (std::size_t e = 0; e < n_old; ++e)
      {
        el_keys[e]             = cell_key(element_cell(element_id[e]));
        const ElementBlock &eb = blocks[e / simd_lanes];
        const unsigned int  l  = e % simd_lanes;
        double             *v  = &el_vals[n_values * e];
        for (unsigned int k = 0; k < 6; ++k)
          v[k] = eb.s[k][l];
        v[6] = eb.eps_p[l], v[7] = eb.visc[l], v[8] = eb.T[l];
        for (unsigned int k = 9; k < n_values - 2; ++k)
          v[k] = eb.q[(k - 9) / dim][(k - 9) % dim][l];
        v[n_values - 2] = T_end[e];
        v[n_values - 1] = eb.dJ[l];
      }
    std::vector<std::uint64_t> nd_keys(n_owned);
    std::vector<double>        nd_vals(dim * n_owned);
    for (std::size_t ln = 0; ln < n_owned; ++ln)
      {
        nd_keys[ln] = node_key(zone_node(node_zone_id[box_of[ln]]));
        for (int d = 0; d < dim; ++d)
          nd_vals[dim * ln + d] = vel[d][box_of[ln]];
      }
    // The transition nodes are the same on every rank.
    std::unordered_map<std::uint64_t, std::size_t> old_tr;
    const std::vector<double>                      old_tr_vel = tr_vel;
    for (std::size_t t = 0; t < tr_ijk.size(); ++t)
      old_tr[node_key(tr_ijk[t])] = t;
    std::vector<std::uint64_t> new_keys;
    std::vector<double>        new_vals;
    for (const auto &[key, a] : new_cells)
      {
        new_keys.push_back(key);
        new_vals.insert(new_vals.end(), a.begin(), a.end());
      }
    const auto all_el_keys  = Utilities::MPI::all_gather(comm, el_keys);
    const auto all_el_vals  = Utilities::MPI::all_gather(comm, el_vals);
    const auto all_nd_keys  = Utilities::MPI::all_gather(comm, nd_keys);
    const auto all_nd_vals  = Utilities::MPI::all_gather(comm, nd_vals);
    const auto all_new_keys = Utilities::MPI::all_gather(comm, new_keys);
    const auto all_new_vals = Utilities::MPI::all_gather(comm, new_vals);
    std::unordered_map<std::uint64_t, const double *> old_el, old_nd, seed;
    for (std::size_t r = 0; r < all_el_keys.size(); ++r)
      {
        for (std::size_t i = 0; i < all_el_keys[r].size(); ++i)
          old_el[all_el_keys[r][i]] = &all_el_vals[r][n_values * i];
        for (std::size_t i = 0; i < all_nd_keys[r].size(); ++i)
          old_nd[all_nd_keys[r][i]] = &all_nd_vals[r][dim * i];
        for (std::size_t i = 0; i < all_new_keys[r].size(); ++i)
          seed[all_new_keys[r][i]] = &all_new_vals[r][7 * i];
      }

    // The larger zone, built as by setup() at the factor in use (the
    // factor's later changes scale these masses).
    zone             = larger;
    zone_given       = true;
    mass_scale_setup = 0;
    inv_mass_setup.clear(), owned_mass_setup.clear(), tr_mass_setup.clear();
    setup(mass_scale, face_fix, g, T);

    // Elements: old state, or the seed of a new one (T_end: the cell's
    // temperature from setup()).
    std::uint64_t added = 0;
    for (std::size_t e = 0; e < element_id.size(); ++e)
      {
        const auto          ijk = element_cell(element_id[e]);
        const std::uint64_t key = cell_key(ijk);
        ElementBlock       &eb  = blocks[e / simd_lanes];
        const unsigned int  l   = e % simd_lanes;
        const auto          it  = old_el.find(key);
        if (it != old_el.end())
          {
            const double *v = it->second;
            for (unsigned int k = 0; k < 6; ++k)
              eb.s[k][l] = v[k];
            eb.eps_p[l] = v[6], eb.visc[l] = v[7], eb.T[l] = v[8];
            for (unsigned int k = 9; k < n_values - 2; ++k)
              eb.q[(k - 9) / dim][(k - 9) % dim][l] = v[k];
            T_end[e] = v[n_values - 2];
            eb.dJ[l] = v[n_values - 1];
            continue;
          }
        const auto is = seed.find(key);
        if (is == seed.end())
          {
            std::ostringstream m;
            m << "FE zone hand-over: no state for the new element of grid "
                 "cell (";
            for (int d = 0; d < dim; ++d)
              m << (d ? ", " : "") << ijk[d];
            m << ") (no solid material point there)";
            AssertThrow(false, ExcMessage(m.str()));
          }
        const double *v = is->second;
        for (unsigned int k = 0; k < 6; ++k)
          eb.s[k][l] = v[k];
        eb.eps_p[l] = v[6], eb.visc[l] = 0, eb.T[l] = T_end[e];
        for (unsigned int al = 0; al < n_hg; ++al)
          for (int i = 0; i < dim; ++i)
            eb.q[al][i][l] = 0;
        eb.dJ[l] = 0;
        ++added;
      }
    // Nodes: old velocity (an old transition node that is now inside the
    // zone takes its transition velocity), new ones at rest.
    for (std::size_t ln = 0; ln < n_local; ++ln)
      {
        const std::uint32_t n   = box_of[ln];
        const std::uint64_t key = node_key(zone_node(node_zone_id[n]));
        const auto          it  = old_nd.find(key);
        const auto          tt  = old_tr.find(key);
        for (int d = 0; d < dim; ++d)
          vel[d][n] = it != old_nd.end() ? it->second[d] :
                      tt != old_tr.end() ? old_tr_vel[dim * tt->second + d] :
                                           0.;
      }
    for (std::size_t t = 0; t < tr_ijk.size(); ++t)
      {
        const auto tt = old_tr.find(node_key(tr_ijk[t]));
        for (int d = 0; d < dim; ++d)
          tr_vel[dim * t + d] =
            tt != old_tr.end() ? old_tr_vel[dim * tt->second + d] : 0.;
      }
    for (const auto &[n, t] : tr_local)
      for (int d = 0; d < dim; ++d)
        vel[d][n] = tr_vel[dim * t + d];
    forces_of_restored_state();
    return Utilities::MPI::sum(added, comm);
  }

  template <int dim>
  void
  SolidFEM<dim>::set_top(const double new_top)
  {
    const double r      = (new_top - grid.origin()[dim - 1]) / grid.h();
    const int    top    = static_cast<int>(std::round(r));
    const int    bottom = static_cast<int>(std::round(
      (prm.lower_corner[dim - 1] - grid.origin()[dim - 1]) / grid.h()));
    AssertThrow(std::abs(r - top) < 1e-6 && top > bottom &&
                  top <= int(grid.n_cells()[dim - 1]),
                ExcMessage("FE zone: the top " + std::to_string(new_top) +
                           " m must be a grid line above the zone's bottom "
                           "and inside the domain"));
    prm.upper_corner[dim - 1] = new_top;
    zone_given                = false;
  }

  template <int dim>
  void
  SolidFEM<dim>::set_cells(const FeZone<dim> &z)
  {
    AssertThrow(z.enabled(), ExcMessage("FE zone: no cell in the zone"));
    const auto &N = grid.n_cells();
    for (int d = 0; d < dim; ++d)
      AssertThrow(z.first_cell()[d] >= 0 &&
                    z.first_cell()[d] + z.n_cells()[d] <= int(N[d]),
                  ExcMessage("FE zone: the zone's cells must lie in the grid"));
    // The mesh's corners: the parameters' where the bounding box keeps
    // their grid lines (the same mesh, bit for bit, as the run that wrote
    // a checkpoint), else the box's.
    const FeZone<dim> box(
      true, prm.lower_corner, prm.upper_corner, grid.origin(), grid.h());
    const Point<dim> a = z.lower_corner(), b = z.upper_corner();
    for (int d = 0; d < dim; ++d)
      {
        if (z.first_cell()[d] != box.first_cell()[d])
          prm.lower_corner[d] = a[d];
        if (z.first_cell()[d] + z.n_cells()[d] !=
            box.first_cell()[d] + box.n_cells()[d])
          prm.upper_corner[d] = b[d];
      }
    zone       = z;
    zone_given = true;
  }

  template <int dim>
  void
  SolidFEM<dim>::save_state(StateWriter &out) const
  {
    // Element state, one array per value (stress components, plastic
    // strain, viscous pressure, temperature of the last step, hourglass
    // amplitudes, end temperature of the advance, volume change J - 1),
    // keyed by zone index.
    constexpr unsigned int n_values = 6 + 3 + n_hg * dim + 2;
    const std::size_t      n_el     = element_id.size();
    out.put_vector(element_id);
    std::vector<double> v(n_el);
    for (unsigned int k = 0; k < n_values; ++k)
      {
        for (std::size_t e = 0; e < n_el; ++e)
          {
            const ElementBlock &eb = blocks[e / simd_lanes];
            const unsigned int  l  = e % simd_lanes;
            v[e]                   = k < 6  ? eb.s[k][l] :
                                     k == 6 ? eb.eps_p[l] :
                                     k == 7 ? eb.visc[l] :
                                     k == 8 ? eb.T[l] :
                                     k < n_values - 2 ? eb.q[(k - 9) / dim][(k - 9) % dim][l] :
                                     k == n_values - 2 ? T_end[e] :
                                                         eb.dJ[l];
          }
        out.put_vector(v);
      }
    // Velocities of the owned nodes, keyed by zone node index.
    std::vector<std::uint64_t> ids(n_owned);
    for (std::size_t ln = 0; ln < n_owned; ++ln)
      ids[ln] = node_zone_id[box_of[ln]];
    out.put_vector(ids);
    v.resize(n_owned);
    for (int d = 0; d < dim; ++d)
      {
        for (std::size_t ln = 0; ln < n_owned; ++ln)
          v[ln] = vel[d][box_of[ln]];
        out.put_vector(v);
      }
    // The same on every rank.
    out.put_vector(tr_vel);
    out.put_vector(tr_disp);
  }

  template <int dim>
  void
  SolidFEM<dim>::load_state(std::vector<StateReader> &parts)
  {
    constexpr unsigned int n_values = 6 + 3 + n_hg * dim + 2;
    const std::size_t      n_el     = element_id.size();
    // Local nodes (owned and ghost) by zone node index.
    std::vector<std::pair<std::uint64_t, std::uint32_t>> node_by_id;
    for (std::size_t ln = 0; ln < n_local; ++ln)
      node_by_id.emplace_back(node_zone_id[box_of[ln]], box_of[ln]);
    std::sort(node_by_id.begin(), node_by_id.end());
    // Elements and nodes of this rank found in the checkpoint, and the
    // elements it holds (every rank reads every part).
    std::size_t         elements_set = 0, nodes_set = 0, elements_saved = 0;
    std::vector<double> tv, td;
    for (std::size_t f = 0; f < parts.size(); ++f)
      {
        StateReader &in  = parts[f];
        const auto   ids = in.get_vector<std::uint64_t>();
        elements_saved += ids.size();
        std::vector<std::int64_t> local(ids.size(), -1);
        for (std::size_t i = 0; i < ids.size(); ++i)
          {
            const auto it =
              std::lower_bound(element_by_id.begin(),
                               element_by_id.end(),
                               std::make_pair(ids[i], std::uint32_t(0)));
            if (it != element_by_id.end() && it->first == ids[i])
              local[i] = it->second, ++elements_set;
          }
        for (unsigned int k = 0; k < n_values; ++k)
          {
            const auto v = in.get_vector<double>();
            AssertThrow(v.size() == ids.size(),
                        ExcMessage("checkpoint: FE element data damaged"));
            for (std::size_t i = 0; i < ids.size(); ++i)
              if (local[i] >= 0)
                {
                  const std::size_t  e  = local[i];
                  ElementBlock      &eb = blocks[e / simd_lanes];
                  const unsigned int l  = e % simd_lanes;
                  if (k < 6)
                    eb.s[k][l] = v[i];
                  else if (k == 6)
                    eb.eps_p[l] = v[i];
                  else if (k == 7)
                    eb.visc[l] = v[i];
                  else if (k == 8)
                    eb.T[l] = v[i];
                  else if (k < n_values - 2)
                    eb.q[(k - 9) / dim][(k - 9) % dim][l] = v[i];
                  else if (k == n_values - 2)
                    T_end[e] = v[i];
                  else
                    eb.dJ[l] = v[i];
                }
          }
        const auto                node_ids = in.get_vector<std::uint64_t>();
        std::vector<std::int64_t> box(node_ids.size(), -1);
        for (std::size_t i = 0; i < node_ids.size(); ++i)
          {
            const auto it =
              std::lower_bound(node_by_id.begin(),
                               node_by_id.end(),
                               std::make_pair(node_ids[i], std::uint32_t(0)));
            if (it != node_by_id.end() && it->first == node_ids[i])
              box[i] = it->second, ++nodes_set;
          }
        for (int d = 0; d < dim; ++d)
          {
            const auto v = in.get_vector<double>();
            for (std::size_t i = 0; i < node_ids.size(); ++i)
              if (box[i] >= 0)
                vel[d][box[i]] = v[i];
          }
        // The transition nodes' values: the same in every part.
        auto v = in.get_vector<double>();
        auto d = in.get_vector<double>();
        if (f == 0)
          tv = std::move(v), td = std::move(d);
      }
    // Every element of the checkpoint is one of this zone's (on some
    // rank), and every element and node of this zone is in the checkpoint
    // (the same answer on every rank).
    const std::size_t used = Utilities::MPI::sum(elements_set, comm);
    AssertThrow(used == elements_saved,
                ExcMessage(
                  "checkpoint: " + std::to_string(elements_saved - used) +
                  " of the " + std::to_string(elements_saved) +
                  " FE elements it holds are not elements of this "
                  "run's FE zone (the checkpoint's zone holds other "
                  "cells)"));
    const unsigned int missing = Utilities::MPI::max(
      elements_set == n_el && nodes_set == n_local ? 0u : 1u, comm);
    AssertThrow(missing == 0,
                ExcMessage("checkpoint: the FE zone's elements or nodes of "
                           "this run are not all in the checkpoint"));
    AssertThrow(tv.size() == tr_vel.size() && td.size() == tr_disp.size(),
                ExcMessage("checkpoint: another number of FE "
                           "transition nodes"));
    tr_vel  = std::move(tv);
    tr_disp = std::move(td);
    forces_of_restored_state();
  }

  template <int dim>
  void
  SolidFEM<dim>::forces_of_restored_state()
  {
    const std::size_t n_el = element_id.size();
    // Spare lanes of the last block repeat the last element (as they do in
    // a run: same inputs, same arithmetic).
    if (n_el > 0)
      {
        ElementBlock      &eb   = blocks.back();
        const unsigned int last = (n_el - 1) % simd_lanes;
        for (unsigned int l = last + 1; l < simd_lanes; ++l)
          {
            for (unsigned int c = 0; c < 6; ++c)
              eb.s[c][l] = eb.s[c][last];
            eb.eps_p[l] = eb.eps_p[last];
            eb.visc[l]  = eb.visc[last];
            eb.T[l]     = eb.T[last];
            eb.dJ[l]    = eb.dJ[last];
            for (unsigned int al = 0; al < n_hg; ++al)
              for (int i = 0; i < dim; ++i)
                eb.q[al][i][l] = eb.q[al][i][last];
          }
      }
    // The next advance() makes the end temperatures its start ones.
    T_start = T_end;
    // The element forces of the next step (what the last update_elements()
    // left in frc and tr_hg): the forces part of the element loop on the
    // restored state.
    for (int d = 0; d < dim; ++d)
      std::fill(frc[d].begin(), frc[d].end(), 0.);
    element_loop<false>(0, 1);
  }

  template <int dim>
  void
  SolidFEM<dim>::save_no_zone(StateWriter &out)
  {
    constexpr unsigned int n_values = 6 + 3 + n_hg * dim + 2;
    out.put_vector(std::vector<std::uint64_t>()); // element ids
    for (unsigned int k = 0; k < n_values; ++k)
      out.put_vector(std::vector<double>());
    out.put_vector(std::vector<std::uint64_t>()); // node ids
    for (int d = 0; d < dim; ++d)
      out.put_vector(std::vector<double>());
    out.put_vector(std::vector<double>()); // transition-node velocities
    out.put_vector(std::vector<double>()); // and displacements
  }

  template <int dim>
  void
  SolidFEM<dim>::load_no_zone(std::vector<StateReader> &parts)
  {
    constexpr unsigned int n_values = 6 + 3 + n_hg * dim + 2;
    for (std::size_t f = 0; f < parts.size(); ++f)
      {
        StateReader &in  = parts[f];
        const auto   ids = in.get_vector<std::uint64_t>();
        for (unsigned int k = 0; k < n_values; ++k)
          AssertThrow(in.get_vector<double>().size() == ids.size(),
                      ExcMessage("checkpoint: FE element data damaged"));
        in.get_vector<std::uint64_t>();
        for (int d = 0; d < dim; ++d)
          in.get_vector<double>();
        const auto tv = in.get_vector<double>();
        in.get_vector<double>(); // transition-node displacements
        AssertThrow(f > 0 || tv.empty(),
                    ExcMessage("checkpoint: another number of FE "
                               "transition nodes"));
      }
  }

  template class SolidFEM<2>;
  template class SolidFEM<3>;
} // namespace femp
