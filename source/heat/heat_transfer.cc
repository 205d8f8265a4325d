// femp: HeatTransfer<dim>, the temperature equation (1) on the background
// grid: diffusion, upwind convection, latent heat, surface losses and the
// laser source. See include/femp/heat/heat_transfer.h for the discretization.
#include <deal.II/base/mpi.h>
#include <deal.II/base/utilities.h>

#include <femp/base/collective_error.h>
#include <femp/base/error_location.h>
#include <femp/base/input_checks.h>
#include <femp/base/parameter_table.h>
#include <femp/base/progress_watchdog.h>
#include <femp/grid/cell_state.h>
#include <femp/heat/heat_transfer.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <sstream>
#include <type_traits>

namespace femp
{
  namespace
  {
    constexpr double stefan_boltzmann = 5.670374419e-8; // W/(m^2 K^4)
    constexpr double gas_constant     = 8.314462618;    // J/(mol K)
  }                                                     // namespace

  template <int dim>
  void
  HeatTransfer<dim>::Parameters::add_parameters(ParameterTable &table)
  {
    ParameterHandler &prm = table.handler();
    table.enter_subsection("Heat transfer");
    if (table.declaring())
      prm.declare_entry(
        "Initial temperature",
        "300",
        Patterns::Anything(),
        "Initial temperature of the metal (and of the cells), K: "
        "a number (uniform), or a function of the position x, y "
        "(2D) or x, y, z (3D), in m, in the syntax of deal.II's "
        "FunctionParser (muparser; e.g. '1800 + 1000*x' or "
        "'if(y < 1e-5, 300, 1800)'). Its value must be finite "
        "and positive at every cell centre; range (0, inf). "
        "Points of 'Material points/Initial bodies' take the "
        "temperature of their body instead. With 'Physics/Heat "
        "transfer = false' this field stays frozen.");
    table.add("Reference temperature",
              reference_temperature,
              Patterns::Double(0.),
              "Ambient temperature T_ref for convection and radiation "
              "losses, K; range (0, inf).");
    table.add(
      "Convection coefficient",
      convection_coefficient,
      Patterns::Double(0.),
      "Surface heat transfer coefficient h, W/(m^2 K); range [0, inf).");
    table.add("Detached drops",
              detached_drops,
              {{false, "off"}, {true, "sphere"}},
              "Heat loss of detached metal: a drop of a few "
              "face-connected metal cells (at most 'Detached drop "
              "cells') with no other metal face neighbour inside "
              "the domain (spatter, or a loose grain). 'off' "
              "(default): such a drop has no surface for the central "
              "difference of alpha (or a small one) and no metal to "
              "conduct to, so it keeps its heat. 'sphere': it loses "
              "heat as a sphere of its metal volume in still gas "
              "(2D: a cylinder), over the "
              "sphere's surface: the convection, radiation and "
              "evaporation losses plus conduction to the gas with "
              "the coefficient 2 k_g/d (Nusselt number 2, d the "
              "sphere's diameter, k_g = Material/Gas thermal "
              "conductivity; argon: 0.018 W/(m K) at 300 K, 0.043 at "
              "1000 K, 0.065 at 2000 K). With the solid, the "
              "solid points of such drops are left out of the solid, "
              "at rest (doc/solid.md). doc/equations.md.");
    table.add("Detached drop cells",
              detached_drop_cells,
              Patterns::Integer(1, 4),
              "With 'Detached drops = sphere': the largest drop, "
              "in cells, that counts as detached: a set of at most "
              "this many face-connected metal cells with no other "
              "metal face neighbour inside the domain. 1: single "
              "cells; 2: single cells and pairs; 3 and 4 also lines, "
              "L shapes and squares of cells, whose central "
              "differences of alpha give a few per cent to a quarter "
              "of the sphere's surface. Range 1 to 4 (finding a drop "
              "of N cells takes N exchanges of the ghost layer). "
              "doc/equations.md.");
    table.add("Emissivity",
              emissivity,
              Patterns::Double(0., 1.),
              "Surface emissivity eps for radiation losses; range [0, 1].");
    table.add("Evaporation coefficient",
              evaporation_coefficient,
              Patterns::Double(0., 1.),
              "Evaporative loss coefficient zeta_q of eq. (1); 0 switches "
              "evaporative cooling off; range [0, 1].");
    table.add("Remove evaporated mass",
              remove_evaporated_mass,
              "Whether the evaporated metal leaves the melt: true: "
              "each step the mass m_dot(T) A dt that "
              "evaporates from a surface cell (m_dot = q_evap/L_v, "
              "kg/(m^2 s); A the cell's surface, the same weight "
              "w |grad alpha| h^dim as the evaporation loss) is taken "
              "from the fluid material points of that cell, outermost "
              "(along the outward normal of alpha) first; a point "
              "left with less than 1 % of a lattice point's mass is "
              "deleted. The surface recedes by m_dot/rho_m, and the "
              "run report books the mass and the heat it carries. "
              "Needs carried points (a bare plate without points "
              "loses no mass) and a non-zero 'Evaporation "
              "coefficient'; false (default): the metal keeps its "
              "mass (evaporation only cools). doc/equations.md.");
    table.add("Front wall piston",
              front_wall_piston,
              "Sub-cell model of the melt film between a boiling surface "
              "and the melting front below it (the piston of Semak and "
              "Matsunawa 1997; doc/equations.md, \"Front wall piston\"): "
              "in a surface cell above the evaporation temperature that "
              "absorbs laser power, the film's thickness follows from "
              "the melt made at the drilling speed and expelled at the "
              "Bernoulli speed of the recoil pressure through the rim "
              "of the beam's spot, and the flux that film conducts "
              "beyond the grid's, at most the absorbed minus the "
              "evaporated flux, moves from the surface cell to the "
              "melting front: the cell below if it is not fully liquid, "
              "else the next one inward if that one is not (only where "
              "the film is thinner than a cell; energy conserved). "
              "Needs Physics/Melt flow with Melt flow/Recoil "
              "coefficient > 0. A switch: true or false "
              "(default false: the grid's conduction only).");
    if (table.declaring())
      prm.declare_entry(
        "Fixed temperatures",
        "",
        Patterns::Map(Patterns::Selection("x-|x+|y-|y+|z-|z+"),
                      Patterns::Double(0.)),
        "Faces of the domain box held at a fixed temperature, as "
        "'face: T' pairs, e.g. 'z-: 300' (faces x-, x+, y-, y+, "
        "z-, z+; K). All other faces are insulated.");
    table.add("Laser deposition",
              laser_deposition,
              {{Deposition::first_surface, "first surface"},
               {Deposition::gradient, "gradient"}},
              "How the laser's surface flux q enters the cells. 'first "
              "surface': in each vertical column of cells, q goes into "
              "the surface cells where the beam first meets metal "
              "(from the cell below the topmost one with alpha >= 1/2 "
              "upward), shared in proportion to the loss weight "
              "w |grad alpha| so that laser and surface losses act on "
              "the same cells (absorbed power = eta P; q/h into the "
              "topmost alpha >= 1/2 cell where the column has no "
              "surface cell there). 'gradient': "
              "q 2 rho c/(rho_m c_m + rho_g c_g) |grad alpha| in every "
              "surface cell, as written in eq. (1); in a powder bed "
              "this heats every grain surface under the beam, also "
              "shadowed ones, and absorbs more than eta P.");
    table.add("Advection by melt flow",
              advection_by_melt_flow,
              {{Advection::points, "points"}, {Advection::upwind, "upwind"}},
              "How heat moves with the melt flow. 'points': the metal "
              "carries its enthalpy on the material points; when "
              "points change cells, a cell's metal takes the "
              "volume-weighted mean specific enthalpy C(T) + L_m "
              "gamma(T) of the points now in it, each at the "
              "temperature of the cell it came from (donor-cell "
              "upwind transport by the points themselves; conserves "
              "energy up to the difference between the grid's metal "
              "volume alpha h^dim and the points' volume). 'upwind': "
              "first-order upwind convection u . grad T of the cell "
              "temperature with the cell velocity of the flow (not "
              "conservative: metal moved between cells at different "
              "temperatures creates or destroys energy, "
              "doc/verification.md). "
              "No effect without Physics/Melt flow.");
    table.add("Metal of melt cells",
              metal_of_melt_cells,
              {{MeltMetal::alpha, "alpha"}, {MeltMetal::points, "points"}},
              "With 'Advection by melt flow = points': the metal whose "
              "heat a cell holding melt (a point that is or has been "
              "fluid) keeps, as heat capacity and as the metal share "
              "of its conductivity. 'alpha': its metal fraction, which "
              "counts the excess volume of over-full neighbour cells "
              "(points bunched by the flow) that their points carry; "
              "the heat the temperature step gives that volume is "
              "lost when the points next change cells, and the heat "
              "it takes is created (booked as created by points "
              "moving between cells). 'points': the volume of its own "
              "points (the conductivity's metal share at most alpha), "
              "so that the grid holds the heat the points carry and "
              "the exchange conserves it to round-off "
              "(doc/verification.md, 'Energy balance').");
    if (table.declaring())
      prm.declare_entry(
        "Prescribed velocity",
        "",
        Patterns::Anything(),
        "Optional steady velocity field for the convection term, "
        "m/s, as dim expressions in x, y, z separated by ';' "
        "(e.g. '0.1; 0; 0'). Empty: no convection unless a flow "
        "solver provides a velocity.");
    table.leave_subsection();
  }

  template <int dim>
  void
  HeatTransfer<dim>::Parameters::declare_parameters(ParameterHandler &prm)
  {
    Parameters     defaults;
    ParameterTable table(prm, ParameterTable::Mode::declare);
    defaults.add_parameters(table);
  }

  template <int dim>
  void
  HeatTransfer<dim>::Parameters::parse_parameters(ParameterHandler &prm)
  {
    ParameterTable table(prm, ParameterTable::Mode::parse);
    add_parameters(table);
    prm.enter_subsection("Heat transfer");
    {
      // A plain number, or a function expression of the position.
      const std::string text = Utilities::trim(prm.get("Initial temperature"));
      initial_temperature_expression.clear();
      initial_function.reset();
      char      *end   = nullptr;
      const auto value = std::strtod(text.c_str(), &end);
      if (!text.empty() && end == text.c_str() + text.size())
        initial_temperature = value;
      else
        {
          const std::string vars = dim == 2 ? "x,y" : "x,y,z"; // muparser list
          const std::string allowed =
            "it must be a number (K) or a function of the position " + vars +
            " (m) in deal.II FunctionParser syntax, e.g. '1800 + 1000*x'";
          require(!text.empty(),
                  "Heat transfer/Initial temperature",
                  "''",
                  allowed);
          auto f = std::make_shared<FunctionParser<dim>>(1);
          try
            {
              f->initialize(vars, text, {});
              // muparser reports unknown variables at the first evaluation.
              const double v = f->value(Point<dim>());
              (void) v;
            }
          catch (...)
            {
              throw InputError("Heat transfer/Initial temperature",
                               text,
                               allowed + "; this one does not parse (unknown "
                                         "variable or syntax error)");
            }
          initial_temperature_expression = text;
          initial_function               = f;
          initial_temperature            = f->value(Point<dim>());
        }
    }
    prescribed_velocity = Utilities::trim(prm.get("Prescribed velocity"));
    fixed_temperatures.clear();
    for (const auto &entry :
         Utilities::split_string_list(prm.get("Fixed temperatures"), ','))
      {
        const auto        kv   = Utilities::split_string_list(entry, ':');
        const std::string face = kv[0];
        require((face[0] - 'x') < dim,
                "Heat transfer/Fixed temperatures",
                entry,
                "in " + std::to_string(dim) + "D only faces of the first " +
                  std::to_string(dim) + " directions exist");
        fixed_temperatures[face] = Utilities::string_to_double(kv[1]);
      }
    prm.leave_subsection();
    if (initial_temperature_expression.empty())
      require(initial_temperature > 0,
              "Heat transfer/Initial temperature",
              initial_temperature,
              "it must be positive (K)");
  }

  template <int dim>
  double
  HeatTransfer<dim>::Parameters::initial_temperature_at(
    const Point<dim> &x) const
  {
    return initial_function ? initial_function->value(x) : initial_temperature;
  }

  template <int dim>
  void
  HeatTransfer<dim>::Parameters::check(const Point<dim> &lower,
                                       const Point<dim> &upper,
                                       const double      h)
  {
    // The prescribed velocity: dim expressions that parse, finite at
    // every cell centre (a NaN would only show as a non-finite
    // temperature later).
    std::unique_ptr<FunctionParser<dim>> velocity;
    if (!prescribed_velocity.empty())
      {
        const auto exprs =
          Utilities::split_string_list(prescribed_velocity, ';');
        require(exprs.size() == static_cast<std::size_t>(dim),
                "Heat transfer/Prescribed velocity",
                prescribed_velocity,
                "it must hold " + std::to_string(dim) +
                  " expressions separated by ';'");
        velocity = std::make_unique<FunctionParser<dim>>(dim);
        try
          {
            velocity->initialize(dim == 2 ? "x,y" : "x,y,z", exprs, {});
            velocity->value(Point<dim>(), 0); // unknown names show here
          }
        catch (...)
          {
            throw InputError(
              "Heat transfer/Prescribed velocity",
              prescribed_velocity,
              "the expressions must be valid functions of x, y (, z)");
          }
      }
    if (!initial_function && !velocity)
      return;
    std::array<unsigned int, dim> n;
    std::size_t                   total = 1;
    for (int d = 0; d < dim; ++d)
      {
        n[d] = std::max(1., std::round((upper[d] - lower[d]) / h));
        total *= n[d];
      }
    for (std::size_t c = 0; c < total; ++c)
      {
        Point<dim>  x;
        std::size_t rest = c;
        for (int d = 0; d < dim; ++d)
          {
            x[d] = lower[d] + (rest % n[d] + 0.5) * h;
            rest /= n[d];
          }
        if (velocity)
          for (int d = 0; d < dim; ++d)
            {
              const double u = velocity->value(x, d);
              if (!std::isfinite(u))
                {
                  std::ostringstream s;
                  s << "every component must be finite (m/s) at every cell "
                       "centre; component "
                    << d << " is " << u << " at x = (" << x << ") m";
                  throw InputError("Heat transfer/Prescribed velocity",
                                   prescribed_velocity,
                                   s.str());
                }
            }
        if (!initial_function)
          continue;
        const double T = initial_function->value(x);
        if (!(std::isfinite(T) && T > 0))
          {
            std::ostringstream s;
            s << "it must be finite and positive (K) at every cell centre; "
                 "it is "
              << T << " at x = (" << x << ") m";
            throw InputError("Heat transfer/Initial temperature",
                             initial_temperature_expression,
                             s.str());
          }
        if (c == 0)
          initial_temperature = T;
      }
  }

  template <int dim>
  HeatTransfer<dim>::HeatTransfer(const Parameters          &prm,
                                  const Material            &material,
                                  const Laser<dim>          &laser,
                                  const BackgroundGrid<dim> &grid)
      : prm(prm)
      , mat(material)
      , laser(laser)
      , grid(grid)
      , evap_pref(prm.evaporation_coefficient *
                  material.latent_heat_evaporation * material.molar_mass /
                  std::sqrt(2 * M_PI * material.molar_mass * gas_constant) *
                  material.ambient_pressure)
      , evap_exp(material.latent_heat_evaporation * material.molar_mass /
                 (gas_constant * material.evaporation_temperature))
  {
  }

  template <int dim>
  void
  HeatTransfer<dim>::initialize()
  {
    T     = grid.make_field(prm.initial_temperature);
    gamma = grid.make_field(mat.liquid_fraction(prm.initial_temperature));
    if (!prm.initial_temperature_expression.empty())
      for (std::size_t idx = 0; idx < T.size(); ++idx)
        if (grid.cell_status()[idx] != BackgroundGrid<dim>::outside)
          {
            T[idx]     = prm.initial_temperature_at(grid.cell_center(idx));
            gamma[idx] = mat.liquid_fraction(T[idx]);
          }
    T_new       = T;
    alpha       = grid.make_field(0.);
    mass        = alpha;
    conductance = grid.make_field(0.);
    capacity    = grid.make_field(1.);
    is_source.assign(grid.n_local(), 0);
    source        = grid.make_field(0.);
    laser_density = grid.make_field(0.);
    loss_weight   = grid.make_field(0.);
    if (prm.detached_drops)
      gas_coefficient = grid.make_field(0.);
    detached.clear();
    budget = EnergyBudget();

    // Fixed-temperature faces: owned cells touching them.
    fixed_faces.clear();
    const auto &n = grid.n_cells();
    for (const auto &[face, value] : prm.fixed_temperatures)
      {
        const int  d     = face[0] - 'x';
        const bool upper = face[1] == '+';
        for (const auto idx : grid.owned_cells())
          {
            const auto ijk = grid.global_index(idx);
            if (ijk[d] == (upper ? int(n[d]) - 1 : 0))
              fixed_faces.push_back({idx, value});
          }
      }

    if (!prm.prescribed_velocity.empty())
      {
        auto exprs = Utilities::split_string_list(prm.prescribed_velocity, ';');
        require(exprs.size() == static_cast<std::size_t>(dim),
                "Heat transfer/Prescribed velocity",
                prm.prescribed_velocity,
                "it must hold " + std::to_string(dim) +
                  " expressions separated by ';'");
        FunctionParser<dim> f(dim);
        try
          {
            f.initialize(dim == 2 ? "x,y" : "x,y,z", exprs, {});
          }
        catch (...)
          {
            throw InputError(
              "Heat transfer/Prescribed velocity",
              prm.prescribed_velocity,
              "the expressions must be valid functions of x, y (, z)");
          }
        for (int d = 0; d < dim; ++d)
          prescribed[d] = grid.make_field(0.);
        for (std::size_t idx = 0; idx < grid.n_local(); ++idx)
          if (grid.cell_status()[idx] != BackgroundGrid<dim>::outside)
            {
              const auto c = grid.cell_center(idx);
              for (int d = 0; d < dim; ++d)
                prescribed[d][idx] = f.value(c, d);
            }
      }
  }

  template <int dim>
  const std::array<std::vector<double>, dim> *
  HeatTransfer<dim>::convection_velocity(const CellFields<dim> &fields) const
  {
    if (fields.velocity &&
        prm.advection_by_melt_flow == Parameters::Advection::upwind)
      return fields.velocity;
    return prescribed[0].empty() ? nullptr : &prescribed;
  }

  template <int dim>
  void
  HeatTransfer<dim>::set_metal_fraction(const std::vector<double> &a,
                                        const MetalBodies<dim>    *bodies,
                                        const std::vector<double> *metal_mass)
  {
    MetalSurface<dim> metal_surface(grid,
                                    mat,
                                    prm.reference_temperature,
                                    prm.detached_drops);
    if (!frozen)
      metal_surface.update(a, bodies);
    set_metal_fraction(a, metal_surface, metal_mass);
  }

  template <int dim>
  void
  HeatTransfer<dim>::set_metal_fraction(const std::vector<double> &a,
                                        const MetalSurface<dim>   &s,
                                        const std::vector<double> *metal_mass)
  {
    alpha = a;
    mass  = metal_mass ? *metal_mass : a;
    if (frozen)
      {
        // No heat equation: no surface lists, no properties; only the peak
        // temperature over metal cells for the reports.
        double Tmax = 0;
        for (const auto idx : grid.owned_cells())
          if (alpha[idx] > 0)
            Tmax = std::max(Tmax, T[idx]);
        T_max = Utilities::MPI::max(Tmax, grid.communicator());
        return;
      }
    surface       = s.cells();
    first_surface = s.first_surface();
    // Detached cells lose over their sphere's surface, with the gas
    // conduction of a sphere added to the convection coefficient.
    for (const auto &dc : detached)
      gas_coefficient[dc.index] = 0;
    Assert(s.detached().empty() || prm.detached_drops,
           ExcMessage("detached cells need 'Detached drops = sphere'"));
    detached = s.detached();
    for (const auto &dc : detached)
      gas_coefficient[dc.index] = dc.gas_h;
    // Stale values of cells that left the lists (the laser's deposit is
    // cleared where it is made: the output reads the last step's deposit
    // after the melt flow has moved the metal).
    std::fill(loss_weight.begin(), loss_weight.end(), 0.);

    // Rows of the box interior that hold metal (owned or ghost); rows of gas
    // only are skipped by the per-step passes: their conductance is zero
    // (set by the full property pass below) and their temperature unused.
    {
      const auto &size = grid.box_size();
      const int   ny = dim > 1 ? size[1] : 1, nz = dim > 2 ? size[2] : 1;
      row_has_metal.assign(std::size_t(ny) * nz, 0);
      for (std::size_t r = 0, idx = 0; r < row_has_metal.size(); ++r)
        for (int i = 0; i < size[0]; ++i, ++idx)
          if (alpha[idx] > 0)
            row_has_metal[r] = 1;
      compute_properties();
    }

    // All cells with sparse sources, once each, in increasing order.
    source_cells.clear();
    for (const auto &sc : surface)
      source_cells.push_back(sc.index);
    for (const auto &lc : first_surface)
      source_cells.push_back(lc.index);
    for (const auto &f : fixed_faces)
      source_cells.push_back(f.index);
    for (const auto &dc : detached)
      source_cells.push_back(dc.index);
    std::sort(source_cells.begin(), source_cells.end());
    source_cells.erase(std::unique(source_cells.begin(), source_cells.end()),
                       source_cells.end());
  }

  template <int dim>
  void
  HeatTransfer<dim>::surface_loss(const double T,
                                  double      &q_evap,
                                  double      &q_conv,
                                  double      &q_rad,
                                  double      &dq_dT,
                                  const double gas_h) const
  {
    const double Tref  = prm.reference_temperature;
    const double Tref4 = Tref * Tref * Tref * Tref;
    // Evaporation; exp() of exponents below -40 (relative 4e-18 of the flux
    // at T_v) is skipped.
    const double exponent = evap_exp * (T - mat.evaporation_temperature) / T;
    q_evap                = (evap_pref > 0 && exponent > -40) ?
                              evap_pref / std::sqrt(T) * std::exp(exponent) :
                              0.;
    q_conv                = (prm.convection_coefficient + gas_h) * (T - Tref);
    q_rad = stefan_boltzmann * prm.emissivity * (T * T * T * T - Tref4);
    dq_dT =
      q_evap * (evap_exp * mat.evaporation_temperature / (T * T) - 0.5 / T) +
      prm.convection_coefficient + gas_h +
      4 * stefan_boltzmann * prm.emissivity * T * T * T;
  }

  template <int dim>
  double
  HeatTransfer<dim>::evaporative_mass_flux(const double T_surface) const
  {
    if (!(mat.latent_heat_evaporation > 0))
      return 0.;
    double qe, qc, qr, dq;
    surface_loss(T_surface, qe, qc, qr, dq, 0.);
    return qe / mat.latent_heat_evaporation;
  }

  template <int dim>
  Tensor<1, dim>
  HeatTransfer<dim>::outward_normal(const std::size_t idx) const
  {
    // Central differences of alpha (ghosts current; zero gradient at the
    // box faces), as MetalSurface finds |grad alpha|.
    const auto    &st  = grid.strides();
    const auto    &n   = grid.n_cells();
    const auto     ijk = grid.global_index(idx);
    Tensor<1, dim> g;
    for (int d = 0; d < dim; ++d)
      {
        const double am = ijk[d] > 0 ? alpha[idx - st[d]] : alpha[idx];
        const double ap =
          ijk[d] < int(n[d]) - 1 ? alpha[idx + st[d]] : alpha[idx];
        g[d] = am - ap;
      }
    const double norm = g.norm();
    return norm > 1e-12 ? g / norm : Tensor<1, dim>();
  }

  template <int dim>
  void
  HeatTransfer<dim>::compute_surface_sources(const double dt, const double time)
  {
    const double V = std::pow(grid.h(), dim);
    Point<dim>   axis;
    double       power    = 0;
    const bool   laser_on = laser.position(time, axis, power);
    const bool   gradient_mode =
      prm.laser_deposition == Parameters::Deposition::gradient;
    const double rho_g_c_g = mat.gas_density * mat.gas_specific_heat;
    double       e_laser   = 0;
    // This step's deposit only: no cell keeps one of a step before.
    std::fill(laser_density.begin(), laser_density.end(), 0.);
    // Loss weights w |grad alpha| at T^n; the losses themselves are taken
    // at the new temperature in advance() (pass C).
    for (const auto &s : surface)
      {
        const double Tc      = T[s.index];
        const double a       = alpha[s.index];
        const double rho_c_m = mat.density * mat.specific_heat.value(Tc);
        const double w       = 2 * heat_capacity(Tc, a) / (rho_c_m + rho_g_c_g);
        const double wg      = w * s.grad_alpha;
        double       q_laser = 0;
        if (laser_on && gradient_mode)
          {
            q_laser = laser.cell_flux(grid.cell_center(s.index),
                                      axis,
                                      power,
                                      grid.h()) *
                      wg;
          }
        laser_density[s.index] = q_laser;
        source[s.index]        = q_laser;
        loss_weight[s.index]   = wg;
        e_laser += q_laser;
      }
    // Detached cells lose over their sphere's surface instead.
    for (const auto &dc : detached)
      loss_weight[dc.index] = dc.area;
    if (tracer)
      e_laser += deposit_traced_laser(time, dt);
    else if (!gradient_mode)
      for (const auto &lc : first_surface)
        {
          if (!laser_on)
            {
              laser_density[lc.index] = 0;
              continue;
            }
          const double q =
            laser.cell_flux(grid.cell_center(lc.index), axis, power, grid.h()) *
            lc.share;
          laser_density[lc.index] = q;
          source[lc.index] += q;
          e_laser += q;
        }
    budget.laser += e_laser * V * dt;
  }

  template <int dim>
  void
  HeatTransfer<dim>::set_absorption_model(
    const typename RayTracedAbsorption<dim>::Parameters &absorption)
  {
    tracer.reset();
    if (absorption.model ==
        RayTracedAbsorption<dim>::Parameters::Model::ray_traced)
      tracer = std::make_unique<RayTracedAbsorption<dim>>(absorption, grid);
  }

  template <int dim>
  void
  HeatTransfer<dim>::enable_front_wall_piston(const RecoilLaw &recoil)
  {
    piston.reset();
    if (!prm.front_wall_piston)
      return;
    if (!(recoil.coefficient() > 0))
      throw InputError("Heat transfer/Front wall piston",
                       "true",
                       "needs the recoil pressure: Physics/Melt flow = true "
                       "and Melt flow/Recoil coefficient > 0 (got " +
                         num(recoil.coefficient()) + ")");
    piston = std::make_unique<FrontWallPiston<dim>>(
      grid, mat, recoil, laser.beam_radius(), prm.initial_temperature);
  }

  template <int dim>
  void
  HeatTransfer<dim>::trace_laser(const double time)
  {
    Assert(tracer, ExcMessage("trace_laser() needs 'ray traced'"));
    ray_deposits.clear();
    trace_result = {};
    Point<dim> axis;
    double     power = 0;
    if (laser.position(time, axis, power) && power > 0)
      trace_result =
        tracer->trace(alpha, axis, power, laser.beam_radius(), ray_deposits);
    traced_time = time;
    traced      = true;
  }

  // Ray-traced laser: each hit's absorbed power W goes into its (owned)
  // surface cell as the volumetric source W/V for this step. A cell that is
  // not yet among the sparse-source cells (not expected: the tracer picks
  // surface cells as set_metal_fraction() does) is added to them, so that
  // no deposit is lost. The beam energy P dt and the escaping part are
  // booked once (rank 0; the trace is the same on every rank).
  template <int dim>
  double
  HeatTransfer<dim>::deposit_traced_laser(const double time, const double dt)
  {
    if (!traced || traced_time != time)
      trace_laser(time);
    traced = false;
    for (const auto idx : ray_cells)
      laser_density[idx] = 0;
    ray_cells.clear();
    const double iV  = 1. / std::pow(grid.h(), dim);
    double       sum = 0;
    for (const auto &[idx, W] : ray_deposits)
      {
        const double q = W * iV;
        if (laser_density[idx] == 0)
          ray_cells.push_back(idx);
        laser_density[idx] += q;
        source[idx] += q;
        sum += q;
        const auto it =
          std::lower_bound(source_cells.begin(), source_cells.end(), idx);
        if (it == source_cells.end() || *it != idx)
          source_cells.insert(it, idx);
      }
    if (Utilities::MPI::this_mpi_process(grid.communicator()) == 0)
      {
        budget.laser_incident += trace_result.incident * dt;
        budget.laser_escaped += trace_result.escaped * dt;
      }
    return sum;
  }

  template <int dim>
  double
  HeatTransfer<dim>::stable_time_step(const CellFields<dim> &fields)
  {
    const auto *velocity = convection_velocity(fields);
    compute_properties();
    const auto  &st       = grid.strides();
    const double ih2      = 1. / (grid.h() * grid.h());
    double       rate_max = 0;
    for (const auto idx : grid.owned_cells())
      {
        const double a = alpha[idx];
        if (a <= 0)
          continue;
        const double kc   = conductance[idx];
        double       sumk = 0;
        for (int d = 0; d < dim; ++d)
          for (const std::ptrdiff_t s : {-st[d], st[d]})
            {
              const double kn = conductance[idx + s];
              sumk += kn > 0 ? 2 * kc * kn / (kc + kn) : 0.;
            }
        double rate = sumk * ih2 / capacity[idx];
        if (velocity)
          for (int d = 0; d < dim; ++d)
            rate += std::abs((*velocity)[d][idx]) / grid.h();
        rate_max = std::max(rate_max, rate);
      }
    for (const auto &f : fixed_faces)
      rate_max =
        std::max(rate_max, 4 * conductance[f.index] * ih2 / capacity[f.index]);
    rate_max = Utilities::MPI::max(rate_max, grid.communicator());
    return rate_max > 0 ? 1. / rate_max : std::numeric_limits<double>::max();
  }

  template <int dim>
  void
  HeatTransfer<dim>::compute_properties()
  {
    compute_properties(0, T.size());
  }

  template <int dim>
  void
  HeatTransfer<dim>::compute_properties(const std::size_t begin,
                                        const std::size_t end)
  {
    // Pass A: conductivity (zero in gas cells and in the padding, which
    // blocks their faces) and heat capacity of every cell of the box.
    const std::uint8_t *status   = grid.cell_status().data();
    const double        rho_g_cg = mat.gas_density * mat.gas_specific_heat;
    const double        k_g      = mat.gas_conductivity;
    const double        rho_m    = mat.density;
    const double       *Tp = T.data(), *ap = alpha.data(), *mp = mass.data();
    double             *kp = conductance.data(), *cp = capacity.data();
    if (!mat.conductivity.has_padded_segments() ||
        !mat.specific_heat.has_padded_segments())
      {
        // Long tables: scalar lookups.
        for (std::size_t idx = begin; idx < end; ++idx)
          {
            const double a     = ap[idx];
            const double metal = (a > 0 && status[idx] != 0) ? 1. : 0.;
            const double ak    = std::min(a, mp[idx]);
            kp[idx] =
              metal * (ak * mat.conductivity.value(Tp[idx]) + (1 - ak) * k_g);
            cp[idx] =
              metal * (mp[idx] * rho_m * mat.specific_heat.value(Tp[idx]) +
                       (1 - a) * rho_g_cg) +
              (1 - metal);
          }
        return;
      }
    const auto k_m = mat.conductivity.segments();
    const auto c_m = mat.specific_heat.segments();
    // Short tables (the usual case) unroll to 4 segments, others to 8.
    auto sweep = [&](auto nk, auto nc) {
      constexpr unsigned int NK = decltype(nk)::value, NC = decltype(nc)::value;
#pragma omp simd
      for (std::size_t idx = begin; idx < end; ++idx)
        {
          const double a     = ap[idx];
          const double metal = (a > 0) & (status[idx] != 0) ? 1. : 0.;
          const double Tc    = Tp[idx];
          const double ak    = std::min(a, mp[idx]);
          kp[idx] = metal * (ak * k_m.template eval<NK>(Tc) + (1 - ak) * k_g);
          cp[idx] = metal * (mp[idx] * rho_m * c_m.template eval<NC>(Tc) +
                             (1 - a) * rho_g_cg) +
                    (1 - metal); // 1 in gas and padding: never used for heat
        }
    };
    using four = std::integral_constant<unsigned int, 4>;
    using eight =
      std::integral_constant<unsigned int, PiecewiseLinear::max_segments>;
    if (k_m.n <= 4 && c_m.n <= 4)
      sweep(four(), four());
    else if (k_m.n <= 4)
      sweep(four(), eight());
    else if (c_m.n <= 4)
      sweep(eight(), four());
    else
      sweep(eight(), eight());
  }

  template <int dim>
  void
  HeatTransfer<dim>::advance(const double           dt,
                             const double           time,
                             const CellFields<dim> &fields)
  {
    Assert(!frozen, ExcMessage("advance() on a frozen temperature field"));
    progress::phase("the temperature step");
    if (std::isnan(T_floor))
      set_temperature_floor();
    // Properties: in 3D plane by plane just ahead of the sweep (pass B), so
    // that they are still in cache when the stencil reads them.
    const std::size_t rows_per_plane =
      dim == 3 ? grid.strides()[dim - 1] / grid.box_size()[0] : 0;
    if (dim == 3)
      properties_of_rows(0, 2 * rows_per_plane);
    else
      properties_of_rows(0, row_has_metal.size());
    compute_surface_sources(dt, time);
    if (piston)
      piston->add_transfer(
        T,
        alpha,
        gamma,
        laser_density,
        loss_weight,
        [this](const double Tc) {
          double qe, qc, qr, dq;
          surface_loss(Tc, qe, qc, qr, dq, 0.);
          return qe;
        },
        surface,
        source,
        source_cells);

    StepSums sums;
    conduction_pass(dt, sums); // pass B: T_new by conduction
    fixed_face_pass(dt, sums); // fixed-temperature faces
    convection_pass(dt, convection_velocity(fields), sums); // upwind
    source_pass(dt, sums);       // pass C: sources, surface losses
    phase_change_pass(sums);     // pass D: enthalpy iteration
    finish_step(dt, time, sums); // budget, T_max, ghosts, next limit
    if (lists_evaporated_mass())
      evaporated_mass_outward(); // the mass to the outermost metal
  }

  // The loss weight w |grad alpha| spreads a surface over the cells that
  // straddle it (a flat surface through a partly filled cell: that cell and
  // the full one below, in proportion alpha to 1 - alpha), and so does the
  // evaporated mass. Taken where it is booked, the full cell below would
  // lose metal while the partly filled one above still holds its points:
  // without a flow to close the gap the metal fraction smears downwards
  // (measured: a layer at 4000 K, 12 um of recession over 60 us, ends with
  // partly filled cells 16 um deep and 11 % less evaporation than the
  // flat surface gives). Each cell therefore passes its evaporated mass to
  // its outward face neighbour along the dominant direction of its normal
  // when that one holds metal (a ghost cell's owner gets it), up to
  // 1/(2 dim + 1) of that neighbour's metal mass, so that the neighbour can
  // give it even to all its inner neighbours at once; the rest stays. One
  // cell is as far as the ghost layer reaches, so the result does not
  // depend on the partition. Collective.
  template <int dim>
  void
  HeatTransfer<dim>::evaporated_mass_outward()
  {
    const auto                 &st     = grid.strides();
    const auto                 &n      = grid.n_cells();
    const auto                 &status = grid.cell_status();
    const double                rho_V  = mat.density * std::pow(grid.h(), dim);
    std::vector<EvaporatedMass> moved;
    std::map<unsigned int, std::vector<double>> outgoing;
    moved.reserve(evaporated.size());
    for (const auto &e : evaporated)
      {
        int d = dim - 1;
        for (int dd = 0; dd < dim; ++dd)
          if (std::abs(e.outward[dd]) > std::abs(e.outward[d]))
            d = dd;
        const int  sign   = e.outward[d] < 0 ? -1 : 1;
        auto       ijk    = grid.global_index(e.index);
        double     share  = 0;
        const bool inside = e.outward.norm() > 0 && ijk[d] + sign >= 0 &&
                            ijk[d] + sign < int(n[d]);
        const std::size_t j =
          inside ? e.index + (sign > 0 ? st[d] : -st[d]) : e.index;
        if (inside && alpha[j] > 0)
          share = std::min(e.mass, rho_V * alpha[j] / (2 * dim + 1));
        if (share > 0)
          {
            if (status[j] == BackgroundGrid<dim>::owned)
              moved.push_back({std::uint32_t(j), share, e.outward});
            else
              {
                ijk[d] += sign;
                auto &buffer = outgoing[grid.cell_iterator(j)->subdomain_id()];
                for (int k = 0; k < dim; ++k)
                  buffer.push_back(ijk[k]);
                buffer.push_back(share);
                for (int k = 0; k < dim; ++k)
                  buffer.push_back(e.outward[k]);
              }
          }
        if (e.mass - share > 0)
          moved.push_back({e.index, e.mass - share, e.outward});
      }
    const auto incoming =
      Utilities::MPI::some_to_some(grid.communicator(), outgoing);
    for (const auto &[rank, buffer] : incoming)
      for (std::size_t k = 0; k + 2 * dim + 1 <= buffer.size();
           k += 2 * dim + 1)
        {
          std::array<int, dim> ijk;
          Tensor<1, dim>       normal;
          for (int q = 0; q < dim; ++q)
            {
              ijk[q]    = static_cast<int>(buffer[k + q]);
              normal[q] = buffer[k + dim + 1 + q];
            }
          moved.push_back(
            {std::uint32_t(grid.local_index(ijk)), buffer[k + dim], normal});
        }
    // One entry per cell, in increasing index; the direction weighted by
    // the masses.
    std::sort(moved.begin(),
              moved.end(),
              [](const EvaporatedMass &a, const EvaporatedMass &b) {
                return a.index < b.index ||
                       (a.index == b.index && a.mass < b.mass);
              });
    evaporated.clear();
    for (const auto &m : moved)
      if (!evaporated.empty() && evaporated.back().index == m.index)
        {
          evaporated.back().outward += m.mass * m.outward;
          evaporated.back().mass += m.mass;
        }
      else
        evaporated.push_back({m.index, m.mass, m.mass * m.outward});
    for (auto &e : evaporated)
      if (e.outward.norm() > 0)
        e.outward /= e.outward.norm();
  }

  template <int dim>
  void
  HeatTransfer<dim>::properties_of_rows(const std::size_t first_row,
                                        const std::size_t n_rows)
  {
    const std::size_t row_len = grid.box_size()[0];
    for (std::size_t r = first_row; r < first_row + n_rows; ++r)
      if (row_has_metal[r])
        compute_properties(r * row_len, (r + 1) * row_len);
  }

  // Pass B: conduction on whole x-rows of the box interior, branch-free
  // so that it vectorizes; gas and padding cells have zero conductance and
  // keep their value. Rows where a cell may need the phase-change
  // iteration are flagged for pass D. In 3D the properties of the plane
  // ahead are computed just before each plane.
  template <int dim>
  void
  HeatTransfer<dim>::conduction_pass(const double dt, StepSums &sums)
  {
    const std::size_t plane   = dim == 3 ? grid.strides()[dim - 1] : T.size();
    const std::size_t row_len = grid.box_size()[0];
    const std::size_t rows_per_plane = dim == 3 ? plane / row_len : 0;
    const auto       &st             = grid.strides();
    const auto       &size           = grid.box_size();
    const double      h              = grid.h();
    const double      ih             = 1. / h;
    const double      ih2            = ih * ih;
    const double      Ts             = mat.solidus;
    const double      Tl             = mat.liquidus;
    const double      rhoL           = mat.density * mat.latent_heat_fusion;
    const bool        variable_c     = !mat.specific_heat.is_constant();

    double rate_max = 0;

    const double *Tp = T.data(), *kp = conductance.data(),
                 *cp = capacity.data(), *gp = gamma.data();
    double *Tn = T_new.data();
    // Peak, lowest temperature and fastest rate over owned cells only: on
    // several ranks the box interior also holds ghost cells and cells this
    // rank does not know, whose new values here use stale neighbours (their
    // owners compute them; the ghost exchange after the step overwrites
    // them). One rank owns every interior cell.
    const std::uint8_t  *own = grid.cell_status().data();
    const std::ptrdiff_t sy = dim > 1 ? st[1] : 0, sz = dim > 2 ? st[2] : 0;
    const int            ny = dim > 1 ? size[1] : 1, nz = dim > 2 ? size[2] : 1;
    const int            j0 = dim > 1 ? 1 : 0, k0 = dim > 2 ? 1 : 0;
    flagged_rows.clear();
    const bool has_latent = rhoL > 0;
    double     box_max = -std::numeric_limits<double>::max(), box_bad = 0;
    double     box_min = std::numeric_limits<double>::max();
    for (int kk = k0; kk < (dim > 2 ? nz - 1 : 1); ++kk)
      {
        if (dim == 3)
          properties_of_rows((kk + 1) * rows_per_plane, rows_per_plane);
        for (int jj = j0; jj < ny - 1; ++jj)
          {
            if (!row_has_metal[(jj * sy + kk * sz) / row_len])
              continue; // gas only: nothing changes
            const std::size_t row = jj * sy + kk * sz;
            double row_rate = 0, row_max = 0, row_bad = 0, row_flags = 0;
            double row_min = std::numeric_limits<double>::max();
#pragma omp simd reduction(max : row_rate, row_max) reduction(min : row_min) reduction(+ : row_bad, row_flags)
            for (int ii = 1; ii < size[0] - 1; ++ii)
              {
                const std::size_t i  = row + ii;
                const double      Tc = Tp[i], kc = kp[i];
                // harmonic mean 2 k_c k_n / (k_c + k_n), zero if either is zero
                const double kxm = kp[i - 1], kxp = kp[i + 1];
                const double fxm = 2 * kc * kxm / (kc + kxm + 1e-300);
                const double fxp = 2 * kc * kxp / (kc + kxp + 1e-300);
                double flux = fxm * (Tp[i - 1] - Tc) + fxp * (Tp[i + 1] - Tc);
                double sumk = fxm + fxp;
                if constexpr (dim > 1)
                  {
                    const double kym = kp[i - sy], kyp = kp[i + sy];
                    const double fym = 2 * kc * kym / (kc + kym + 1e-300);
                    const double fyp = 2 * kc * kyp / (kc + kyp + 1e-300);
                    flux += fym * (Tp[i - sy] - Tc) + fyp * (Tp[i + sy] - Tc);
                    sumk += fym + fyp;
                  }
                if constexpr (dim > 2)
                  {
                    const double kzm = kp[i - sz], kzp = kp[i + sz];
                    const double fzm = 2 * kc * kzm / (kc + kzm + 1e-300);
                    const double fzp = 2 * kc * kzp / (kc + kzp + 1e-300);
                    flux += fzm * (Tp[i - sz] - Tc) + fzp * (Tp[i + sz] - Tc);
                    sumk += fzm + fzp;
                  }
                const double inv_c = 1. / cp[i];
                const double Tnew  = Tc + dt * ih2 * flux * inv_c;
                Tn[i]              = Tnew;
                const bool   owned = own[i] == BackgroundGrid<dim>::owned;
                const double rate  = owned ? sumk * ih2 * inv_c : 0.;
                row_rate           = rate > row_rate ? rate : row_rate;
                // metal cells only: gas may keep a stale T after points moved
                row_max = owned & (kc > 0) & (Tnew > row_max) ? Tnew : row_max;
                row_min = owned & (kc > 0) & (Tnew < row_min) ? Tnew : row_min;
                row_bad += Tnew - Tnew; // NaN if Tnew is not finite
                // Flag: a cell may change phase (unless clearly solid or
                // clearly liquid) or, with c(T) tables, takes a large step.
                const double g      = gp[i];
                const bool   solid  = (Tnew < Ts) & (g == 0.);
                const bool   liquid = (Tnew > Tl) & (g == 1.);
                const bool   phase  = has_latent & !(solid | liquid);
                const bool   large  = variable_c & (std::abs(Tnew - Tc) > 1.);
                row_flags += (phase | large) ? 1. : 0.;
              }
            const bool needs_phase = row_flags > 0;
            box_max                = std::max(box_max, row_max);
            box_min                = std::min(box_min, row_min);
            box_bad += row_bad;
            rate_max = std::max(rate_max, row_rate);
            if (needs_phase)
              flagged_rows.push_back(row);
          }
      }

    sums.rate_max = rate_max;
    sums.box_max  = box_max;
    sums.box_min  = box_min;
    sums.box_bad  = box_bad;
  }

  template <int dim>
  void
  HeatTransfer<dim>::fixed_face_pass(const double dt, StepSums &sums)
  {
    const double h        = grid.h();
    const double ih       = 1. / h;
    const double ih2      = ih * ih;
    const double V        = std::pow(h, dim);
    double       rate_max = sums.rate_max;
    // Fixed-temperature faces: the face value sits h/2 from the cell centre.
    double e_boundary = 0;
    for (const auto &f : fixed_faces)
      if (alpha[f.index] > 0)
        {
          const double k = conductance[f.index];
          const double q = 2 * k * (f.value - T[f.index]) * ih2;
          source[f.index] += q;
          e_boundary += q * V * dt;
          rate_max = std::max(rate_max, 4 * k * ih2 / capacity[f.index]);
        }
    sums.e_boundary = e_boundary;
    sums.rate_max   = rate_max;
  }

  // Convection (only when a velocity field is present): first-order
  // upwind, no advective flux from gas or from outside the domain. In a
  // partly filled cell (alpha < 1) the metal flowing in mixes with alpha
  // of metal, so its temperature moves at the rate 1/alpha: the part
  // (1/alpha - 1) is taken implicitly in the cell's own temperature
  // (a convex mix of T* and the upwind values: no step limit); full cells
  // are unchanged. With it, the alpha update from the points (which
  // books the arriving volume at the cell's T) and the convection give
  // the arriving metal the upwind temperature (doc/equations.md).
  template <int dim>
  void
  HeatTransfer<dim>::convection_pass(
    const double                                dt,
    const std::array<std::vector<double>, dim> *velocity,
    StepSums                                   &sums)
  {
    const auto  &st          = grid.strides();
    const double ih          = 1. / grid.h();
    const double ih2         = ih * ih;
    double       rate_max    = sums.rate_max;
    double       e_advection = 0;
    if (velocity)
      for (const auto idx : grid.owned_cells())
        {
          if (alpha[idx] <= 0)
            continue;
          double conv = 0, rate = 0, r_up = 0, rT_up = 0;
          for (int d = 0; d < dim; ++d)
            {
              const double         u  = (*velocity)[d][idx];
              const std::ptrdiff_t s  = u > 0 ? -st[d] : st[d];
              const bool           up = conductance[idx + s] > 0;
              const double         dT = up ? T[idx] - T[idx + s] : 0.;
              conv -= std::abs(u) * dT * ih;
              rate += std::abs(u) * ih;
              if (up)
                {
                  r_up += std::abs(u) * ih;
                  rT_up += std::abs(u) * ih * T[idx + s];
                }
            }
          if (alpha[idx] < 1 && r_up > 0)
            {
              // T_new = (T* + w sum r T_up) / (1 + w sum r), w = dt (1/alpha -
              // 1)
              const double w     = dt * (1. / alpha[idx] - 1);
              const double Tstar = T_new[idx] + dt * conv;
              const double Tmix  = (Tstar + w * rT_up) / (1 + w * r_up);
              conv += (Tmix - Tstar) / dt;
            }
          T_new[idx] += dt * conv;
          e_advection += capacity[idx] * conv;
          // Convection and diffusion rates add up in this cell.
          double sumk = 0;
          for (int d = 0; d < dim; ++d)
            for (const std::ptrdiff_t s : {-st[d], st[d]})
              {
                const double kn = conductance[idx + s], kc = conductance[idx];
                sumk += kn > 0 ? 2 * kc * kn / (kc + kn) : 0.;
              }
          rate_max = std::max(rate_max, rate + sumk * ih2 / capacity[idx]);
        }
    sums.e_advection = e_advection;
    sums.rate_max    = rate_max;
  }

  // Pass C: cells with sparse sources (laser, surface losses, fixed
  // faces). The surface loss q(T) w |grad alpha| is taken at the new
  // temperature (fully implicit, a local Newton iteration): a cell heated
  // from cold in one step meets the evaporation of the temperature it
  // reaches, not the one it starts from (a linearization about T^n let
  // the first steps of the 3D track heat powder tops to 8000 K and
  // more). The loss is booked at the new temperature, so the energy
  // stays balanced exactly.
  template <int dim>
  void
  HeatTransfer<dim>::source_pass(const double dt, StepSums &sums)
  {
    const double rhoL       = mat.density * mat.latent_heat_fusion;
    const bool   variable_c = !mat.specific_heat.is_constant();
    std::size_t  nphase     = 0;
    double       e_evap = 0, e_conv = 0, e_rad = 0;
    // The evaporated mass per cell (q_evap W V dt / L_v), with the outward
    // normal of alpha for the removal from the points.
    evaporated.clear();
    const bool   list_mass = lists_evaporated_mass();
    const double mass_per_loss =
      list_mass ? std::pow(grid.h(), dim) * dt / mat.latent_heat_evaporation :
                  0.;
    for (const auto idx : source_cells)
      {
        const double Tc   = T[idx];
        const double rc   = capacity[idx];
        const double dH   = (T_new[idx] - Tc) * rc + dt * source[idx];
        const double W    = loss_weight[idx];
        const double hg   = gas_coefficient.empty() ? 0. : gas_coefficient[idx];
        double       Tnew = Tc + dH / rc;
        // The cell's local solve: sensible heat only, or with the latent
        // heat when the step crosses the melting range.
        const auto solve = [&](const bool enthalpy) {
          return solve_cell(mass[idx],
                            1 - alpha[idx],
                            Tc,
                            gamma[idx],
                            rc,
                            dH,
                            dt * W,
                            enthalpy,
                            Tnew,
                            hg);
        };
        if (W > 0)
          Tnew = solve(false);
        if (needs_local_solve(Tc, Tnew, gamma[idx], rhoL, variable_c))
          {
            ++nphase;
            Tnew = solve(true);
          }
        if (W > 0)
          {
            double qe, qc, qr, dq;
            surface_loss(Tnew, qe, qc, qr, dq, hg);
            e_evap += qe * W;
            if (list_mass && qe > 0)
              evaporated.push_back(
                {idx, qe * W * mass_per_loss, outward_normal(idx)});
            e_conv += qc * W;
            e_rad += qr * W;
          }
        T_new[idx]     = Tnew;
        gamma[idx]     = mat.liquid_fraction(Tnew);
        is_source[idx] = 1;
      }
    sums.nphase = nphase;
    sums.e_evap = e_evap;
    sums.e_conv = e_conv;
    sums.e_rad  = e_rad;
  }

  // Pass D: the local enthalpy iteration in flagged rows (not for source
  // cells, done above): find T with
  //   H(T) = H(T^n) + dH,  H = a rho_m (C(T) + L gamma(T)) + (1-a) rho_g c_g T,
  // C the antiderivative of c_m; exact bookkeeping of c(T) and latent heat.
  template <int dim>
  void
  HeatTransfer<dim>::phase_change_pass(StepSums &sums)
  {
    const auto  &size       = grid.box_size();
    const double rhoL       = mat.density * mat.latent_heat_fusion;
    const bool   variable_c = !mat.specific_heat.is_constant();
    std::size_t  nphase     = sums.nphase;
    const auto  &status     = grid.cell_status();
    for (const std::size_t row : flagged_rows)
      for (int ii = 1; ii < size[0] - 1; ++ii)
        {
          const std::size_t idx = row + ii;
          if (is_source[idx] || alpha[idx] <= 0 ||
              status[idx] != BackgroundGrid<dim>::owned)
            continue;
          const double Tc   = T[idx];
          double       Tnew = T_new[idx];
          if (!needs_local_solve(Tc, Tnew, gamma[idx], rhoL, variable_c))
            continue;
          ++nphase;
          const double dH = (Tnew - Tc) * capacity[idx];
          Tnew            = solve_cell(mass[idx],
                            1 - alpha[idx],
                            Tc,
                            gamma[idx],
                            capacity[idx],
                            dH,
                            0.,
                            true,
                            Tnew);
          T_new[idx]      = Tnew;
          gamma[idx]      = mat.liquid_fraction(Tnew);
        }
    sums.nphase = nphase;
  }

  template <int dim>
  void
  HeatTransfer<dim>::finish_step(const double    dt,
                                 const double    time,
                                 const StepSums &sums)
  {
    const auto  &size   = grid.box_size();
    const double V      = std::pow(grid.h(), dim);
    const double e_evap = sums.e_evap, e_conv = sums.e_conv, e_rad = sums.e_rad;
    const double e_boundary  = sums.e_boundary;
    const double e_advection = sums.e_advection;
    const double box_max = sums.box_max, box_bad = sums.box_bad;
    const double rate_max    = sums.rate_max;
    const std::size_t nphase = sums.nphase;
    // Reset the sparse sources.
    for (const auto idx : source_cells)
      {
        source[idx]    = 0;
        is_source[idx] = 0;
      }
    budget.evaporation += e_evap * V * dt;
    budget.convection += e_conv * V * dt;
    budget.radiation += e_rad * V * dt;
    budget.boundary += e_boundary;
    budget.advection += e_advection * V * dt;

    // Peak and lowest temperature over owned metal cells (the sweep took
    // owned cells only), reduced over the ranks below; finiteness over the
    // box. Cells changed after pass B (sources, phase change) are added
    // here.
    const auto &status = grid.cell_status();
    double      Tmax = box_max, Tmin = sums.box_min;
    for (const auto idx : source_cells)
      if (alpha[idx] > 0 && status[idx] == BackgroundGrid<dim>::owned)
        {
          Tmax = std::max(Tmax, T_new[idx]);
          Tmin = std::min(Tmin, T_new[idx]);
        }
    for (const std::size_t row : flagged_rows)
      for (int ii = 1; ii < size[0] - 1; ++ii)
        if (alpha[row + ii] > 0 &&
            status[row + ii] == BackgroundGrid<dim>::owned)
          {
            Tmax = std::max(Tmax, T_new[row + ii]);
            Tmin = std::min(Tmin, T_new[row + ii]);
          }
    bool finite = std::isfinite(box_bad) && std::isfinite(Tmax);
    for (const auto idx : source_cells)
      finite = finite && std::isfinite(T_new[idx]);
    if (!finite)
      Tmax = std::numeric_limits<double>::infinity();

    std::swap(T, T_new);
    grid.update_ghosts(T);
    grid.update_ghosts(gamma);
    n_phase_cells = nphase;

    // One reduction for the peak, the rate and the lowest temperature.
    const double local[3] = {Tmax, rate_max, -Tmin};
    double       global[3];
    Utilities::MPI::max(ArrayView<const double>(local, 3),
                        grid.communicator(),
                        ArrayView<double>(global, 3));
    T_max = global[0];
    dt_stable_next =
      global[1] > 0 ? 1. / global[1] : std::numeric_limits<double>::max();

    if (!std::isfinite(T_max))
      {
        // Every rank knows (T_max is global): the first rank with a
        // non-finite owned cell tells the others where, and all stop with
        // the same message.
        Point<dim> where;
        bool       found = false;
        for (const auto idx : grid.owned_cells())
          if (!std::isfinite(T[idx]))
            {
              where = grid.cell_center(idx), found = true;
              break;
            }
        share_location(found, where, grid.communicator());
        throw CollectiveError(
          "The temperature became non-finite at time " + num(time + dt) +
          " s (step size " + num(dt) +
          " s). First non-finite temperature in "
          "the cell at " +
          location_text(where) +
          " m. The step may exceed the "
          "stable limit, or a surface loss (evaporation) may be too stiff.");
      }
    check_temperature_floor(-global[2], dt, time);
  }

  template <int dim>
  double
  HeatTransfer<dim>::enthalpy_density(const double m,
                                      const double g,
                                      const double T) const
  {
    return m * mat.density *
             (mat.specific_heat.antiderivative(T) +
              mat.latent_heat_fusion * mat.liquid_fraction(T)) +
           g * mat.gas_density * mat.gas_specific_heat * T;
  }

  template <int dim>
  double
  HeatTransfer<dim>::solve_cell(const double m,
                                const double g,
                                const double Tc,
                                const double gc,
                                const double rc,
                                const double dH,
                                const double dtW,
                                const bool   enthalpy,
                                const double guess,
                                const double gas_h) const
  {
    // f(T) = H(T) - H(Tc) + dtW q(T) - dH, increasing in T (q grows with T
    // below ~2 L_v M/R, 1e5 K for steel). With the sensible part only,
    // H(T) - H(Tc) = rc (T - Tc).
    const double H0 = enthalpy ?
                        m * mat.density *
                            (mat.specific_heat.antiderivative(Tc) +
                             mat.latent_heat_fusion * gc) +
                          g * mat.gas_density * mat.gas_specific_heat * Tc :
                        0.;
    auto         f  = [&](const double T, double &slope) {
      double qe = 0, qc = 0, qr = 0, dq = 0;
      if (dtW > 0)
        surface_loss(T, qe, qc, qr, dq, gas_h);
      if (enthalpy)
        {
          slope = m * mat.density *
                    (mat.specific_heat.value(T) +
                     ((T > mat.solidus && T < mat.liquidus) ?
                                 mat.latent_heat_fusion / (mat.liquidus - mat.solidus) :
                                 0.)) +
                  g * mat.gas_density * mat.gas_specific_heat +
                  dtW * std::max(0., dq);
          return enthalpy_density(m, g, T) - H0 + dtW * (qe + qc + qr) - dH;
        }
      slope = rc + dtW * std::max(0., dq);
      return rc * (T - Tc) + dtW * (qe + qc + qr) - dH;
    };
    // Bracket: the slope is at least c_min, so the root lies between Tc and
    // Tc - f(Tc)/c_min; temperatures stay positive.
    const double c_min = enthalpy ?
                           m * mat.density * mat.specific_heat.min_value() +
                             g * mat.gas_density * mat.gas_specific_heat :
                           rc;
    // Start from the guess, or without the enthalpy tables from the
    // linearization about Tc (one Newton step; exact for the convection
    // part, within round-off for cold cells, whose loss is nearly linear).
    double       slope = 0;
    const double f0    = f(Tc, slope);
    const double Tfar  = Tc - f0 / c_min;
    double       lo = std::min(Tc, Tfar) - 1e-9, hi = std::max(Tc, Tfar) + 1e-9;
    lo       = std::max(lo, 1e-3 * Tc);
    double T = std::clamp(enthalpy ? guess : Tc - f0 / slope, lo, hi);
    // Residual tolerance (J/m^3): the loss is booked at the T returned, so
    // the balance holds to this residual per cell.
    const double tol =
      1e-12 * (std::abs(H0) + c_min * Tc + std::abs(dH) + std::abs(f0)) +
      1e-300;
    for (unsigned int it = 0; it < 100; ++it)
      {
        const double r = f(T, slope);
        if (std::abs(r) <= tol)
          break;
        (r > 0 ? hi : lo) = T;
        double next       = T - r / slope;
        if (!(next > lo && next < hi))
          next = 0.5 * (lo + hi);
        if (hi - lo < 1e-12 * std::abs(T))
          break;
        T = next;
      }
    return T;
  }

  template <int dim>
  void
  HeatTransfer<dim>::take_point_enthalpy(
    const std::vector<std::pair<std::uint32_t, double>> &mean_e)
  {
    // Each listed cell's metal gets the mean specific enthalpy e (J/kg,
    // e(T) = C(T) + L_m gamma(T)) of its points: T from e(T) = mean, the
    // same enthalpy relation as the phase-change iteration (a = 1: the gas
    // part of a partly filled cell is not carried by points).
    const double rho = mat.density;
    for (const auto &[idx, e] : mean_e)
      {
        if (alpha[idx] <= 0)
          continue;
        const double Tc = T[idx];
        const double dH = rho * (e - specific_enthalpy(Tc));
        set_cell_temperature(
          idx,
          solve_cell(
            1., 0., Tc, mat.liquid_fraction(Tc), 0., dH, 0., true, Tc));
      }
    update_ghosts();
  }

  template <int dim>
  double
  HeatTransfer<dim>::specific_enthalpy(const double T_cell) const
  {
    return mat.specific_heat.antiderivative(T_cell) +
           mat.latent_heat_fusion * mat.liquid_fraction(T_cell);
  }

  template <int dim>
  double
  HeatTransfer<dim>::stored_enthalpy() const
  {
    const double Tref = prm.reference_temperature;
    const double V    = std::pow(grid.h(), dim);
    double       H    = 0;
    for (const auto idx : grid.owned_cells())
      {
        const double a = alpha[idx];
        if (a <= 0)
          continue;
        const double m = mass[idx];
        H += enthalpy_density(m, 1 - a, T[idx]) -
             enthalpy_density(m, 1 - a, Tref) +
             m * mat.density * mat.latent_heat_fusion *
               (gamma[idx] - mat.liquid_fraction(T[idx]));
      }
    return Utilities::MPI::sum(H * V, grid.communicator());
  }

  template <int dim>
  typename HeatTransfer<dim>::EnergyBudget
  HeatTransfer<dim>::energy_budget() const
  {
    const double local[8] = {budget.laser,
                             budget.evaporation,
                             budget.convection,
                             budget.radiation,
                             budget.boundary,
                             budget.advection,
                             budget.laser_incident,
                             budget.laser_escaped};
    double       global[8];
    Utilities::MPI::sum(ArrayView<const double>(local, 8),
                        grid.communicator(),
                        ArrayView<double>(global, 8));
    return {global[0],
            global[1],
            global[2],
            global[3],
            global[4],
            global[5],
            global[6],
            global[7]};
  }

  template <int dim>
  double
  HeatTransfer<dim>::total_losses() const
  {
    const auto e = energy_budget();
    return e.evaporation + e.convection + e.radiation;
  }

  template <int dim>
  void
  HeatTransfer<dim>::save_state(StateWriter &out) const
  {
    save_cell_fields(out, grid, {&T, &T_new, &gamma, &alpha});
    out.put(budget);
    out.put(T_max);
    out.put(dt_stable_next);
  }

  template <int dim>
  void
  HeatTransfer<dim>::load_state(std::vector<StateReader> &parts)
  {
    std::vector<double> a = grid.make_field(0.);
    load_cell_fields(parts, grid, {&T, &T_new, &gamma, &a});
    // The energy accounts are sums per rank: on as many ranks as wrote
    // them each takes its own (bit-identical totals), else rank 0 takes
    // the total.
    const unsigned int rank =
      Utilities::MPI::this_mpi_process(grid.communicator());
    const bool same =
      parts.size() == Utilities::MPI::n_mpi_processes(grid.communicator());
    budget = EnergyBudget();
    for (std::size_t r = 0; r < parts.size(); ++r)
      {
        const auto b = parts[r].get<EnergyBudget>();
        if ((same && r == rank) || (!same && rank == 0))
          {
            budget.laser += b.laser;
            budget.evaporation += b.evaporation;
            budget.convection += b.convection;
            budget.radiation += b.radiation;
            budget.boundary += b.boundary;
            budget.advection += b.advection;
            budget.laser_incident += b.laser_incident;
            budget.laser_escaped += b.laser_escaped;
          }
        const double Tmax = parts[r].get<double>();
        const double dts  = parts[r].get<double>();
        if (r == 0)
          {
            T_max          = Tmax;
            dt_stable_next = dts;
          }
      }
    const double Tmax = T_max;
    set_metal_fraction(a);
    T_max = Tmax;
  }

  template <int dim>
  void
  HeatTransfer<dim>::set_temperature_floor()
  {
    double lowest = std::numeric_limits<double>::max();
    for (const auto idx : grid.owned_cells())
      if (alpha[idx] > 0)
        lowest = std::min(lowest, T[idx]);
    // Each rank holds only the fixed faces of its own cells: reduce after.
    for (const auto &f : fixed_faces)
      lowest = std::min(lowest, f.value);
    T_floor = std::min(Utilities::MPI::min(lowest, grid.communicator()),
                       prm.reference_temperature);
  }

  template <int dim>
  void
  HeatTransfer<dim>::check_temperature_floor(const double T_min,
                                             const double dt,
                                             const double time) const
  {
    // Round-off and the enthalpy iteration's tolerance stay far inside
    // this margin; the unstable checkerboard of a step twice the limit
    // falls below it by kelvins within a few steps.
    const double margin = 1e-6 * std::max(1., std::abs(T_floor));
    if (!(T_min < T_floor - margin))
      return;
    Point<dim> where;
    bool       found  = false;
    double     lowest = std::numeric_limits<double>::max();
    for (const auto idx : grid.owned_cells())
      if (alpha[idx] > 0 && T[idx] < lowest)
        lowest = T[idx], where = grid.cell_center(idx);
    // The rank that holds the global minimum tells the others.
    found = lowest <= T_min;
    share_location(found, where, grid.communicator());
    throw CollectiveError(
      "The temperature step broke the discrete maximum principle at time " +
      num(time + dt) + " s (step size " + num(dt) + " s): the cell at " +
      location_text(where) + " m fell to " + num(T_min) + " K, below " +
      num(T_floor) +
      " K, the lowest initial, fixed-face or reference "
      "temperature, which no stable step can undershoot. The step exceeds "
      "the stable limit of the explicit temperature step (an unstable step "
      "can stay finite: the latent heat clamps it into a wrong "
      "checkerboard). Use a smaller 'Time stepping/Safety factor' or "
      "'Time stepping/Time step'.");
  }

  template class HeatTransfer<2>;
  template class HeatTransfer<3>;
} // namespace femp
