// femp: melt-pool flow, improved incompressible MPM (paper sec. 2.3,
// eqs. 3-4 with gravity, viscosity, Darcy damping, surface tension,
// Marangoni stress and recoil pressure; doc/method.md, "Melt flow", ref. [11]).
//
// Discretization choices (documented in doc/flow.md):
// - velocities on grid nodes, pressure on the centres of fluid cells;
// - divergence of the nodal velocity at a cell centre: mean over the
//   2^(dim-1) cell edges of the difference quotient; nodal pressure
//   gradient: mean over the 2^(dim-1) pairs of cells that straddle the node;
//   the Poisson operator is the compact 5-point (7-point) Laplacian, so the
//   projection is approximate (exact for a linear pressure);
// - free surface: Dirichlet pressure p_s at the interface on each face
//   between a fluid and a gas cell, at theta h from the fluid centre (where
//   the smoothed alpha is 1/2; theta in [0.05, 1]), imposed by the ghost
//   value p_c + (p_s - p_c)/theta in both the Poisson equation and the
//   nodal gradient (ghost-fluid method; exact hydrostatics);
// - smoothed alpha: point volume mapped to nodes with tent weights divided
//   by h^dim, averaged to cell centres; computed only near the fluid;
// - p_s = sigma div(n) + recoil: n = -grad alpha/|grad alpha| at the nodes
//   of a surface cell (pair-averaged differences of the cell values) and
//   div(n) at its centre (edge-averaged differences); the recoil from the
//   cell's temperature limited to the range of its surface neighbours'
//   (Melt flow/Recoil temperature);
// - Marangoni: traction dsigma/dT (grad T - (n.grad T) n) on the fluid-gas
//   faces, weighted by |n_d|, spread to the face nodes;
// - walls: zero normal velocity on the domain boundary (free slip) and zero
//   velocity on the nodes of solid (non-fluid metal) cells (no slip);
//   Neumann pressure on both; with Melt flow/Front wall film, slip along
//   the wall (zero wall-normal component, no Darcy damping) on the nodes
//   where the melt between a solid cell and a recoil-driven surface cell
//   is less than a cell thick (FrontWallFilm, front_wall_film.cc);
// - viscosity: explicit, from the Q1 stiffness of each fluid cell with the
//   lumped nodal volume (cell-wise, so it is independent of the partition);
// - G2P: v_p <- beta (v_p + sum w (u_new - u_old)) + (1 - beta) sum w u_new
//   (FLIP fraction beta, default 0.95); points move with sum w u_new;
// - or APIC (Melt flow/Velocity transfer; Jiang et al. 2015): P2G
//   scatters m_p w (v_p + C_p (x_i - x_p)), G2P sets v_p = sum w u_new and
//   C_p = sum u_new (grad w)^T (= B_p D_p^-1 for tent weights, D_p =
//   diag(h^2 xi_d (1 - xi_d))); C_p is a point property only then;
// - optional point shifting (SPH-type, -A h |u| dt grad alpha) and volume
//   correction (positions moved by grad psi, lap psi = c (V_c/h^dim - 1),
//   psi = 0 at the free surface; Melt flow/Volume correction), both off by
//   default.
// The free surface (alpha, theta, capillary, recoil and Marangoni terms) is
// in FreeSurface (free_surface.cc), the pressure system and its solvers in
// PressureSolver (pressure_solver.cc).
#include <deal.II/base/mpi.h>

#include <femp/base/collective_error.h>
#include <femp/base/error_location.h>
#include <femp/base/input_checks.h>
#include <femp/base/parameter_table.h>
#include <femp/base/progress_watchdog.h>
#include <femp/base/recoil_law.h>
#include <femp/flow/incompressible_flow.h>
#include <femp/grid/cell_state.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>
#include <type_traits>
#include <utility>

namespace femp
{
  namespace
  {
    using flow_cells::Section;
  } // namespace

  template <int dim>
  IncompressibleFlow<dim>::Parameters::Parameters()
  {
    gravity[dim - 1] = -9.81;
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::Parameters::add_parameters(ParameterTable &table)
  {
    ParameterHandler &prm = table.handler();
    table.enter_subsection("Melt flow");
    table.add("Viscosity",
              viscosity,
              Patterns::Double(0.),
              "Dynamic viscosity mu of the melt, Pa s; range [0, inf).");
    table.add("Darcy constant",
              darcy_constant,
              Patterns::Double(0.),
              "Mushy-zone constant K_c of the Darcy damping "
              "K_c (1-gamma)^2/(gamma^3+eps0) u, kg/(m^3 s); range [0, inf).");
    table.add("Darcy epsilon",
              darcy_epsilon,
              Patterns::Double(0.),
              "eps0 of the Darcy damping, avoids division by zero; "
              "range (0, 1].");
    table.add("FLIP fraction",
              flip_fraction,
              Patterns::Double(0., 1.),
              "beta of the grid-to-point update of the FLIP-PIC "
              "transfer: 1 pure FLIP, 0 pure PIC (not used by APIC); "
              "dimensionless, range [0, 1].");
    table.add("Velocity transfer",
              velocity_transfer,
              {{VelocityTransfer::flip_pic, "FLIP-PIC"},
               {VelocityTransfer::apic, "APIC"}},
              "How the fluid points exchange velocities with the grid "
              "nodes. FLIP-PIC: a point brings m_p v_p to the nodes and "
              "takes back beta (v_p + the interpolated change of the "
              "nodal velocity) + (1 - beta) (the interpolated nodal "
              "velocity), beta the FLIP fraction; the PIC part damps by "
              "a fixed fraction per step. APIC (affine particle-in-cell, "
              "Jiang et al. 2015): each fluid point also carries the "
              "affine velocity C_p (1/s, dim x dim, the point properties "
              "affine_velocity_xx ...), brings m_p (v_p + C_p (x_i - x_p)) "
              "to node i and takes back v_p = sum w u_i and C_p = sum u_i "
              "(grad w_ip)^T, so that rotation and shear survive the round "
              "trip; the FLIP fraction is not used. See doc/flow.md, "
              "\"Velocity transfer\". One of FLIP-PIC, APIC (default "
              "FLIP-PIC).");
    table.add("Courant number",
              cfl,
              Patterns::Double(0.),
              "C of the convective limit dt <= C h / u_max; range (0, 1].");
    table.add("Capillary step fraction",
              capillary_fraction,
              Patterns::Double(0.),
              "Fraction of the capillary limit sqrt(rho h^3/(2 pi "
              "sigma)) used by the automatic fluid step (surface "
              "tension is explicit on the old geometry; "
              "doc/flow.md); range (0, 1].");
    table.add("Time step",
              time_step,
              Patterns::Double(0.),
              "Prescribed fluid step, s; 0 (default) chooses it "
              "automatically at every sub-step as the smallest of the "
              "convective, viscous and (fraction of the) capillary "
              "limits. A prescribed step above the viscous limit "
              "h^2 rho/(2 dim mu) or the capillary limit is refused; "
              "above the convective limit the step-halving safety "
              "applies. Range [0, inf).");
    table.add("Point shifting",
              point_shifting,
              Patterns::Double(0.),
              "Coefficient A of the point shifting: each fluid point "
              "is moved, besides its advection, by -A h |u| dt "
              "grad(alpha) (alpha the metal fraction at the nodes, "
              "tangential part only next to the free surface, at "
              "most h/4 per step), which keeps the points evenly "
              "spread (see doc/flow.md); dimensionless, 0 switches it "
              "off. Range [0, 10].");
    table.add("Volume correction",
              volume_correction,
              Patterns::Double(0.),
              "Relaxation factor c of the volume correction: each "
              "step the fluid points move, besides their advection, "
              "by grad(psi), where lap(psi) = c (V_c/h^dim - 1) on the "
              "fluid cells (V_c the volume of the metal points in the "
              "cell; only the over-filled part in cells next to gas) "
              "with psi = 0 at the free surface, so that cells "
              "over-filled by bunched points push them apart and "
              "under-filled ones pull them in (at most h/4 per step; "
              "velocities unchanged). Keeps the fluid volume of the "
              "points (see doc/flow.md); dimensionless, 0 switches it "
              "off. Range [0, 1].");
    table.add("Front wall film",
              front_wall_film,
              "Sub-cell wall condition for the melt film that the recoil "
              "pressure drives along a solid wall: on the nodes where the "
              "melt between a solid cell and a surface cell that boils "
              "(recoil pressure above zeta_p p0, i.e. T above the "
              "evaporation temperature) and whose recoil exceeds the "
              "magnitude of its capillary pressure is less than one cell "
              "thick, only the velocity component normal to the wall is "
              "zero (slip) and the Darcy damping is not applied; "
              "elsewhere the nodes of solid cells stay no-slip. Needs "
              "the recoil pressure (Melt flow/Recoil coefficient > 0); "
              "see doc/flow.md, \"Front wall film\". A switch: true or "
              "false (default false: no slip on every node of a solid "
              "cell).");
    table.add("Front wall expulsion",
              front_wall_expulsion,
              "Sub-cell expulsion of the melt from a boiling surface (the "
              "piston of Semak and Matsunawa 1997): on the nodes of a "
              "surface cell that boils (recoil pressure p_r above zeta_p "
              "p0, i.e. T above the evaporation temperature, and above the "
              "magnitude of its capillary pressure) and holds more melt "
              "(alpha h) than the piston's film (Heat transfer/Front wall "
              "piston, doc/equations.md), the velocity along the surface "
              "away from the hot spot (down the surface gradient of T) is "
              "raised to at least the Bernoulli speed sqrt(2 p_r/rho) after "
              "the pressure correction; nodes of solid cells stay fixed. "
              "Needs the recoil pressure (Melt flow/Recoil coefficient > "
              "0) and the laser; see doc/flow.md, \"Front wall "
              "expulsion\". A switch: true or false (default false).");
    if (table.declaring())
      FreeSurface<dim>::Parameters::declare_parameters(prm);
    if (table.declaring())
      PressureSolver<dim>::Parameters::declare_parameters(prm);
    table.leave_subsection();
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::Parameters::declare_parameters(ParameterHandler &prm)
  {
    Parameters     defaults;
    ParameterTable table(prm, ParameterTable::Mode::declare);
    defaults.add_parameters(table);
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::Parameters::parse_parameters(ParameterHandler &prm)
  {
    ParameterTable table(prm, ParameterTable::Mode::parse);
    add_parameters(table);
    prm.enter_subsection("Melt flow");
    typename FreeSurface<dim>::Parameters surface;
    surface.parse_parameters(prm);
    surface_tension          = surface.surface_tension;
    surface_tension_gradient = surface.surface_tension_gradient;
    surface_tension_model    = surface.surface_tension_model;
    surfactant               = surface.surfactant;
    recoil_coefficient       = surface.recoil_coefficient;
    recoil_temperature       = surface.recoil_temperature;
    recoil_above_ambient     = surface.recoil_above_ambient;
    curvature_smoothing      = surface.curvature_smoothing;
    curvature                = surface.curvature;
    pressure.parse_parameters(prm);
    prm.leave_subsection();
    require(viscosity >= 0,
            "Melt flow/Viscosity",
            viscosity,
            "it must be non-negative (Pa s)");
    require(darcy_constant >= 0,
            "Melt flow/Darcy constant",
            darcy_constant,
            "it must be non-negative (kg/(m^3 s))");
    require(darcy_epsilon > 0 && darcy_epsilon <= 1,
            "Melt flow/Darcy epsilon",
            darcy_epsilon,
            "it must lie in (0, 1]");
    require(flip_fraction >= 0 && flip_fraction <= 1,
            "Melt flow/FLIP fraction",
            flip_fraction,
            "it must lie in [0, 1]");
    require(cfl > 0 && cfl <= 1,
            "Melt flow/Courant number",
            cfl,
            "it must lie in (0, 1]");
    require(point_shifting >= 0 && point_shifting <= 10,
            "Melt flow/Point shifting",
            point_shifting,
            "it must lie in [0, 10]");
    require(volume_correction >= 0 && volume_correction <= 1,
            "Melt flow/Volume correction",
            volume_correction,
            "it must lie in [0, 1]");
    require(capillary_fraction > 0 && capillary_fraction <= 1,
            "Melt flow/Capillary step fraction",
            capillary_fraction,
            "it must lie in (0, 1]");
    require(time_step >= 0,
            "Melt flow/Time step",
            time_step,
            "it must be non-negative (s; 0: automatic)");
  }

  template <int dim>
  typename FreeSurface<dim>::Parameters
  IncompressibleFlow<dim>::Parameters::surface_parameters() const
  {
    typename FreeSurface<dim>::Parameters s;
    s.surface_tension          = surface_tension;
    s.surface_tension_gradient = surface_tension_gradient;
    s.surface_tension_model    = surface_tension_model;
    s.surfactant               = surfactant;
    s.recoil_coefficient       = recoil_coefficient;
    s.recoil_temperature       = recoil_temperature;
    s.recoil_above_ambient     = recoil_above_ambient;
    s.curvature_smoothing      = curvature_smoothing;
    s.curvature                = curvature;
    return s;
  }

  template <int dim>
  typename IncompressibleFlow<dim>::StepLimits
  IncompressibleFlow<dim>::material_limits(const Parameters &prm,
                                           const double      h,
                                           const double      rho)
  {
    StepLimits limits;
    limits.convective = std::numeric_limits<double>::infinity();
    limits.viscous    = prm.viscosity > 0 ?
                          h * h * rho / (2 * dim * prm.viscosity) :
                          std::numeric_limits<double>::infinity();
    limits.capillary =
      prm.surface_tension > 0 ?
        std::sqrt(rho * h * h * h / (2 * numbers::PI * prm.surface_tension)) :
        std::numeric_limits<double>::infinity();
    limits.capillary_fraction = prm.capillary_fraction;
    return limits;
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::Parameters::check_time_step(const double h,
                                                       const double rho) const
  {
    if (time_step <= 0)
      return;
    const StepLimits   l = material_limits(*this, h, rho);
    std::ostringstream allowed;
    allowed << "it exceeds the "
            << (l.viscous <= l.capillary ?
                  "viscous limit h^2 rho/(2 dim mu) = " :
                  "capillary limit sqrt(rho h^3/(2 pi "
                  "sigma)) = ")
            << std::min(l.viscous, l.capillary) << " s (h = " << h
            << " m, rho = " << rho << " kg/m^3, mu = " << viscosity
            << " Pa s, sigma = " << surface_tension
            << " N/m); use 0 (automatic) or a step at most this limit";
    require(time_step <= std::min(l.viscous, l.capillary) * (1 + 1e-12),
            "Melt flow/Time step",
            time_step,
            allowed.str());
  }

  template <int dim>
  IncompressibleFlow<dim>::IncompressibleFlow(const Parameters &prm,
                                              const Material   &material,
                                              const BackgroundGrid<dim> &grid,
                                              MaterialPoints<dim>       &points,
                                              TimerOutput               *timer)
      : prm(prm)
      , mat(material)
      , rho(material.density)
      , grid(grid)
      , points(points)
      , timer(timer)
      , corner_offset(flow_cells::corner_offsets(grid, true))
      , around_offset(flow_cells::corner_offsets(grid, false))
      , stencil(flow_cells::neighbourhood(grid))
      , surface(prm.surface_parameters(), material, grid, points)
      , pressure_solver(prm.pressure, grid, prm.volume_correction > 0, timer)
  {
    // Q1 stiffness int grad N_a . grad N_b over a cell of size h
    // (2-point Gauss rule per direction, exact for Q1).
    const double h     = grid.h();
    const double gp[2] = {0.5 - 0.5 / std::sqrt(3.), 0.5 + 0.5 / std::sqrt(3.)};
    for (auto &row : stiffness)
      row.fill(0.);
    for (unsigned int q = 0; q < n_corners; ++q)
      {
        std::array<double, dim> xi;
        for (int d = 0; d < dim; ++d)
          xi[d] = gp[(q >> d) & 1];
        const double w = std::pow(0.5, dim) * std::pow(h, dim);
        std::array<std::array<double, dim>, n_corners> grad;
        for (unsigned int a = 0; a < n_corners; ++a)
          for (int k = 0; k < dim; ++k)
            {
              double g = ((a >> k) & 1) ? 1. : -1.;
              for (int d = 0; d < dim; ++d)
                if (d != k)
                  g *= ((a >> d) & 1) ? xi[d] : 1. - xi[d];
              grad[a][k] = g / h;
            }
        for (unsigned int a = 0; a < n_corners; ++a)
          for (unsigned int b = 0; b < n_corners; ++b)
            for (int k = 0; k < dim; ++k)
              stiffness[a][b] += w * grad[a][k] * grad[b][k];
      }

    type     = grid.make_field(outside);
    type_old = grid.make_field(-1.);
    p_cell   = grid.make_field(0.);
    mass     = grid.make_node_field();
    volume   = grid.make_node_field();
    if (prm.volume_correction > 0)
      {
        occupancy = grid.make_field(0.);
        psi       = grid.make_field(0.);
      }
    if (prm.front_wall_film)
      film.emplace(grid);
    if (prm.affine())
      {
        using P = typename MaterialPoints<dim>::PropertyIndex;
        AssertThrow(points.n_properties() >= P::n_properties,
                    ExcMessage("Melt flow/Velocity transfer = APIC: the "
                               "material points do not carry the affine "
                               "velocity"));
        points.set_phase_change_drops_affine(true);
      }
    node_mark = std::vector<std::uint8_t>(grid.n_local_nodes(), 0);
    node_fix  = std::vector<std::uint8_t>(grid.n_local_nodes(), 0);
    for (int d = 0; d < dim; ++d)
      {
        mom[d]    = grid.make_node_field();
        u_old[d]  = grid.make_node_field();
        u_new[d]  = grid.make_node_field();
        force[d]  = grid.make_node_field();
        u_cell[d] = grid.make_field();
      }
  }

  template <int dim>
  typename IncompressibleFlow<dim>::StepLimits
  IncompressibleFlow<dim>::stable_time_step() const
  {
    double umax = stats.max_point_speed;
    if (stats.steps == 0)
      {
        using P = typename MaterialPoints<dim>::PropertyIndex;
        for (const auto &particle : points.particle_handler())
          {
            const auto v = particle.get_properties();
            if (v[P::state] != MaterialPoints<dim>::fluid)
              continue;
            double s = 0;
            for (int d = 0; d < dim; ++d)
              s += v[P::velocity + d] * v[P::velocity + d];
            umax = std::max(umax, std::sqrt(s));
          }
        umax = Utilities::MPI::max(umax, grid.communicator());
      }
    const double h      = grid.h();
    StepLimits   limits = material_limits(prm, h, rho);
    limits.convective =
      prm.cfl * h / std::max(umax, std::sqrt(prm.gravity.norm() * h) + 1e-300);
    return limits;
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::particles_to_grid()
  {
    Section section(timer, "flow: transfer to grid");
    classify_cells();
    transfer_to_grid();
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::classify_cells()
  {
    // One pass over the points of the occupied cells does both the cell
    // classification and the P2G scatter of mass and momentum (a deal.II
    // particles_in_cell() range per cell is the dominant cost of a pass).
    using P             = typename MaterialPoints<dim>::PropertyIndex;
    const auto  &status = grid.cell_status();
    const double h      = grid.h();
    const double ih     = 1. / h;
    const auto  &x0     = grid.origin();
    std::swap(type, type_old);
    for (std::size_t i = 0; i < type.size(); ++i)
      type[i] = status[i] == BackgroundGrid<dim>::outside ? outside : gas;
    fluid_cells.clear();
    // Zero the whole node arrays: sum_shared_nodes() writes the partial sums
    // of neighbour ranks also onto nodes that are not active here, and stale
    // values there would re-enter the next sum (a memset, ~1 ns per node).
    std::fill(mass.begin(), mass.end(), 0.);
    for (int d = 0; d < dim; ++d)
      std::fill(mom[d].begin(), mom[d].end(), 0.);
    const auto &handler      = points.particle_handler();
    const bool  count_volume = prm.volume_correction > 0;
    const auto &occupied     = points.occupied_cells();
    // Only cells that held a fluid point at the last classification, or
    // that points entered or whose points changed state since, can hold
    // one now (MaterialPoints::cell_changed_since()):
    // the others (the substrate and powder far from the melt, most cells
    // while only a few drops are liquid) stay solid without a look at
    // their points.
    const bool all_cells = !classified;
    for (std::size_t c = 0; c < occupied.size(); ++c)
      {
        // Cells without a fluid point (powder, substrate) are found from
        // the cached property arrays; only fluid cells need the positions.
        const auto &[idx, cell] = occupied[c];
        if (!all_cells && type_old[idx] != fluid &&
            !points.cell_changed_since(classified_at, idx))
          {
            type[idx] = solid; // (occupancy is read in fluid cells only)
            continue;
          }
        bool   any_fluid = false;
        double V_cell    = 0;
        for (const double *v : points.cell_point_properties(c))
          {
            V_cell += v[P::volume];
            any_fluid = any_fluid || v[P::state] == MaterialPoints<dim>::fluid;
          }
        type[idx] = any_fluid ? fluid : solid;
        if (count_volume)
          occupancy[idx] = V_cell; // read only for fluid cells
        if (!any_fluid)
          continue;
        fluid_cells.push_back(idx);
        const auto        ijk = grid.global_index(idx);
        const std::size_t n0  = grid.first_node_of_cell(idx);
        double           *nm[n_corners];
        double           *nu[dim][n_corners];
        for (unsigned int k = 0; k < n_corners; ++k)
          {
            nm[k] = &mass[n0 + corner_offset[k]];
            for (int d = 0; d < dim; ++d)
              nu[d][k] = &mom[d][n0 + corner_offset[k]];
          }
        // The point loop is compiled twice (with and without the affine
        // velocity), so that APIC costs nothing when it is off.
        const auto scatter = [&](auto affine_tag) {
          constexpr bool affine = decltype(affine_tag)::value;
          for (const auto &particle : handler.particles_in_cell(cell))
            {
              const auto v = particle.get_properties();
              if (v[P::state] != MaterialPoints<dim>::fluid)
                continue;
              const Point<dim> &x = particle.get_location();
              // Tent weights of the 2^dim corners (product over
              // directions).
              double w[n_corners];
              tent_weights<dim>(x, x0, ih, ijk, v[P::mass], w);
              double vel[dim];
              for (int d = 0; d < dim; ++d)
                vel[d] = v[P::velocity + d];
              if constexpr (affine)
                {
                  // APIC: corner k receives v_p + C_p (x_k - x_p), with
                  // x_k - x_p = h (k_e - xi_e): the velocity at corner 0
                  // plus h C_de for each upper direction e of k.
                  const double *C = &v[P::affine_velocity];
                  double        hC[dim * dim], v0[dim];
                  for (int d = 0; d < dim; ++d)
                    v0[d] = vel[d];
                  for (int e = 0; e < dim; ++e)
                    {
                      const double xi = (x[e] - x0[e]) * ih - ijk[e];
                      for (int d = 0; d < dim; ++d)
                        {
                          hC[d * dim + e] = h * C[d * dim + e];
                          v0[d] -= hC[d * dim + e] * xi;
                        }
                    }
                  for (unsigned int k = 0; k < n_corners; ++k)
                    {
                      *nm[k] += w[k];
                      for (int d = 0; d < dim; ++d)
                        {
                          double u = v0[d];
                          for (int e = 0; e < dim; ++e)
                            if ((k >> e) & 1)
                              u += hC[d * dim + e];
                          *nu[d][k] += w[k] * u;
                        }
                    }
                }
              else
                for (unsigned int k = 0; k < n_corners; ++k)
                  {
                    *nm[k] += w[k];
                    for (int d = 0; d < dim; ++d)
                      *nu[d][k] += w[k] * vel[d];
                  }
            }
        };
        if (prm.affine())
          scatter(std::true_type());
        else
          scatter(std::false_type());
      }
    classified_at = points.layout_mark();
    classified    = true;
    grid.update_ghosts(type);

    // Active nodes (nodes of owned fluid cells) and their wall flags.
    for (const auto n : active)
      node_mark[n] = 0;
    active.clear();
    active_cell.clear();
    if (film)
      film->clear();
    const auto  &nc       = grid.n_cells();
    const double node_vol = std::pow(0.5 * grid.h(), dim);
    for (const auto c : fluid_cells)
      {
        const std::size_t n0  = grid.first_node_of_cell(c);
        const auto        ijc = grid.global_index(c);
        for (unsigned int k = 0; k < n_corners; ++k)
          {
            const std::size_t n = n0 + corner_offset[k];
            if (node_mark[n])
              continue;
            node_mark[n] = 1;
            active.push_back(n);
            const std::size_t c0 = c + around_offset[k];
            active_cell.push_back(c0);
            // Node ijk equals the cell index of c0.
            std::uint8_t fix = 0;
            for (int d = 0; d < dim; ++d)
              {
                const int i = ijc[d] + int((k >> d) & 1);
                if (i == 0 || i == int(nc[d]))
                  fix |= (1u << d);
              }
            int                n_fluid    = 0;
            const std::uint8_t domain_fix = fix;
            for (unsigned int j = 0; j < n_corners; ++j)
              {
                const auto t = type[c0 - around_offset[j]];
                if (t == solid)
                  fix = (1u << dim) - 1;
                n_fluid += (t == fluid);
              }
            if (film && fix != domain_fix)
              film->add_wall_node(n, c0, domain_fix);
            node_fix[n] = fix;
            volume[n]   = n_fluid * node_vol;
          }
      }
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::transfer_to_grid()
  {
    // The scatter itself happened in classify_cells(); sum over ranks and
    // divide.
    grid.sum_shared_nodes(mass);
    for (int d = 0; d < dim; ++d)
      grid.sum_shared_nodes(mom[d]);
    for (const auto n : active)
      for (int d = 0; d < dim; ++d)
        u_old[d][n] = mass[n] > 0 ? mom[d][n] / mass[n] : 0.;
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::apply_boundary_conditions(
    std::array<std::vector<double>, dim> &u) const
  {
    for (const auto n : active)
      if (node_fix[n])
        for (int d = 0; d < dim; ++d)
          if ((node_fix[n] >> d) & 1)
            u[d][n] = 0;
    if (film)
      film->project(u);
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::enable_front_wall_expulsion(const double spot_radius,
                                                       const double T_far)
  {
    expulsion.reset();
    if (!prm.front_wall_expulsion)
      return;
    if (!(prm.recoil_coefficient > 0))
      throw InputError("Melt flow/Front wall expulsion",
                       "true",
                       "needs the recoil pressure that expels the melt: "
                       "Melt flow/Recoil coefficient > 0 (got " +
                         num(prm.recoil_coefficient) + ")");
    expulsion = std::make_unique<FrontWallExpulsion<dim>>(
      grid,
      mat,
      RecoilLaw(mat, prm.recoil_coefficient, prm.recoil_above_ambient),
      spot_radius,
      T_far);
  }

  template <int dim>
  unsigned long
  IncompressibleFlow<dim>::recoil_driven_cells() const
  {
    unsigned long n = 0;
    if ((film || expulsion) && recoil_driven.size() == grid.n_local())
      for (const auto c : fluid_cells)
        n += recoil_driven[c] != 0;
    return Utilities::MPI::sum(n, grid.communicator());
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::predictor(const double               dt,
                                     const std::vector<double> *gamma)
  {
    Section     section(timer, "flow: predictor");
    const auto &surface_force = surface.marangoni_force();
    const bool  marangoni     = prm.surface_parameters().marangoni();
    // Viscous force -mu K u per fluid cell, summed over ranks; per cell
    // also its dissipation mu u^T K u, for check_viscous_energy().
    const bool viscous = prm.viscosity > 0;
    if (viscous)
      {
        for (int d = 0; d < dim; ++d)
          std::fill(force[d].begin(), force[d].end(), 0.);
        cell_dissipation.resize(fluid_cells.size());
        for (std::size_t i = 0; i < fluid_cells.size(); ++i)
          {
            const std::size_t n0  = grid.first_node_of_cell(fluid_cells[i]);
            double            uKu = 0;
            for (int d = 0; d < dim; ++d)
              {
                double u[n_corners];
                for (unsigned int b = 0; b < n_corners; ++b)
                  u[b] = u_old[d][n0 + corner_offset[b]];
                for (unsigned int a = 0; a < n_corners; ++a)
                  {
                    double f = 0;
                    for (unsigned int b = 0; b < n_corners; ++b)
                      f += stiffness[a][b] * u[b];
                    force[d][n0 + corner_offset[a]] -= prm.viscosity * f;
                    uKu += u[a] * f;
                  }
              }
            cell_dissipation[i] = prm.viscosity * uKu;
          }
        for (int d = 0; d < dim; ++d)
          grid.sum_shared_nodes(force[d]);
        check_viscous_energy(dt);
      }
    const double darcy = dt * prm.darcy_constant / rho;
    for (std::size_t a = 0; a < active.size(); ++a)
      {
        const std::size_t n       = active[a];
        double            damping = 1;
        // Film nodes (Melt flow/Front wall film): the film is liquid, its
        // mushy layer lies inside the cell, under the slip condition.
        if (gamma != nullptr && prm.darcy_constant > 0 &&
            !(film && film->is_film(n)))
          {
            const std::size_t c0 = active_cell[a];
            double            g  = 0;
            int               k  = 0;
            for (unsigned int j = 0; j < n_corners; ++j)
              if (type[c0 - around_offset[j]] == fluid)
                g += (*gamma)[c0 - around_offset[j]], ++k;
            g = k > 0 ? g / k : 1.;
            damping +=
              darcy * (1 - g) * (1 - g) / (g * g * g + prm.darcy_epsilon);
          }
        for (int d = 0; d < dim; ++d)
          {
            double acc = prm.gravity[d];
            if (viscous && volume[n] > 0)
              acc += force[d][n] / (rho * volume[n]);
            if (marangoni && volume[n] > 0)
              acc += surface_force[d][n] / (rho * volume[n]);
            u_new[d][n] = (u_old[d][n] + dt * acc) / damping;
          }
      }
    apply_boundary_conditions(u_new);
  }

  // The explicit viscous update u -> u + dt M^-1 f, f = -mu K u, with K the
  // fluid cells' Q1 stiffness and M their lumped masses rho V_n, changes
  // the kinetic energy by
  //   dE = dt (-u^T mu K u + dt/2 f^T M^-1 f),
  // which no step within the stable limit of forward Euler (dt mu lambda <=
  // 2 for every eigenvalue lambda of M^-1 K) can make positive: the viscous
  // term only dissipates. A step above it makes the grid-scale modes grow,
  // and the step rejection of advance() can keep them bounded and wrong
  // instead of non-finite. So dE > 0 beyond round-off stops the run. Both
  // sums go cell by cell over the owned fluid cells (a node's share of
  // f^T M^-1 f divided among its fluid cells), so no node is counted
  // twice on two ranks; one reduction of three numbers per step.
  template <int dim>
  void
  IncompressibleFlow<dim>::check_viscous_energy(const double dt) const
  {
    const double node_vol   = std::pow(0.5 * grid.h(), dim);
    double       sums[3]    = {0, 0, 0}; // dissipation, f M^-1 f, 2 E
    double       worst      = -std::numeric_limits<double>::max();
    std::size_t  worst_cell = 0;
    for (std::size_t i = 0; i < fluid_cells.size(); ++i)
      {
        const std::size_t n0  = grid.first_node_of_cell(fluid_cells[i]);
        double            fMf = 0, uMu = 0;
        for (unsigned int a = 0; a < n_corners; ++a)
          {
            const std::size_t n  = n0 + corner_offset[a];
            double            f2 = 0, u2 = 0;
            for (int d = 0; d < dim; ++d)
              {
                f2 += force[d][n] * force[d][n];
                u2 += u_old[d][n] * u_old[d][n];
              }
            fMf += f2 * node_vol / (rho * volume[n] * volume[n]);
            uMu += u2;
          }
        sums[0] += cell_dissipation[i];
        sums[1] += fMf;
        sums[2] += rho * node_vol * uMu;
        const double gain = 0.5 * dt * fMf - cell_dissipation[i];
        if (gain > worst)
          worst = gain, worst_cell = fluid_cells[i];
      }
    Utilities::MPI::sum(ArrayView<const double>(sums, 3),
                        grid.communicator(),
                        ArrayView<double>(sums, 3));
    const double dE = dt * (0.5 * dt * sums[1] - sums[0]);
    const double E  = 0.5 * sums[2];
    if (!(dE > 1e-10 * E))
      return;
    // Where the gain is largest: the rank holding the global maximum says.
    const double global_worst = Utilities::MPI::max(worst, grid.communicator());
    Point<dim>   where;
    const bool   found = fluid_cells.size() > 0 && worst >= global_worst;
    if (found)
      where = grid.cell_center(worst_cell);
    share_location(found, where, grid.communicator());
    const auto l = stable_time_step();
    throw CollectiveError(
      "Melt flow: the explicit viscous update of a step of " + num(dt) +
      " s raised the melt's kinetic energy by " +
      num(dE / std::max(E, 1e-300)) +
      " of itself, which no stable step can do (viscosity only dissipates); "
      "the grid-scale velocity mode grows fastest in the cell at " +
      location_text(where) +
      " m. The step exceeds the stable limit of the "
      "explicit viscous term (femp's viscous limit h^2 rho/(2 dim mu) is " +
      num(l.viscous) +
      " s here): use 'Melt flow/Time step = 0' (steps "
      "chosen within the limits) or a smaller prescribed step.");
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::update_free_surface(const std::vector<double> *T)
  {
    Section section(timer, "flow: free surface");
    surface.update(type, fluid_cells, T);
    if (film || expulsion)
      surface.mark_recoil_driven(fluid_cells, recoil_driven);
    if (film)
      film->select(type, recoil_driven, node_fix);
    if (expulsion)
      {
        Assert(T, ExcMessage("Front wall expulsion needs the temperature"));
        expulsion->select(fluid_cells,
                          recoil_driven,
                          type,
                          surface.surface_pressure(),
                          surface.capillary_pressure(),
                          surface.alpha_at_cells(),
                          *T);
        const unsigned long n =
          Utilities::MPI::sum(expulsion->n_cells(), grid.communicator());
        stats.expelling_cell_steps += n;
        stats.expelling_steps += n > 0;
        stats.max_expulsion_speed =
          std::max(stats.max_expulsion_speed,
                   Utilities::MPI::max(expulsion->max_speed(),
                                       grid.communicator()));
      }
  }

  template <int dim>
  typename PressureSolver<dim>::FluidCells
  IncompressibleFlow<dim>::fluid_cell_set() const
  {
    return {type,
            type_old,
            fluid_cells,
            surface.near_fluid(),
            surface.interface_position()};
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::velocity_divergence()
  {
    // Divergence of u* at the owned fluid cells.
    const double scale = 1. / (grid.h() * (1u << (dim - 1)));
    divergence.resize(fluid_cells.size());
    for (std::size_t i = 0; i < fluid_cells.size(); ++i)
      {
        const std::size_t n0  = grid.first_node_of_cell(fluid_cells[i]);
        double            div = 0;
        for (unsigned int k = 0; k < n_corners; ++k)
          for (int d = 0; d < dim; ++d)
            div +=
              (((k >> d) & 1) ? 1. : -1.) * u_new[d][n0 + corner_offset[k]];
        divergence[i] = div * scale;
      }
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::pressure_solve(const double dt)
  {
    velocity_divergence();
    const auto cells = fluid_cell_set();
    const bool capillary =
      prm.surface_tension > 0 || prm.recoil_coefficient > 0;
    pressure_solver.update_system(cells);
    {
      const auto &s = pressure_solver.statistics();
      load.all += s.n_fluid_cells;
      load.busiest += s.n_fluid_cells_busiest;
      load.own += cells.fluid.size();
    }
    pressure_solver.solve_pressure(cells,
                                   divergence,
                                   surface.surface_pressure(),
                                   capillary,
                                   rho,
                                   dt,
                                   p_cell);
    copy_solver_statistics();
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::copy_solver_statistics()
  {
    const auto &s           = pressure_solver.statistics();
    stats.matrix_rebuilds   = s.matrix_rebuilds;
    stats.amg_setups        = s.amg_setups;
    stats.cg_iterations     = s.cg_iterations;
    stats.last_iterations   = s.last_iterations;
    stats.max_iterations    = s.max_iterations;
    stats.n_fluid_cells     = s.n_fluid_cells;
    stats.volume_iterations = s.volume_iterations;
    stats.volume_skipped    = s.volume_skipped;
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::correction(const double dt)
  {
    Section      section(timer, "flow: correction");
    const auto  &theta     = surface.interface_position();
    const auto  &p_surface = surface.surface_pressure();
    const double h         = grid.h();
    const auto  &cs        = grid.strides();
    const double f         = dt / (rho * h);
    for (std::size_t a = 0; a < active.size(); ++a)
      {
        const std::size_t n  = active[a];
        const std::size_t c0 = active_cell[a]; // cell above the node
        for (int d = 0; d < dim; ++d)
          {
            if ((node_fix[n] >> d) & 1)
              continue;
            double sum = 0;
            int    k   = 0;
            // Pairs: upper cell c0 - o (o_d = 0), lower = upper - stride_d.
            for (unsigned int j = 0; j < n_corners; ++j)
              {
                if ((j >> d) & 1)
                  continue;
                const std::size_t up = c0 - around_offset[j];
                const std::size_t lo = up - cs[d];
                const auto        tu = type[up], tl = type[lo];
                if (tu == fluid && tl == fluid)
                  sum += p_cell[up] - p_cell[lo], ++k;
                else if (tu == fluid && tl == gas)
                  sum += (p_cell[up] - p_surface[up]) / theta[2 * d][up], ++k;
                else if (tu == gas && tl == fluid)
                  sum -= (p_cell[lo] - p_surface[lo]) / theta[2 * d + 1][lo],
                    ++k;
              }
            if (k > 0)
              u_new[d][n] -= f * sum / k;
          }
      }
    apply_boundary_conditions(u_new);
    if (expulsion)
      expulsion->apply(active, active_cell, node_fix, u_new);
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::stop_non_finite_velocity(const double dt) const
  {
    // Every rank knows (max_nodal_speed() is global); the lowest rank with
    // a non-finite nodal velocity says where.
    Point<dim> where;
    bool       found = false;
    for (const auto n : active)
      {
        bool finite = true;
        for (int d = 0; d < dim; ++d)
          finite = finite && std::isfinite(u_new[d][n]);
        if (finite)
          continue;
        std::size_t rest = n;
        for (int e = dim - 1; e >= 0; --e)
          {
            const int i =
              grid.box_lower()[e] + int(rest / grid.node_strides()[e]);
            rest %= grid.node_strides()[e];
            where[e] = grid.origin()[e] + i * grid.h();
          }
        found = true;
        break;
      }
    share_location(found, where, grid.communicator());
    throw CollectiveError("Melt flow became unstable: non-finite velocity at "
                          "the grid node at x = " +
                          location_text(where) + " m (time step " + num(dt) +
                          " s). Reduce the time step.");
  }

  // Volume correction (doc/flow.md, "Volume correction"). The fluid points
  // carry a fixed volume, but the advection with an only approximately
  // divergence-free nodal velocity lets them bunch (up to 27 per cell
  // instead of 4 in the dam break), and cells between the bunches empty:
  // the area of the cells holding fluid shrinks and so does the metal
  // fraction of the heat equation. This is the density-invariance
  // ("volume") correction of incompressible SPH and PIC/FLIP solvers
  // applied to the positions only: with e_c = V_c/h^dim - 1 the volume
  // error of a fluid cell (V_c the volume of the metal points in it), solve
  //   lap(psi) = c e_c  (psi = 0 at the free surface, zero flux into walls
  //                      and solid cells)
  // with the pressure matrix (A = -h^2 lap: A (psi/h^2) = -c e), and move
  // each point by grad(psi), taken on the cell faces and interpolated
  // linearly across the cell per direction (the lowest-order
  // Raviart-Thomas field of the face values), so that its divergence in
  // each cell is exactly c e_c: over-filled cells push their points apart,
  // under-filled ones draw them in. Next to the free surface (a gas cell
  // among the 3^dim neighbours) cells are partly filled by nature, so only
  // the over-filled part (e_c > 0) counts there. The velocities are not
  // changed (a velocity correction that the points keep over-expanded the
  // dam break, doc/flow.md). The solve reuses the matrix and the AMG
  // hierarchy of the pressure and its tolerance (with 1e-6 the 1- and
  // 2-rank dam breaks drifted apart by 0.01 a in the late front: the flow
  // amplifies round-off), and a solve that does not converge (a fluid region
  // without free surface has a singular matrix and an inconsistent right
  // hand side) skips the correction for that step (counted in the
  // statistics).
  template <int dim>
  void
  IncompressibleFlow<dim>::volume_solve()
  {
    if (prm.volume_correction == 0)
      return;
    Section      section(timer, "flow: volume correction");
    const double ihd = std::pow(1. / grid.h(), dim);
    volume_source.resize(fluid_cells.size());
    for (std::size_t i = 0; i < fluid_cells.size(); ++i)
      {
        const auto c = fluid_cells[i];
        double     e = occupancy[c] * ihd - 1;
        if (e < 0)
          for (const auto o : stencil)
            if (type[c + o] == gas)
              {
                e = 0;
                break;
              }
        volume_source[i] = -prm.volume_correction * e;
      }
    pressure_solver.solve_volume(fluid_cell_set(), volume_source, psi);
    copy_solver_statistics();
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::volume_faces(const std::size_t c, double *G) const
  {
    const auto  &theta = surface.interface_position();
    const double h     = grid.h();
    const auto  &cs    = grid.strides();
    for (int d = 0; d < dim; ++d)
      for (const int side : {0, 1})
        {
          const std::size_t e    = side ? c + cs[d] : c - cs[d];
          double            jump = 0; // psi(neighbour or ghost) - psi(c), /h^2
          if (type[e] == fluid)
            jump = psi[e] - psi[c];
          else if (type[e] == gas)
            jump = -psi[c] / theta[2 * d + side][c];
          // d psi / d x_d on the face, m (psi = h^2 x the solution).
          G[2 * d + side] = h * (side ? jump : -jump);
        }
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::grid_to_points(const double dt)
  {
    Section section(timer, "flow: grid to points + advection");
    using P              = typename MaterialPoints<dim>::PropertyIndex;
    const double h       = grid.h();
    const double ih      = 1. / h;
    const auto  &x0      = grid.origin();
    const auto  &nc      = grid.n_cells();
    const double beta    = prm.flip_fraction;
    auto        &handler = points.particle_handler_for_update();
    // Cells where a point left (increasing): only their points are checked
    // by the re-sort, not every point of the powder and the substrate.
    std::vector<std::uint32_t> left_cells;
    // The point loop is compiled eight times (with and without the point
    // shifting, the volume correction and the APIC transfer), so that each
    // costs nothing when it is off.
    const auto loop = [&](auto mode_tag) {
      constexpr int  mode     = decltype(mode_tag)::value;
      constexpr bool shifting = mode & 1;
      constexpr bool volume_c = mode & 2;
      constexpr bool affine   = mode & 4;
      bool           moved    = false;
      double         umax     = 0;
      for (const auto &[idx, cell] : points.occupied_cells())
        {
          if (type[idx] != fluid)
            continue;
          const auto        ijk = grid.global_index(idx);
          const std::size_t n0  = grid.first_node_of_cell(idx);
          ShiftCell         sc;
          if constexpr (shifting)
            sc = shift_cell(idx);
          double G[2 * dim] = {};
          if constexpr (volume_c)
            volume_faces(idx, G);
          bool cell_left = false;
          for (auto &particle : handler.particles_in_cell(cell))
            {
              const auto v = particle.get_properties();
              if (v[P::state] != MaterialPoints<dim>::fluid)
                continue;
              Point<dim> x = particle.get_location();
              double     xi[dim];
              for (int d = 0; d < dim; ++d)
                xi[d] = (x[d] - x0[d]) * ih - ijk[d];
              double vg[dim] = {}, dv[dim] = {};
              // APIC: C_p = sum u_k (grad w_k)^T, times h (row-major).
              double Ch[dim * dim] = {};
              for (unsigned int k = 0; k < n_corners; ++k)
                {
                  double w = 1;
                  for (int d = 0; d < dim; ++d)
                    w *= ((k >> d) & 1) ? xi[d] : 1. - xi[d];
                  const std::size_t n = n0 + corner_offset[k];
                  if constexpr (affine)
                    {
                      // h dw_k/dx_e = (+-1) prod_{f != e} (xi_f or 1 - xi_f).
                      double gw[dim];
                      for (int e = 0; e < dim; ++e)
                        {
                          gw[e] = ((k >> e) & 1) ? 1. : -1.;
                          for (int f = 0; f < dim; ++f)
                            if (f != e)
                              gw[e] *= ((k >> f) & 1) ? xi[f] : 1. - xi[f];
                        }
                      for (int d = 0; d < dim; ++d)
                        {
                          vg[d] += w * u_new[d][n];
                          for (int e = 0; e < dim; ++e)
                            Ch[d * dim + e] += u_new[d][n] * gw[e];
                        }
                    }
                  else
                    for (int d = 0; d < dim; ++d)
                      {
                        vg[d] += w * u_new[d][n];
                        dv[d] += w * (u_new[d][n] - u_old[d][n]);
                      }
                }
              if constexpr (affine)
                for (int c = 0; c < dim * dim; ++c)
                  v[P::affine_velocity + c] = Ch[c] * ih;
              double     speed2 = 0, step2 = 0;
              bool       left = false;
              Point<dim> ref;
              double     shift[dim] = {};
              if constexpr (shifting)
                {
                  double s2 = 0;
                  for (int d = 0; d < dim; ++d)
                    s2 += vg[d] * vg[d];
                  shift_of_point(sc, xi, std::sqrt(s2), dt, shift);
                }
              if constexpr (volume_c)
                {
                  // grad(psi) across the cell, at most h/4.
                  double vc[dim], n2 = 0;
                  for (int d = 0; d < dim; ++d)
                    {
                      vc[d] = (1 - xi[d]) * G[2 * d] + xi[d] * G[2 * d + 1];
                      n2 += vc[d] * vc[d];
                    }
                  const double f =
                    n2 > 0.0625 * h * h ? 0.25 * h / std::sqrt(n2) : 1.;
                  for (int d = 0; d < dim; ++d)
                    shift[d] += f * vc[d];
                }
              for (int d = 0; d < dim; ++d)
                {
                  if constexpr (affine)
                    v[P::velocity + d] = vg[d];
                  else
                    v[P::velocity + d] =
                      beta * (v[P::velocity + d] + dv[d]) + (1 - beta) * vg[d];
                  speed2 += v[P::velocity + d] * v[P::velocity + d];
                  const double dx = dt * vg[d];
                  step2 += dx * dx;
                  // Stay inside the domain (walls are free slip).
                  const double lo = x0[d] + 1e-9 * h;
                  const double hi = x0[d] + nc[d] * h - 1e-9 * h;
                  x[d]   = std::min(std::max(x[d] + ((shifting || volume_c) ?
                                                       dx + shift[d] :
                                                       dx),
                                           lo),
                                  hi);
                  ref[d] = (x[d] - x0[d]) * ih - ijk[d];
                  left   = left || ref[d] < 0 || ref[d] >= 1;
                }
              if (!(step2 <= h * h))
                {
                  std::ostringstream msg;
                  msg << "Melt flow became unstable: a point at x = " << x
                      << " m would move " << std::sqrt(step2)
                      << " m in one step, more than a cell (" << h
                      << " m); time step " << dt << " s. Reduce the time step "
                      << "or the Courant number.";
                  throw std::runtime_error(msg.str());
                }
              umax = std::max(umax, speed2);
              particle.set_location(x);
              if (!left)
                particle.set_reference_location(ref);
              cell_left = cell_left || left;
            }
          if (cell_left)
            left_cells.push_back(idx);
          moved = moved || cell_left;
        }
      return std::make_pair(moved, umax);
    };
    const int mode = (prm.point_shifting > 0 ? 1 : 0) +
                     (prm.volume_correction > 0 ? 2 : 0) +
                     (prm.affine() ? 4 : 0);
    const auto [moved, umax] =
      mode == 0 ? loop(std::integral_constant<int, 0>()) :
      mode == 1 ? loop(std::integral_constant<int, 1>()) :
      mode == 2 ? loop(std::integral_constant<int, 2>()) :
      mode == 3 ? loop(std::integral_constant<int, 3>()) :
      mode == 4 ? loop(std::integral_constant<int, 4>()) :
      mode == 5 ? loop(std::integral_constant<int, 5>()) :
      mode == 6 ? loop(std::integral_constant<int, 6>()) :
                  loop(std::integral_constant<int, 7>());
    stats.max_point_speed =
      std::sqrt(Utilities::MPI::max(umax, grid.communicator()));
    if (Utilities::MPI::logical_or(moved, grid.communicator()))
      {
        // Its own section, not inside the advection's (no time counted
        // twice in the cost report and layer_cost.csv).
        section.scope.reset();
        Section s(timer, "flow: re-sort points");
        // Points are moved cell by cell, to a neighbour rank where their new
        // cell is a ghost cell; only a point beyond the ghost layer (not
        // possible with the one-cell step limit) needs deal.II's global sort
        // of all points.
        if (!points.relocate_points(&left_cells))
          {
            points.points_moved();
            ++stats.global_sorts;
          }
        ++stats.resorts;
      }
  }

  // Point shifting: fluid points are displaced down the gradient of the
  // metal fraction alpha (nodal values from FreeSurface::update()), so that
  // they stay evenly spread (4 per cell in 2D) instead of bunching or leaving
  // voids in the liquid. The displacement -A h |u| dt grad(alpha) is the
  // diffusion-type shifting of SPH (Lind et al. 2012 with the
  // velocity-scaled coefficient of Skillen et al. 2013), here with the
  // gradient of the grid's bilinear alpha; next to the free surface (a gas
  // cell among the 3^dim cells round the point's cell) only its component
  // tangential to the surface is kept, so the liquid does not spread

  template <int dim>
  typename IncompressibleFlow<dim>::ShiftCell
  IncompressibleFlow<dim>::shift_cell(const std::size_t c) const
  {
    ShiftCell   sc;
    const auto &cs = grid.strides();
    sc.alpha       = surface.corner_alpha(c);
    for (const auto o : stencil)
      sc.near_surface = sc.near_surface || type[c + o] == gas;
    if (sc.near_surface)
      {
        // Outward normal -grad(alpha~) at the cell centre (central
        // differences; zero gradient across the domain boundary).
        const auto &status     = grid.cell_status();
        const auto &alpha_cell = surface.alpha_at_cells();
        double      norm       = 0;
        for (int d = 0; d < dim; ++d)
          {
            const std::size_t lo = c - cs[d], up = c + cs[d];
            const bool        l = status[lo] != BackgroundGrid<dim>::outside;
            const bool        u = status[up] != BackgroundGrid<dim>::outside;
            sc.normal[d]        = -((u ? alpha_cell[up] : alpha_cell[c]) -
                             (l ? alpha_cell[lo] : alpha_cell[c]));
            norm += sc.normal[d] * sc.normal[d];
          }
        norm = std::sqrt(norm);
        for (int d = 0; d < dim; ++d)
          sc.normal[d] = norm > 1e-12 ? sc.normal[d] / norm : 0.;
      }
    return sc;
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::shift_of_point(const ShiftCell &sc,
                                          const double    *xi,
                                          const double     speed,
                                          const double     dt,
                                          double          *dx) const
  {
    // grad(alpha) h: derivative of the bilinear (trilinear) interpolant in
    // reference coordinates.
    double g[dim] = {};
    for (unsigned int k = 0; k < n_corners; ++k)
      for (int d = 0; d < dim; ++d)
        {
          double w = ((k >> d) & 1) ? 1. : -1.;
          for (int e = 0; e < dim; ++e)
            if (e != d)
              w *= ((k >> e) & 1) ? xi[e] : 1. - xi[e];
          g[d] += w * sc.alpha[k];
        }
    if (sc.near_surface)
      {
        double gn = 0;
        for (int d = 0; d < dim; ++d)
          gn += g[d] * sc.normal[d];
        for (int d = 0; d < dim; ++d)
          g[d] -= gn * sc.normal[d];
      }
    const double a  = -prm.point_shifting * speed * dt; // times grad(alpha) h
    double       n2 = 0;
    for (int d = 0; d < dim; ++d)
      {
        dx[d] = a * g[d];
        n2 += dx[d] * dx[d];
      }
    const double cap = 0.25 * grid.h();
    if (n2 > cap * cap)
      for (int d = 0; d < dim; ++d)
        dx[d] *= cap / std::sqrt(n2);
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::step(const double dt, const CellFields<dim> &fields)
  {
    progress::phase("melt-flow sub-steps");
    progress::substep(stats.steps + 1, dt);
    const StepLimits limits = stable_time_step();
    if (!(dt > 0) || dt > limits.viscous * (1 + 1e-12) ||
        dt > limits.capillary * (1 + 1e-12))
      {
        std::ostringstream msg;
        msg << "Melt flow: the time step " << dt
            << " s is not positive or exceeds the viscous limit "
            << limits.viscous << " s (h^2 rho/(2 dim mu)) or the capillary "
            << "limit " << limits.capillary
            << " s (sqrt(rho h^3/(2 pi sigma))).";
        throw std::runtime_error(msg.str());
      }
    advance(dt, 0, fields);
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::advance(const double           dt,
                                   const unsigned int     depth,
                                   const CellFields<dim> &fields)
  {
    particles_to_grid(); // P2G: cell classes, nodal mass and momentum
    update_free_surface(fields.temperature); // alpha, theta, p_s, Marangoni
    predictor(dt, fields.liquid_fraction);   // u*: gravity, viscosity,
                                             // surface forces, Darcy
    pressure_solve(dt);                      // div(dt/rho grad p) = div u*
    correction(dt);                          // u = u* - dt/rho grad p
    // Step rejection: if the new nodal velocity would carry a point more
    // than a cell (e.g. a sudden recoil or capillary pressure that the
    // limits of the last step did not foresee), redo the step as two halves.
    const double umax = max_nodal_speed();
    if (!std::isfinite(umax))
      stop_non_finite_velocity(dt);
    if (umax * dt > grid.h())
      {
        if (depth >= 20)
          {
            std::ostringstream msg;
            msg << "Melt flow became unstable: nodal speed " << umax
                << " m/s moves points more than a cell even after halving "
                << "the step 20 times (step " << dt << " s).";
            throw CollectiveError(msg.str()); // umax is global
          }
        ++stats.halvings;
        advance(dt / 2, depth + 1, fields);
        advance(dt / 2, depth + 1, fields);
        return;
      }
    update_cell_velocity();
    volume_solve();     // psi of the volume correction (when on)
    grid_to_points(dt); // G2P: FLIP/PIC update and advection
    ++stats.steps;
  }

  template <int dim>
  double
  IncompressibleFlow<dim>::max_nodal_speed() const
  {
    double umax = 0;
    for (const auto n : active)
      {
        double s2 = 0;
        for (int d = 0; d < dim; ++d)
          s2 += u_new[d][n] * u_new[d][n];
        // A non-finite velocity makes the maximum infinite on every rank.
        umax = std::isfinite(s2) ? std::max(umax, s2) :
                                   std::numeric_limits<double>::infinity();
      }
    return std::sqrt(Utilities::MPI::max(umax, grid.communicator()));
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::update_cell_velocity()
  {
    Section section(timer, "flow: cell velocity");
    for (int d = 0; d < dim; ++d)
      std::fill(u_cell[d].begin(), u_cell[d].end(), 0.);
    for (const auto c : fluid_cells)
      {
        const std::size_t n0 = grid.first_node_of_cell(c);
        for (int d = 0; d < dim; ++d)
          {
            double s = 0;
            for (unsigned int k = 0; k < n_corners; ++k)
              s += u_new[d][n0 + corner_offset[k]];
            u_cell[d][c] = s / n_corners;
          }
      }
    for (int d = 0; d < dim; ++d)
      grid.update_ghosts(u_cell[d]);
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::fluid_forces_on_solid(
    std::array<std::vector<double>, 2 * dim * dim> &F,
    std::vector<std::uint32_t>                     &cells) const
  {
    // (Flow and solid together, doc/solid.md; a separate entry point, not
    // part of the fluid step.) From the solid side, so that a fluid
    // neighbour owned by another rank counts too: type, p_cell and u_cell
    // carry ghost values.
    for (auto &f : F)
      {
        if (f.size() != grid.n_local())
          f = grid.make_field(0.);
        else
          for (const auto c : cells)
            f[c] = 0;
      }
    cells.clear();
    if (stats.n_fluid_cells == 0) // global
      return;
    const auto  &cs   = grid.strides();
    const double h    = grid.h();
    const double area = std::pow(h, dim - 1);
    for (const auto c : grid.owned_cells())
      {
        if (type[c] != solid)
          continue;
        bool written = false;
        for (int d = 0; d < dim; ++d)
          for (unsigned int side = 0; side < 2; ++side)
            {
              const std::size_t n = side ? c + cs[d] : c - cs[d];
              if (type[n] != fluid)
                continue;
              if (!written)
                cells.push_back(c);
              written        = true;
              const double s = side ? 1. : -1.;
              const double p = p_cell[n] - 0.5 * h * s * rho * prm.gravity[d];
              const unsigned int f = dim * (2 * d + side);
              F[f + d][c]          = -s * p * area;
              for (int e = 0; e < dim; ++e)
                if (e != d)
                  F[f + e][c] = prm.viscosity * u_cell[e][n] / (0.5 * h) * area;
            }
      }
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::save_state(StateWriter &out)
  {
    std::vector<const std::vector<double> *> fields = {&type,
                                                       &type_old,
                                                       &p_cell};
    for (int d = 0; d < dim; ++d)
      fields.push_back(&u_cell[d]);
    save_cell_fields(out, grid, fields);
    // The statistics are global (the same on every rank); field by field
    // (no padding bytes in the file).
    const auto &s = stats;
    for (const unsigned int v : {s.steps,
                                 s.matrix_rebuilds,
                                 s.amg_setups,
                                 s.last_iterations,
                                 s.max_iterations,
                                 s.resorts,
                                 s.global_sorts,
                                 s.halvings,
                                 s.volume_skipped})
      out.put(v);
    for (const unsigned long v :
         {s.cg_iterations, s.n_fluid_cells, s.volume_iterations})
      out.put(v);
    out.put(s.max_point_speed);
    pressure_solver.restart(pressure_solver.statistics());
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::load_state(std::vector<StateReader> &parts)
  {
    std::vector<std::vector<double> *> fields = {&type, &type_old, &p_cell};
    for (int d = 0; d < dim; ++d)
      fields.push_back(&u_cell[d]);
    load_cell_fields(parts, grid, fields);
    classified = false; // the points were loaded anew
    auto &in   = parts[0];
    auto &s    = stats;
    for (unsigned int *v : {&s.steps,
                            &s.matrix_rebuilds,
                            &s.amg_setups,
                            &s.last_iterations,
                            &s.max_iterations,
                            &s.resorts,
                            &s.global_sorts,
                            &s.halvings,
                            &s.volume_skipped})
      *v = in.get<unsigned int>();
    for (unsigned long *v :
         {&s.cg_iterations, &s.n_fluid_cells, &s.volume_iterations})
      *v = in.get<unsigned long>();
    s.max_point_speed = in.get<double>();
    typename PressureSolver<dim>::Statistics ps;
    ps.matrix_rebuilds   = s.matrix_rebuilds;
    ps.amg_setups        = s.amg_setups;
    ps.cg_iterations     = s.cg_iterations;
    ps.last_iterations   = s.last_iterations;
    ps.max_iterations    = s.max_iterations;
    ps.n_fluid_cells     = s.n_fluid_cells;
    ps.volume_iterations = s.volume_iterations;
    ps.volume_skipped    = s.volume_skipped;
    pressure_solver.restart(ps);
  }

  template <int dim>
  bool
  IncompressibleFlow<dim>::advance_over(const double                 time,
                                        const double                 dt,
                                        const CellFields<dim>       &fields,
                                        const std::function<bool()> &may_melt,
                                        const SubcycleControl       &control)
  {
    // Sub-cycle with the current limits (they change as the flow speeds
    // up), or with the prescribed step, in equal pieces that end with the
    // temperature step. The limits and which one governed are recorded for
    // the report at the end of the run.
    const unsigned int resorts = stats.resorts;
    auto              &r       = subcycles;
    // Nothing to flow, and nothing can start to: the last flow step had no
    // fluid cell (its pressure, nodal velocities and forces on the solid
    // are zero) and no metal cell is above the solidus, so the points'
    // states left no point fluid. A flow step would change nothing; skip it
    // (in the cooling after the laser's path, once the last drop has
    // solidified).
    if (may_melt && stats.steps > 0 && stats.n_fluid_cells == 0 && !may_melt())
      {
        ++r.idle_steps;
        return false;
      }
    double       t     = 0;
    unsigned int n_sub = 0;
    while (t < dt * (1 - 1e-12))
      {
        const auto l = stable_time_step();
        r.record(l, prm.time_step > 0);
        const double wanted = prm.time_step > 0 ? prm.time_step : l.min();
        // Equal sub-steps over the rest of the temperature step, none above
        // the wanted step: no tiny last sub-step (uneven sub-steps shortened
        // the droplet period in prm/oscillating_droplet.prm).
        const double rest = dt - t;
        const double dt_f =
          rest / std::max(1., std::ceil(rest / wanted * (1 - 1e-12)));
        // Collective: the limits are global, so is the count. A sub-step
        // that cannot move the time on ends the run at once.
        if (++n_sub > control.max_substeps || !(t + dt_f > t))
          throw CollectiveError(
            InputError("Run limits/Maximum flow sub-steps",
                       std::to_string(control.max_substeps),
                       "the flow needed more sub-steps in the temperature "
                       "step of " +
                         num(dt) + " s (sub-step now " + num(dt_f) + " s, " +
                         flow_limit_name(l.governing()) +
                         (prm.time_step > 0 ? " ('Melt flow/Time step' "
                                              "prescribed)" :
                                              "") +
                         ": the flow may have blown up); raise "
                         "the bound if the flow is right")
              .what());
        step(dt_f, fields);
        t += dt_f;
        // Feedback during a long sub-cycle (the progress line comes only
        // between temperature steps).
        const double wall = control.wall_time ? control.wall_time() : 0.;
        if (wall > next_substep_report)
          {
            if (control.log)
              *control.log << "  melt flow: sub-step " << n_sub
                           << " of the temperature "
                           << "step at t = " << time << " s, " << t / dt * 100
                           << " % done, sub-steps of " << dt_f << " s (wall "
                           << wall << " s)" << std::endl;
            next_substep_report = wall + 30;
          }
      }
    if (control.wall_time)
      next_substep_report = control.wall_time() + 30;
    r.record_substeps(n_sub);
    return stats.resorts != resorts;
  }

  std::string
  flow_limit_name(const unsigned int governing)
  {
    switch (governing)
      {
        case 0:
          return "set by the convective limit (the flow speed and "
                 "'Melt flow/Courant number'; at rest 'Physics/Gravity')";
        case 1:
          return "set by the viscous limit ('Melt flow/Viscosity')";
        default:
          return "set by the capillary limit ('Melt flow/Surface tension')";
      }
  }

  template class IncompressibleFlow<2>;
  template class IncompressibleFlow<3>;
} // namespace femp
