// femp: melt-pool flow, improved incompressible MPM (paper sec. 2.3,
// eqs. 3-4 with gravity, viscosity, Darcy damping, surface tension,
// Marangoni stress and recoil pressure; METHOD sec. 3, ref. [11]).
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
//   surface temperature round the cell (median over the surface cells
//   among its 3^dim neighbours);
// - Marangoni: traction dsigma/dT (grad T - (n.grad T) n) on the fluid-gas
//   faces, weighted by |n_d|, spread to the face nodes;
// - walls: zero normal velocity on the domain boundary (free slip) and zero
//   velocity on the nodes of solid (non-fluid metal) cells (no slip);
//   Neumann pressure on both;
// - viscosity: explicit, from the Q1 stiffness of each fluid cell with the
//   lumped nodal volume (cell-wise, so it is independent of the partition);
// - G2P: v_p <- beta (v_p + sum w (u_new - u_old)) + (1 - beta) sum w u_new
//   (FLIP fraction beta, default 0.95); points move with sum w u_new;
// - optional point shifting (SPH-type, -A h |u| dt grad alpha) and volume
//   correction (positions moved by grad psi, lap psi = c (V_c/h^dim - 1),
//   psi = 0 at the free surface; Melt flow/Volume correction), both off by
//   default.
#include <deal.II/base/mpi.h>
#include <deal.II/lac/solver_cg.h>
#include <deal.II/lac/solver_control.h>
#include <deal.II/lac/trilinos_sparsity_pattern.h>

#include <femp/flow/incompressible_flow.h>
#include <femp/base/input_checks.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <type_traits>
#include <utility>
#include <sstream>

namespace femp
{
  namespace
  {
    /// A timer section when a timer is given.
    struct Section
    {
      Section(TimerOutput *t, const char *name)
      {
        if (t)
          scope.emplace(*t, name);
      }
      std::optional<TimerOutput::Scope> scope;
    };
  } // namespace

  template <int dim>
  IncompressibleFlow<dim>::Parameters::Parameters()
  {
    gravity[dim - 1] = -9.81;
  }


  template <int dim>
  void
  IncompressibleFlow<dim>::Parameters::declare_parameters(ParameterHandler &prm)
  {
    prm.enter_subsection("Melt flow");
    prm.declare_entry("Viscosity", "6e-3", Patterns::Double(0.),
                      "Dynamic viscosity mu of the melt, Pa s; range [0, inf).");
    prm.declare_entry("Gravity", "9.81", Patterns::Double(0.),
                      "Magnitude of the gravitational acceleration g, m/s^2, "
                      "acting along -y (2D) or -z (3D); range [0, inf).");
    prm.declare_entry("Darcy constant", "1e8", Patterns::Double(0.),
                      "Mushy-zone constant K_c of the Darcy damping "
                      "K_c (1-gamma)^2/(gamma^3+eps0) u, kg/(m^3 s); range [0, inf).");
    prm.declare_entry("Darcy epsilon", "1e-3", Patterns::Double(0.),
                      "eps0 of the Darcy damping, avoids division by zero; "
                      "range (0, 1].");
    prm.declare_entry("FLIP fraction", "0.95", Patterns::Double(0., 1.),
                      "beta of the grid-to-point update: 1 pure FLIP, 0 pure "
                      "PIC; range [0, 1].");
    prm.declare_entry("Courant number", "0.25", Patterns::Double(0.),
                      "C of the convective limit dt <= C h / u_max; range (0, 1].");
    prm.declare_entry("Capillary step fraction", "0.5", Patterns::Double(0.),
                      "Fraction of the capillary limit sqrt(rho h^3/(2 pi "
                      "sigma)) used by the automatic fluid step (surface "
                      "tension is explicit on the old geometry; the "
                      "oscillating-droplet study in doc/flow.md chose 0.5); "
                      "range (0, 1].");
    prm.declare_entry("Time step", "0", Patterns::Double(0.),
                      "Prescribed fluid step, s; 0 (default) chooses it "
                      "automatically at every sub-step as the smallest of the "
                      "convective, viscous and (fraction of the) capillary "
                      "limits. A prescribed step above the viscous limit "
                      "h^2 rho/(2 dim mu) or the capillary limit is refused; "
                      "above the convective limit the step-halving safety "
                      "applies. Range [0, inf).");
    prm.declare_entry("Point shifting", "0", Patterns::Double(0.),
                      "Coefficient A of the point shifting: each fluid point "
                      "is moved, besides its advection, by -A h |u| dt "
                      "grad(alpha) (alpha the metal fraction at the nodes, "
                      "tangential part only next to the free surface, at "
                      "most h/4 per step), which keeps the points evenly "
                      "spread (see doc/flow.md); dimensionless, 0 switches it "
                      "off. Range [0, 10].");
    prm.declare_entry("Curvature smoothing", "0", Patterns::Integer(0, 4),
                      "Passes of the curvature smoothing: each pass replaces "
                      "the capillary pressure of a free-surface cell by the "
                      "mean over the free-surface cells among its 3^dim "
                      "neighbours (see doc/flow.md); 0: none. Range [0, 4].");
    prm.declare_entry("Volume correction", "0", Patterns::Double(0.),
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
    prm.declare_entry("Surface tension", "0", Patterns::Double(0.),
                      "Surface tension coefficient sigma, N/m (0: no surface "
                      "tension); enters as the capillary pressure sigma div(n) "
                      "at the free surface. Range [0, inf).");
    prm.declare_entry("Surface tension temperature derivative", "0",
                      Patterns::Double(),
                      "dsigma/dT of the Marangoni stress, N/(m K) (negative "
                      "for most metals; 0: no Marangoni stress). Range any "
                      "real number.");
    prm.declare_entry("Recoil coefficient", "0", Patterns::Double(0., 1.),
                      "zeta_p of the recoil pressure zeta_p p0 exp[L_v M "
                      "(T - T_v)/(R T T_v)] (about 0.54; 0: no recoil), with "
                      "L_v, M, T_v, p0 from the Heat transfer subsection. "
                      "Range [0, 1].");
    prm.declare_entry("Solver tolerance", "1e-10", Patterns::Double(0.),
                      "Relative residual of the pressure CG solve; range (0, 1e-2].");
    prm.declare_entry("Maximum iterations", "1000", Patterns::Integer(1),
                      "Most CG iterations per pressure solve; range [1, inf).");
    prm.leave_subsection();
  }


  template <int dim>
  void
  IncompressibleFlow<dim>::Parameters::parse_parameters(ParameterHandler &prm)
  {
    prm.enter_subsection("Melt flow");
    viscosity = prm.get_double("Viscosity");
    gravity          = Tensor<1, dim>();
    gravity[dim - 1] = -prm.get_double("Gravity");
    darcy_constant   = prm.get_double("Darcy constant");
    darcy_epsilon    = prm.get_double("Darcy epsilon");
    flip_fraction    = prm.get_double("FLIP fraction");
    cfl              = prm.get_double("Courant number");
    capillary_fraction = prm.get_double("Capillary step fraction");
    time_step        = prm.get_double("Time step");
    point_shifting   = prm.get_double("Point shifting");
    curvature_smoothing = prm.get_integer("Curvature smoothing");
    volume_correction = prm.get_double("Volume correction");
    surface_tension  = prm.get_double("Surface tension");
    surface_tension_gradient =
      prm.get_double("Surface tension temperature derivative");
    recoil_coefficient = prm.get_double("Recoil coefficient");
    solver_tolerance = prm.get_double("Solver tolerance");
    max_iterations   = prm.get_integer("Maximum iterations");
    prm.leave_subsection();
    require(viscosity >= 0, "Melt flow/Viscosity", viscosity,
            "it must be non-negative (Pa s)");
    require(darcy_constant >= 0, "Melt flow/Darcy constant", darcy_constant,
            "it must be non-negative (kg/(m^3 s))");
    require(darcy_epsilon > 0 && darcy_epsilon <= 1, "Melt flow/Darcy epsilon",
            darcy_epsilon, "it must lie in (0, 1]");
    require(flip_fraction >= 0 && flip_fraction <= 1, "Melt flow/FLIP fraction",
            flip_fraction, "it must lie in [0, 1]");
    require(cfl > 0 && cfl <= 1, "Melt flow/Courant number", cfl,
            "it must lie in (0, 1]");
    require(point_shifting >= 0 && point_shifting <= 10,
            "Melt flow/Point shifting", point_shifting, "it must lie in [0, 10]");
    require(volume_correction >= 0 && volume_correction <= 1,
            "Melt flow/Volume correction", volume_correction,
            "it must lie in [0, 1]");
    require(surface_tension >= 0, "Melt flow/Surface tension", surface_tension,
            "it must be non-negative (N/m)");
    require(capillary_fraction > 0 && capillary_fraction <= 1,
            "Melt flow/Capillary step fraction", capillary_fraction,
            "it must lie in (0, 1]");
    require(time_step >= 0, "Melt flow/Time step", time_step,
            "it must be non-negative (s; 0: automatic)");
    require(solver_tolerance > 0 && solver_tolerance <= 1e-2,
            "Melt flow/Solver tolerance", solver_tolerance,
            "it must lie in (0, 1e-2]");
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
            << (l.viscous <= l.capillary ? "viscous limit h^2 rho/(2 dim mu) = " :
                                           "capillary limit sqrt(rho h^3/(2 pi "
                                           "sigma)) = ")
            << std::min(l.viscous, l.capillary) << " s (h = " << h
            << " m, rho = " << rho << " kg/m^3, mu = " << viscosity
            << " Pa s, sigma = " << surface_tension
            << " N/m); use 0 (automatic) or a step at most this limit";
    require(time_step <= std::min(l.viscous, l.capillary) * (1 + 1e-12),
            "Melt flow/Time step", time_step, allowed.str());
  }


  template <int dim>
  IncompressibleFlow<dim>::IncompressibleFlow(const Parameters &         prm,
                                              const Material &           material,
                                              const BackgroundGrid<dim> &grid,
                                              MaterialPoints<dim> &      points,
                                              TimerOutput *              timer)
    : prm(prm)
    , rho(material.density)
    , grid(grid)
    , points(points)
    , timer(timer)
  {
    const auto &ns = grid.node_strides();
    const auto &cs = grid.strides();
    for (unsigned int c = 0; c < n_corners; ++c)
      {
        corner_offset[c] = 0;
        around_offset[c] = 0;
        for (int d = 0; d < dim; ++d)
          if ((c >> d) & 1)
            {
              corner_offset[c] += ns[d];
              around_offset[c] += cs[d];
            }
      }
    // Q1 stiffness int grad N_a . grad N_b over a cell of size h
    // (2-point Gauss rule per direction, exact for Q1).
    const double h   = grid.h();
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

    type       = grid.make_field(outside);
    type_old   = grid.make_field(-1.);
    gid        = grid.make_field(-1.);
    p_cell     = grid.make_field(0.);
    p_surface  = grid.make_field(0.);
    p_capillary  = grid.make_field(0.);
    surface_mark = grid.make_field(0.);
    alpha_cell = grid.make_field(0.);
    alpha_node = grid.make_node_field();
    for (int d = 0; d < dim; ++d)
      surface_force[d] = grid.make_node_field();
    for (int f = 0; f < 2 * dim; ++f)
      theta[f] = grid.make_field(0.5);
    near1 = grid.make_field();
    near2 = grid.make_field();
    // Offsets of the 3^dim cells around a cell.
    for (unsigned int k = 0; k < std::pow(3, dim); ++k)
      {
        std::ptrdiff_t o = 0;
        unsigned int   r = k;
        for (int d = 0; d < dim; ++d, r /= 3)
          o += (int(r % 3) - 1) * cs[d];
        stencil.push_back(o);
      }
    mass       = grid.make_node_field();
    volume     = grid.make_node_field();
    if (prm.volume_correction > 0)
      {
        occupancy = grid.make_field(0.);
        psi       = grid.make_field(0.);
      }
    node_mark  = std::vector<std::uint8_t>(grid.n_local_nodes(), 0);
    node_fix   = std::vector<std::uint8_t>(grid.n_local_nodes(), 0);
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
  void
  IncompressibleFlow<dim>::set_liquid_fraction(const std::vector<double> *g)
  {
    gamma = g;
  }


  template <int dim>
  void
  IncompressibleFlow<dim>::set_temperature(const std::vector<double> *T)
  {
    temperature = T;
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
  IncompressibleFlow<dim>::classify_cells()
  {
    // One pass over the points of the occupied cells does both the cell
    // classification and the P2G scatter of mass and momentum (a deal.II
    // particles_in_cell() range per cell is the dominant cost of a pass).
    using P            = typename MaterialPoints<dim>::PropertyIndex;
    const auto &status = grid.cell_status();
    const double ih    = 1. / grid.h();
    const auto & x0    = grid.origin();
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
    const auto &handler = points.particle_handler();
    const bool  count_volume = prm.volume_correction > 0;
    const auto &occupied     = points.occupied_cells();
    for (std::size_t c = 0; c < occupied.size(); ++c)
      {
        // Cells without a fluid point (powder, substrate) are found from
        // the cached property arrays; only fluid cells need the positions.
        const auto &[idx, cell] = occupied[c];
        bool        any_fluid   = false;
        double      V_cell      = 0;
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
        const auto        ijk       = grid.global_index(idx);
        const std::size_t n0        = grid.first_node_of_cell(idx);
        double *          nm[n_corners];
        double *          nu[dim][n_corners];
        for (unsigned int k = 0; k < n_corners; ++k)
          {
            nm[k] = &mass[n0 + corner_offset[k]];
            for (int d = 0; d < dim; ++d)
              nu[d][k] = &mom[d][n0 + corner_offset[k]];
          }
        for (const auto &particle : handler.particles_in_cell(cell))
          {
            const auto v = particle.get_properties();
            if (v[P::state] != MaterialPoints<dim>::fluid)
              continue;
            const Point<dim> &x = particle.get_location();
            // Tent weights of the 2^dim corners (product over directions).
            double w[n_corners];
            tent_weights<dim>(x, x0, ih, ijk, v[P::mass], w);
            double vel[dim];
            for (int d = 0; d < dim; ++d)
              vel[d] = v[P::velocity + d];
            for (unsigned int k = 0; k < n_corners; ++k)
              {
                *nm[k] += w[k];
                for (int d = 0; d < dim; ++d)
                  *nu[d][k] += w[k] * vel[d];
              }
          }
      }
    grid.update_ghosts(type);

    // Active nodes (nodes of owned fluid cells) and their wall flags.
    for (const auto n : active)
      node_mark[n] = 0;
    active.clear();
    active_cell.clear();
    const auto & nc        = grid.n_cells();
    const double node_vol  = std::pow(0.5 * grid.h(), dim);
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
            int n_fluid = 0;
            for (unsigned int j = 0; j < n_corners; ++j)
              {
                const auto t = type[c0 - around_offset[j]];
                if (t == solid)
                  fix = (1u << dim) - 1;
                n_fluid += (t == fluid);
              }
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
  }


  template <int dim>
  void
  IncompressibleFlow<dim>::predictor(const double dt)
  {
    // Viscous force -mu K u per fluid cell, summed over ranks.
    const bool viscous = prm.viscosity > 0;
    if (viscous)
      {
        for (int d = 0; d < dim; ++d)
          std::fill(force[d].begin(), force[d].end(), 0.);
        for (const auto c : fluid_cells)
          {
            const std::size_t n0 = grid.first_node_of_cell(c);
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
                  }
              }
          }
        for (int d = 0; d < dim; ++d)
          grid.sum_shared_nodes(force[d]);
      }
    const double darcy = dt * prm.darcy_constant / rho;
    for (std::size_t a = 0; a < active.size(); ++a)
      {
        const std::size_t n = active[a];
        double            damping = 1;
        if (gamma != nullptr && prm.darcy_constant > 0)
          {
            const std::size_t c0 = active_cell[a];
            double            g = 0;
            int               k = 0;
            for (unsigned int j = 0; j < n_corners; ++j)
              if (type[c0 - around_offset[j]] == fluid)
                g += (*gamma)[c0 - around_offset[j]], ++k;
            g = k > 0 ? g / k : 1.;
            damping += darcy * (1 - g) * (1 - g) / (g * g * g + prm.darcy_epsilon);
          }
        for (int d = 0; d < dim; ++d)
          {
            double acc = prm.gravity[d];
            if (viscous && volume[n] > 0)
              acc += force[d][n] / (rho * volume[n]);
            if (prm.surface_tension_gradient != 0 && volume[n] > 0)
              acc += surface_force[d][n] / (rho * volume[n]);
            u_new[d][n] = (u_old[d][n] + dt * acc) / damping;
          }
      }
    apply_boundary_conditions(u_new);
  }


  template <int dim>
  void
  IncompressibleFlow<dim>::surface_terms()
  {
    const bool thermal =
      prm.surface_tension_gradient != 0 || prm.recoil_coefficient > 0;
    AssertThrow(!thermal || temperature != nullptr,
                ExcMessage("Melt flow: Marangoni stress and recoil pressure "
                           "need the temperature (set_temperature())."));
    using P          = typename MaterialPoints<dim>::PropertyIndex;
    const double h   = grid.h();
    const double ih  = 1. / h;
    const double ihd = std::pow(ih, dim);
    const auto & x0  = grid.origin();
    const auto & cs  = grid.strides();
    // Only cells near the fluid need alpha: near1 = within one cell of a
    // fluid cell (alpha_cell is used there), near2 = within two (their
    // points contribute to the nodes of near1 cells). Marked from the fluid
    // cells of the local box; near1 of ghosts comes from their owners.
    const auto &status = grid.cell_status();
    std::fill(near1.begin(), near1.end(), 0.);
    std::fill(near2.begin(), near2.end(), 0.);
    for (std::size_t c = 0; c < type.size(); ++c)
      if (type[c] == fluid)
        for (const auto o : stencil)
          {
            const std::ptrdiff_t e = std::ptrdiff_t(c) + o;
            if (e >= 0 && std::size_t(e) < near1.size())
              near1[e] = 1;
          }
    grid.update_ghosts(near1);
    for (std::size_t c = 0; c < near1.size(); ++c)
      if (near1[c] != 0 && status[c] != BackgroundGrid<dim>::outside)
        for (const auto o : stencil)
          {
            const std::ptrdiff_t e = std::ptrdiff_t(c) + o;
            if (e >= 0 && std::size_t(e) < near2.size())
              near2[e] = 1;
          }
    // alpha at nodes: volume of the metal points near the fluid, tent
    // weights.
    std::fill(alpha_node.begin(), alpha_node.end(), 0.);
    const auto &handler = points.particle_handler();
    for (const auto &[idx, cell] : points.occupied_cells())
      {
        if (near2[idx] == 0)
          continue;
        const auto        ijk = grid.global_index(idx);
        const std::size_t n0  = grid.first_node_of_cell(idx);
        for (const auto &particle : handler.particles_in_cell(cell))
          {
            const Point<dim> x = particle.get_location();
            double           xi[dim];
            for (int d = 0; d < dim; ++d)
              xi[d] = (x[d] - x0[d]) * ih - ijk[d];
            const double V = particle.get_properties()[P::volume] * ihd;
            for (unsigned int k = 0; k < n_corners; ++k)
              {
                double w = V;
                for (int d = 0; d < dim; ++d)
                  w *= ((k >> d) & 1) ? xi[d] : 1. - xi[d];
                alpha_node[n0 + corner_offset[k]] += w;
              }
          }
      }
    grid.sum_shared_nodes(alpha_node);
    // Smoothed alpha at the owned near1 cell centres: mean of the cell's
    // nodes, node values mirrored at the domain boundary (walls are not
    // free surfaces).
    std::fill(alpha_cell.begin(), alpha_cell.end(), 0.);
    for (const auto c : grid.owned_cells())
      {
        if (near1[c] == 0)
          continue;
        double a = 0;
        for (const double ak : corner_alpha(c))
          a += ak;
        alpha_cell[c] = a / n_corners;
      }
    grid.update_ghosts(alpha_cell);

    // Free-surface position on each fluid-gas face: where the smoothed
    // alpha, linear between the two cell centres, is 1/2; theta is its
    // distance from the fluid cell centre in units of h, in
    // [theta_min, 1] (1/2 for a fluid cell filled to its face).
    for (int f = 0; f < 2 * dim; ++f)
      std::fill(theta[f].begin(), theta[f].end(), 0.5);
    for (const auto c : fluid_cells)
      for (int d = 0; d < dim; ++d)
        for (const int side : {0, 1})
          {
            const std::size_t g = side ? c + cs[d] : c - cs[d];
            if (type[g] != gas)
              continue;
            const double ac = alpha_cell[c], ag = alpha_cell[g];
            const double th = ac > ag ? (ac - 0.5) / (ac - ag) : theta_min;
            theta[2 * d + side][c] = std::min(std::max(th, theta_min), 1.);
          }
    for (int f = 0; f < 2 * dim; ++f)
      grid.update_ghosts(theta[f]);
    if (!has_surface_terms())
      return;

    // Surface cells (owned fluid cells with a gas face): p_s = sigma div(n)
    // + p_recoil(T), and the Marangoni traction on their gas faces.
    std::fill(p_surface.begin(), p_surface.end(), 0.);
    std::fill(p_capillary.begin(), p_capillary.end(), 0.);
    std::fill(surface_mark.begin(), surface_mark.end(), 0.);
    if (prm.surface_tension_gradient != 0)
      for (int d = 0; d < dim; ++d)
        std::fill(surface_force[d].begin(), surface_force[d].end(), 0.);
    for (const auto c : fluid_cells)
      {
        bool surface = false;
        for (int d = 0; d < dim; ++d)
          surface = surface || type[c + cs[d]] == gas || type[c - cs[d]] == gas;
        if (!surface)
          continue;
        double div = 0;
        double nc[dim] = {};
        for (unsigned int k = 0; k < n_corners; ++k)
          {
            // Node k of cell c; the cell above it is c0.
            const std::size_t c0 = c + around_offset[k];
            double            g[dim], norm = 0;
            for (int d = 0; d < dim; ++d)
              {
                g[d] = 0;
                for (unsigned int j = 0; j < n_corners; ++j)
                  if (!((j >> d) & 1))
                    {
                      const std::size_t up = c0 - around_offset[j];
                      const std::size_t lo = up - cs[d];
                      // Outside the domain alpha has zero gradient.
                      if (status[up] != BackgroundGrid<dim>::outside &&
                          status[lo] != BackgroundGrid<dim>::outside)
                        g[d] += alpha_cell[up] - alpha_cell[lo];
                    }
                norm += g[d] * g[d];
              }
            norm = std::sqrt(norm);
            if (norm > 1e-8)
              for (int d = 0; d < dim; ++d)
                {
                  div -= (((k >> d) & 1) ? 1. : -1.) * g[d] / norm;
                  nc[d] -= g[d] / norm;
                }
          }
        double ps = prm.surface_tension * div / (h * (1u << (dim - 1)));
        p_capillary[c]  = ps;
        surface_mark[c] = 1;
        p_surface[c]    = ps; // the recoil is added by add_recoil_pressure()
        if (prm.surface_tension_gradient == 0)
          continue;
        const double T = (*temperature)[c];
        // Unit normal of the cell; grad T from metal neighbours.
        double nn = 0;
        for (int d = 0; d < dim; ++d)
          nn += nc[d] * nc[d];
        nn = std::sqrt(nn);
        if (nn < 1e-12)
          continue;
        double gT[dim], ndotg = 0;
        for (int d = 0; d < dim; ++d)
          {
            nc[d] /= nn;
            const bool   m = type[c - cs[d]] == fluid || type[c - cs[d]] == solid;
            const bool   p = type[c + cs[d]] == fluid || type[c + cs[d]] == solid;
            const double Tm = m ? (*temperature)[c - cs[d]] : T;
            const double Tp = p ? (*temperature)[c + cs[d]] : T;
            gT[d] = (m && p) ? (Tp - Tm) / (2 * h) : (Tp - Tm) / h;
            ndotg += nc[d] * gT[d];
          }
        const double face = std::pow(h, dim - 1) / (1u << (dim - 1));
        for (int d = 0; d < dim; ++d)
          for (const int side : {0, 1})
            {
              const std::ptrdiff_t o = side ? cs[d] : -cs[d];
              if (type[c + o] != gas)
                continue;
              const double w = prm.surface_tension_gradient * face * std::abs(nc[d]);
              const std::size_t n0 = grid.first_node_of_cell(c);
              for (unsigned int k = 0; k < n_corners; ++k)
                if ((int((k >> d) & 1)) == side)
                  for (int e = 0; e < dim; ++e)
                    surface_force[e][n0 + corner_offset[k]] +=
                      w * (gT[e] - ndotg * nc[e]);
            }
      }
    if (prm.surface_tension_gradient != 0)
      for (int d = 0; d < dim; ++d)
        grid.sum_shared_nodes(surface_force[d]);
    if (prm.recoil_coefficient > 0 ||
        (prm.curvature_smoothing > 0 && prm.surface_tension > 0))
      grid.update_ghosts(surface_mark);
    add_recoil_pressure();
    smooth_capillary_pressure();
    grid.update_ghosts(p_surface);
  }


  // Recoil pressure zeta_p p0 exp[L_v M (T_s - T_v)/(R T_s T_v)] of each
  // surface cell (doc/flow.md, "3D track with recoil"). T_s is the median
  // of the cell temperatures over the surface cells among its 3^dim
  // neighbours (itself included; the mean of the two middle values for an
  // even count). The cell temperature of single surface cells has outliers:
  // on the 3D track, surface cells at the top of melting powder grains
  // reached 8,000-17,000 K next to cells at 4,500-6,000 K (fragments of
  // 2-30 cells), and the exponential turned that into recoil jumps of
  // 1e9-3e10 Pa between neighbouring cells, which blew the fragment apart
  // at 300-5,000 m/s (the spikes of the convective limit). The median drops
  // such a single-cell outlier, gives a fragment of a few cells one recoil
  // pressure on its whole surface (no net force or internal drive, as for a
  // uniformly hot droplet), and keeps the cell's own temperature where T is
  // linear along a flat surface (in 2D wherever T is monotone along it); at
  // a smooth temperature peak it takes about the value one cell away. Cost
  // on the track: the recoil of surface cells above 4000 K is typically
  // 0.3 (0.03-0.65) of the cell-wise value (the surface T varies by several
  // hundred K per cell near the beam).
  template <int dim>
  void
  IncompressibleFlow<dim>::add_recoil_pressure()
  {
    if (prm.recoil_coefficient == 0)
      return;
    const double R_gas = 8.314462618;
    const double Tv    = prm.evaporation_temperature;
    const double a     = prm.latent_heat_evaporation * prm.molar_mass /
                     (R_gas * Tv);
    std::array<double, 27> Ts;
    for (const auto c : fluid_cells)
      {
        if (surface_mark[c] == 0)
          continue;
        unsigned int n = 0;
        for (const auto o : stencil)
          if (surface_mark[c + o] != 0)
            Ts[n++] = (*temperature)[c + o];
        std::sort(Ts.begin(), Ts.begin() + n);
        const double T = (n % 2) ? Ts[n / 2] : 0.5 * (Ts[n / 2 - 1] + Ts[n / 2]);
        if (T > 0)
          p_surface[c] += prm.recoil_coefficient * prm.ambient_pressure *
                          std::exp(a * (T - Tv) / T);
      }
  }


  // Curvature smoothing: the curvature div(n) of the smoothed alpha at a
  // staircase surface is noisy from cell to cell (at a round drop of
  // R = 20 h the capillary pressure of single surface cells ranged from 0.13
  // to 2.5 sigma/R). Each pass replaces the capillary part of p_s of every
  // surface cell by the mean over the surface cells among its 3^dim
  // neighbours (itself included), i.e. the curvature is averaged along the
  // interface over about three cells per pass, the usual remedy of
  // convolved-CSF schemes (smoothed curvature; cf. the height-function and
  // smoothing comparisons of Cummins, Francois and Kothe 2005). The recoil
  // part is not smoothed.
  template <int dim>
  void
  IncompressibleFlow<dim>::smooth_capillary_pressure()
  {
    if (prm.curvature_smoothing == 0 || prm.surface_tension == 0)
      return;
    std::vector<double> smoothed(fluid_cells.size());
    for (unsigned int pass = 0; pass < prm.curvature_smoothing; ++pass)
      {
        grid.update_ghosts(p_capillary);
        for (std::size_t i = 0; i < fluid_cells.size(); ++i)
          {
            const std::size_t c = fluid_cells[i];
            if (surface_mark[c] == 0)
              continue;
            double sum = 0, n = 0;
            for (const auto o : stencil)
              if (surface_mark[c + o] != 0)
                sum += p_capillary[c + o], n += 1;
            smoothed[i] = sum / n;
          }
        for (std::size_t i = 0; i < fluid_cells.size(); ++i)
          {
            const std::size_t c = fluid_cells[i];
            if (surface_mark[c] == 0)
              continue;
            p_surface[c] += smoothed[i] - p_capillary[c];
            p_capillary[c] = smoothed[i];
          }
      }
  }


  template <int dim>
  void
  IncompressibleFlow<dim>::pressure_solve(const double dt)
  {
    const MPI_Comm comm = grid.communicator();
    const double   h    = grid.h();
    const auto &   cs   = grid.strides();

    // Divergence of u* at the owned fluid cells.
    const double scale = 1. / (h * (1u << (dim - 1)));
    divergence.resize(fluid_cells.size());
    for (std::size_t i = 0; i < fluid_cells.size(); ++i)
      {
        const std::size_t n0  = grid.first_node_of_cell(fluid_cells[i]);
        double            div = 0;
        for (unsigned int k = 0; k < n_corners; ++k)
          for (int d = 0; d < dim; ++d)
            div += (((k >> d) & 1) ? 1. : -1.) * u_new[d][n0 + corner_offset[k]];
        divergence[i] = div * scale;
      }

    // The matrix rows are the owned cells of a band: the cells within one
    // of a fluid cell (near1, from surface_terms(); a band of two cells cost
    // more in solves than it saved in setups in the 3D track). Rows of band cells that
    // are not fluid are identity rows (decoupled, p = 0), so the numbering,
    // the graph and the AMG hierarchy survive changes of the fluid set that
    // stay inside the band:
    //  - fluid set and neighbour types unchanged: only the diagonal (theta);
    //  - changed inside the band: all values of the band rows are reset, the
    //    old hierarchy keeps preconditioning the new matrix while CG
    //    converges in at most n + 40 iterations, n those of the first
    //    solve after its setup; else ML is set up again and the solve
    //    repeated;
    //  - a fluid cell outside the band: new band, graph and hierarchy.
    bool set_changed = !have_matrix;
    if (!set_changed)
      for (const auto c : fluid_cells)
        {
          if (type_old[c] != fluid)
            {
              set_changed = true;
              break;
            }
          for (int d = 0; d < dim && !set_changed; ++d)
            set_changed = type_old[c + cs[d]] != type[c + cs[d]] ||
                          type_old[c - cs[d]] != type[c - cs[d]];
          if (set_changed)
            break;
        }
    // Cells that stopped being fluid also change the system.
    if (!set_changed)
      set_changed = fluid_cells.size() != n_fluid_rows;
    set_changed = Utilities::MPI::logical_or(set_changed, comm);
    n_fluid_rows = fluid_cells.size();
    bool renumber = !have_matrix;
    if (set_changed && !renumber)
      for (const auto c : fluid_cells)
        if (gid[c] < 0)
          {
            renumber = true;
            break;
          }
    renumber = Utilities::MPI::logical_or(renumber, comm);
    const auto &status = grid.cell_status();

    if (renumber)
      {
        Section s(timer, "flow: pressure matrix setup");
        band.clear();
        for (const auto c : grid.owned_cells())
          if (near1[c] != 0 && status[c] != BackgroundGrid<dim>::outside)
            band.push_back(c);
        const types::global_dof_index n_local = band.size();
        // (types::global_dof_index is 32 bits in this deal.II build: the
        // exscan goes through a 64-bit integer.)
        std::uint64_t n_local64 = n_local, offset64 = 0;
        MPI_Exscan(&n_local64, &offset64, 1, MPI_UINT64_T, MPI_SUM, comm);
        if (Utilities::MPI::this_mpi_process(comm) == 0)
          offset64 = 0;
        const types::global_dof_index offset = offset64;
        const types::global_dof_index n_total =
          Utilities::MPI::sum(n_local, comm);
        std::fill(gid.begin(), gid.end(), -1.);
        for (std::size_t i = 0; i < band.size(); ++i)
          gid[band[i]] = offset + i;
        grid.update_ghosts(gid);
        owned_rows = IndexSet(n_total);
        owned_rows.add_range(offset, offset + n_local);
        owned_rows.compress();

        // (An empty row range must ask for 0 entries per row: Epetra's
        // size check uses the min/max row of the range.)
        TrilinosWrappers::SparsityPattern sp(owned_rows, comm,
                                             n_local > 0 ? 2 * dim + 1 : 0);
        for (std::size_t i = 0; i < band.size(); ++i)
          {
            const std::size_t c   = band[i];
            const auto        row = offset + i;
            sp.add(row, row);
            for (int d = 0; d < dim; ++d)
              for (const std::ptrdiff_t o : {-cs[d], cs[d]})
                if (gid[c + o] >= 0)
                  sp.add(row, types::global_dof_index(gid[c + o]));
          }
        sp.compress();
        matrix.reinit(sp);
        rhs.reinit(owned_rows, comm);
        solution.reinit(owned_rows, comm);
        if (prm.volume_correction > 0)
          psi_solution.reinit(owned_rows, comm);
        ++stats.matrix_rebuilds;
      }
    const auto row_offset =
      owned_rows.n_elements() > 0 ? *owned_rows.begin() : 0;
    if (set_changed)
      {
        // All values of the band rows: -1 between fluid cells, 0 for the
        // other stored neighbours, identity rows outside the fluid.
        Section s(timer, "flow: pressure matrix values");
        for (std::size_t i = 0; i < band.size(); ++i)
          {
            const std::size_t       c   = band[i];
            const auto              row = row_offset + i;
            const bool              f   = type[c] == fluid;
            types::global_dof_index cols[2 * dim + 1];
            double                  vals[2 * dim + 1];
            unsigned int            n = 0;
            double                  diag = f ? 0. : 1.;
            for (int d = 0; d < dim; ++d)
              for (const int side : {0, 1})
                {
                  const std::size_t e = side ? c + cs[d] : c - cs[d];
                  const bool        ef = type[e] == fluid;
                  if (f && ef)
                    diag += 1;
                  else if (f && type[e] == gas)
                    diag += 1. / theta[2 * d + side][c];
                  if (gid[e] >= 0)
                    {
                      cols[n] = types::global_dof_index(gid[e]);
                      vals[n] = (f && ef) ? -1. : 0.;
                      ++n;
                    }
                }
            cols[n] = row;
            vals[n] = diag;
            ++n;
            matrix.set(row, n, cols, vals);
          }
        matrix.compress(VectorOperation::insert);
      }
    else
      {
        // Diagonal only: the free-surface faces contribute 1/theta
        // (Dirichlet value at the interface, ghost-fluid method).
        for (const auto c : fluid_cells)
          {
            double diag = 0;
            for (int d = 0; d < dim; ++d)
              for (const int side : {0, 1})
                {
                  const auto t = type[side ? c + cs[d] : c - cs[d]];
                  if (t == fluid)
                    diag += 1;
                  else if (t == gas)
                    diag += 1. / theta[2 * d + side][c];
                }
            const auto row = types::global_dof_index(gid[c]);
            matrix.set(row, row, diag);
          }
        matrix.compress(VectorOperation::insert);
      }
    stats.n_fluid_cells = Utilities::MPI::sum(
      static_cast<unsigned long>(fluid_cells.size()), comm);
    // ML keeps a reference to the matrix it was set up with: it gets its
    // own copy, so that a kept hierarchy stays one fixed SPD operator while
    // the values of the system matrix change (with the system matrix
    // itself, the fine-level Chebyshev smoother would run with stale
    // eigenvalue bounds and could stop being a preconditioner).
    const auto setup_amg = [&]() {
      Section s(timer, "flow: AMG setup");
      if (owned_rows.size() > 0)
        {
          TrilinosWrappers::PreconditionAMG::AdditionalData data;
          data.elliptic              = true;
          data.higher_order_elements = false;
          data.smoother_sweeps       = 2;
          data.aggregation_threshold = 0.02;
          amg_matrix.copy_from(matrix);
          amg.initialize(amg_matrix, data);
        }
      have_matrix = true;
      ++stats.amg_setups;
    };
    // A new hierarchy whenever the set of fluid cells changed. Keeping one
    // across set changes inside the band (tried until 2026-11-24) cost more
    // than it saved: in the 0.2 ms 3D track the stale hierarchy needed 50
    // CG iterations per solve on average and failed its limit in 1509 of
    // 1917 steps (then set up anyway), against 7 with a fresh one; the
    // track took 19.5 s against about 14 s. With the same set only the
    // free-surface diagonal 1/theta changed, and the kept hierarchy is
    // tried first (below).
    const bool new_hierarchy = renumber || set_changed;
    if (new_hierarchy)
      setup_amg();
    if (stats.n_fluid_cells == 0)
      return;

    std::optional<Section> solve_section;
    solve_section.emplace(timer, "flow: pressure solve");
    const double f      = -rho * h * h / dt;
    const bool capillary = prm.surface_tension > 0 || prm.recoil_coefficient > 0;
    rhs = 0; // identity rows of the band: p = 0
    for (std::size_t i = 0; i < fluid_cells.size(); ++i)
      {
        double b = f * divergence[i];
        if (capillary)
          {
            const std::size_t c = fluid_cells[i];
            for (int d = 0; d < dim; ++d)
              for (const int side : {0, 1})
                if (type[side ? c + cs[d] : c - cs[d]] == gas)
                  b += p_surface[c] / theta[2 * d + side][c];
          }
        rhs(types::global_dof_index(gid[fluid_cells[i]])) = b;
      }
    rhs.compress(VectorOperation::insert);
    // Warm start from the previous pressure (same numbering).
    if (renumber)
      solution = 0;
    const double norm = rhs.l2_norm();
    if (norm == 0)
      solution = 0;
    else
      {
        // With a hierarchy built for other matrix values CG may use at
        // most n + 40 iterations (n: those of the first solve after the
        // setup; 40 iterations cost about one ML setup in the 3D track,
        // fewer than one in 2D); beyond, ML is set up again on the current
        // matrix and the solve restarts from the same initial guess.
        bool                          fresh = new_hierarchy;
        unsigned int                  total = 0;
        TrilinosWrappers::MPI::Vector guess;
        if (!fresh)
          guess = solution;
        for (;;)
          {
            const unsigned int limit =
              fresh ? prm.max_iterations :
                      std::min(prm.max_iterations,
                               iterations_after_setup + 40);
            SolverControl control(limit, prm.solver_tolerance * norm);
            SolverCG<TrilinosWrappers::MPI::Vector> cg(control);
            try
              {
                cg.solve(matrix, solution, rhs, amg);
                total += control.last_step();
                if (fresh)
                  iterations_after_setup = std::max(1u, control.last_step());
                break;
              }
            catch (const SolverControl::NoConvergence &e)
              {
                total += e.last_step;
                if (fresh)
                  {
                    std::ostringstream msg;
                    msg << "Melt flow: the pressure CG solve did not converge in "
                        << e.last_step << " iterations (residual "
                        << e.last_residual << ", target "
                        << control.tolerance() << ", " << stats.n_fluid_cells
                        << " fluid cells).";
                    throw std::runtime_error(msg.str());
                  }
                solve_section.reset();
                setup_amg();
                solve_section.emplace(timer, "flow: pressure solve");
                solution = guess;
                fresh    = true;
              }
          }
        stats.last_iterations = total;
        stats.cg_iterations += total;
        stats.max_iterations = std::max(stats.max_iterations, total);
      }
    std::fill(p_cell.begin(), p_cell.end(), 0.);
    for (std::size_t i = 0; i < fluid_cells.size(); ++i)
      p_cell[fluid_cells[i]] = solution(types::global_dof_index(gid[fluid_cells[i]]));
    grid.update_ghosts(p_cell);
  }


  template <int dim>
  void
  IncompressibleFlow<dim>::correction(const double dt)
  {
    const double h  = grid.h();
    const auto & cs = grid.strides();
    const double f  = dt / (rho * h);
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
                  sum -= (p_cell[lo] - p_surface[lo]) / theta[2 * d + 1][lo], ++k;
              }
            if (k > 0)
              u_new[d][n] -= f * sum / k;
          }
      }
    apply_boundary_conditions(u_new);

    for (const auto n : active)
      for (int d = 0; d < dim; ++d)
        if (!std::isfinite(u_new[d][n]))
          {
            std::size_t          rest = n;
            std::array<int, dim> ijk;
            for (int e = dim - 1; e >= 0; --e)
              {
                ijk[e] = grid.box_lower()[e] + int(rest / grid.node_strides()[e]);
                rest %= grid.node_strides()[e];
              }
            std::ostringstream msg;
            msg << "Melt flow became unstable: non-finite velocity at the grid "
                << "node at x =";
            for (int e = 0; e < dim; ++e)
              msg << ' ' << grid.origin()[e] + ijk[e] * grid.h();
            msg << " m (time step " << dt << " s). Reduce the time step.";
            throw std::runtime_error(msg.str());
          }
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
    std::fill(psi.begin(), psi.end(), 0.);
    if (stats.n_fluid_cells == 0)
      return;
    const double ihd = std::pow(1. / grid.h(), dim);
    rhs              = 0;
    for (const auto c : fluid_cells)
      {
        double e = occupancy[c] * ihd - 1;
        if (e < 0)
          for (const auto o : stencil)
            if (type[c + o] == gas)
              {
                e = 0;
                break;
              }
        rhs(types::global_dof_index(gid[c])) = -prm.volume_correction * e;
      }
    rhs.compress(VectorOperation::insert);
    const double norm = rhs.l2_norm();
    if (norm > 0)
      {
        SolverControl control(prm.max_iterations, prm.solver_tolerance * norm);
        SolverCG<TrilinosWrappers::MPI::Vector> cg(control);
        psi_solution = 0;
        try
          {
            cg.solve(matrix, psi_solution, rhs, amg);
            stats.volume_iterations += control.last_step();
          }
        catch (const SolverControl::NoConvergence &e)
          {
            stats.volume_iterations += e.last_step;
            ++stats.volume_skipped;
            return; // psi = 0: no correction in this step
          }
        for (const auto c : fluid_cells)
          psi[c] = psi_solution(types::global_dof_index(gid[c]));
      }
    grid.update_ghosts(psi);
  }


  template <int dim>
  void
  IncompressibleFlow<dim>::volume_faces(const std::size_t c, double *G) const
  {
    const double h  = grid.h();
    const auto & cs = grid.strides();
    for (int d = 0; d < dim; ++d)
      for (const int side : {0, 1})
        {
          const std::size_t e = side ? c + cs[d] : c - cs[d];
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
    using P           = typename MaterialPoints<dim>::PropertyIndex;
    const double h    = grid.h();
    const double ih   = 1. / h;
    const auto & x0   = grid.origin();
    const auto & nc   = grid.n_cells();
    const double beta = prm.flip_fraction;
    auto &       handler = points.particle_handler();
    // Cells where a point left (increasing): only their points are checked
    // by the re-sort, not every point of the powder and the substrate.
    std::vector<std::uint32_t> left_cells;
    // The point loop is compiled four times (with and without the point
    // shifting and the volume correction), so that either costs nothing
    // when it is off.
    const auto loop = [&](auto mode_tag) {
    constexpr int  mode     = decltype(mode_tag)::value;
    constexpr bool shifting = mode & 1;
    constexpr bool volume_c = mode & 2;
    bool         moved   = false;
    double       umax    = 0;
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
            for (unsigned int k = 0; k < n_corners; ++k)
              {
                double w = 1;
                for (int d = 0; d < dim; ++d)
                  w *= ((k >> d) & 1) ? xi[d] : 1. - xi[d];
                const std::size_t n = n0 + corner_offset[k];
                for (int d = 0; d < dim; ++d)
                  {
                    vg[d] += w * u_new[d][n];
                    dv[d] += w * (u_new[d][n] - u_old[d][n]);
                  }
              }
            double   speed2 = 0, step2 = 0;
            bool     left   = false;
            Point<dim> ref;
            double   shift[dim] = {};
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
                v[P::velocity + d] =
                  beta * (v[P::velocity + d] + dv[d]) + (1 - beta) * vg[d];
                speed2 += v[P::velocity + d] * v[P::velocity + d];
                const double dx = dt * vg[d];
                step2 += dx * dx;
                // Stay inside the domain (walls are free slip).
                const double lo = x0[d] + 1e-9 * h;
                const double hi = x0[d] + nc[d] * h - 1e-9 * h;
                x[d] = std::min(std::max(x[d] + ((shifting || volume_c) ? dx + shift[d] : dx), lo), hi);
                ref[d]          = (x[d] - x0[d]) * ih - ijk[d];
                left            = left || ref[d] < 0 || ref[d] >= 1;
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
    const int  mode = (prm.point_shifting > 0 ? 1 : 0) +
                     (prm.volume_correction > 0 ? 2 : 0);
    const auto [moved, umax] =
      mode == 0 ? loop(std::integral_constant<int, 0>()) :
      mode == 1 ? loop(std::integral_constant<int, 1>()) :
      mode == 2 ? loop(std::integral_constant<int, 2>()) :
                  loop(std::integral_constant<int, 3>());
    stats.max_point_speed =
      std::sqrt(Utilities::MPI::max(umax, grid.communicator()));
    if (Utilities::MPI::logical_or(moved, grid.communicator()))
      {
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
  // metal fraction alpha (nodal values from surface_terms()), so that they
  // stay evenly spread (4 per cell in 2D) instead of bunching or leaving
  // voids in the liquid. The displacement -A h |u| dt grad(alpha) is the
  // diffusion-type shifting of SPH (Lind et al. 2012 with the
  // velocity-scaled coefficient of Skillen et al. 2013), here with the
  // gradient of the grid's bilinear alpha; next to the free surface (a gas
  // cell among the 3^dim cells round the point's cell) only its component
  // tangential to the surface is kept, so the liquid does not spread
  // outward. It changes positions only, not the point velocities.
  template <int dim>
  std::array<double, (1u << dim)>
  IncompressibleFlow<dim>::corner_alpha(const std::size_t c) const
  {
    const auto &                    nc  = grid.n_cells();
    const auto                      ijk = grid.global_index(c);
    const std::size_t               n0  = grid.first_node_of_cell(c);
    std::array<double, (1u << dim)> a;
    for (unsigned int k = 0; k < n_corners; ++k)
      {
        double f = 1;
        for (int d = 0; d < dim; ++d)
          {
            const int i = ijk[d] + ((k >> d) & 1);
            if (i == 0 || i == int(nc[d]))
              f *= 2;
          }
        a[k] = f * alpha_node[n0 + corner_offset[k]];
      }
    return a;
  }


  template <int dim>
  typename IncompressibleFlow<dim>::ShiftCell
  IncompressibleFlow<dim>::shift_cell(const std::size_t c) const
  {
    ShiftCell         sc;
    const auto &cs = grid.strides();
    sc.alpha       = corner_alpha(c);
    for (const auto o : stencil)
      sc.near_surface = sc.near_surface || type[c + o] == gas;
    if (sc.near_surface)
      {
        // Outward normal -grad(alpha~) at the cell centre (central
        // differences; zero gradient across the domain boundary).
        const auto &status = grid.cell_status();
        double      norm   = 0;
        for (int d = 0; d < dim; ++d)
          {
            const std::size_t lo = c - cs[d], up = c + cs[d];
            const bool        l = status[lo] != BackgroundGrid<dim>::outside;
            const bool        u = status[up] != BackgroundGrid<dim>::outside;
            sc.normal[d] = -((u ? alpha_cell[up] : alpha_cell[c]) -
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
                                          const double *   xi,
                                          const double     speed,
                                          const double     dt,
                                          double *         dx) const
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
    const double a = -prm.point_shifting * speed * dt; // times grad(alpha) h
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
  IncompressibleFlow<dim>::step(const double dt)
  {
    const StepLimits limits = stable_time_step();
    if (!(dt > 0) || dt > limits.viscous * (1 + 1e-12) ||
        dt > limits.capillary * (1 + 1e-12))
      {
        std::ostringstream msg;
        msg << "Melt flow: the time step " << dt
            << " s is not positive or exceeds the viscous limit "
            << limits.viscous << " s (h^2 rho/(2 dim mu)) or the capillary "
            << "limit " << limits.capillary << " s (sqrt(rho h^3/(2 pi sigma))).";
        throw std::runtime_error(msg.str());
      }
    advance(dt, 0);
  }


  template <int dim>
  void
  IncompressibleFlow<dim>::advance(const double dt, const unsigned int depth)
  {
    {
      Section s(timer, "flow: transfer to grid");
      classify_cells();
      transfer_to_grid();
    }
    {
      Section s(timer, "flow: free surface");
      surface_terms();
    }
    {
      Section s(timer, "flow: predictor");
      predictor(dt);
    }
    pressure_solve(dt);
    {
      Section s(timer, "flow: correction");
      correction(dt);
    }
    // Step rejection: if the new nodal velocity would carry a point more
    // than a cell (e.g. a sudden recoil or capillary pressure that the
    // limits of the last step did not foresee), redo the step as two halves.
    {
      double umax = 0;
      for (const auto n : active)
        {
          double s2 = 0;
          for (int d = 0; d < dim; ++d)
            s2 += u_new[d][n] * u_new[d][n];
          umax = std::max(umax, s2);
        }
      umax = std::sqrt(Utilities::MPI::max(umax, grid.communicator()));
      if (umax * dt > grid.h())
        {
          if (depth >= 20)
            {
              std::ostringstream msg;
              msg << "Melt flow became unstable: nodal speed " << umax
                  << " m/s moves points more than a cell even after halving "
                  << "the step 20 times (step " << dt << " s).";
              throw std::runtime_error(msg.str());
            }
          ++stats.halvings;
          advance(dt / 2, depth + 1);
          advance(dt / 2, depth + 1);
          return;
        }
    }
    {
      Section s(timer, "flow: cell velocity");
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
    if (prm.volume_correction > 0)
      {
        Section s(timer, "flow: volume correction");
        volume_solve();
      }
    {
      Section s(timer, "flow: grid to points + advection");
      grid_to_points(dt);
    }
    ++stats.steps;
  }

  template <int dim>
  void
  IncompressibleFlow<dim>::fluid_forces_on_solid(
    std::array<std::vector<double>, 2 * dim * dim> &F) const
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
          std::fill(f.begin(), f.end(), 0.);
      }
    if (stats.n_fluid_cells == 0) // global
      return;
    const auto & cs   = grid.strides();
    const double h    = grid.h();
    const double area = std::pow(h, dim - 1);
    for (const auto c : grid.owned_cells())
      {
        if (type[c] != solid)
          continue;
        for (int d = 0; d < dim; ++d)
          for (unsigned int side = 0; side < 2; ++side)
            {
              const std::size_t n = side ? c + cs[d] : c - cs[d];
              if (type[n] != fluid)
                continue;
              const double s = side ? 1. : -1.;
              const double p = p_cell[n] - 0.5 * h * s * rho * prm.gravity[d];
              const unsigned int f = dim * (2 * d + side);
              F[f + d][c] = -s * p * area;
              for (int e = 0; e < dim; ++e)
                if (e != d)
                  F[f + e][c] = prm.viscosity * u_cell[e][n] / (0.5 * h) * area;
            }
      }
  }

  template class IncompressibleFlow<2>;
  template class IncompressibleFlow<3>;
} // namespace femp
