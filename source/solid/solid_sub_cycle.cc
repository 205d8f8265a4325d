// femp: the solid step (paper eqs. 5-17, doc/method.md, "Solid" and "Macro time
// step"): MPM and FE coupled at the transition nodes through the
// background-grid nodes, with sub-cycling against the temperature step; see
// solid_sub_cycle.h.
#include <deal.II/base/mpi.h>
#include <deal.II/base/utilities.h>

#include <femp/base/collective_error.h>
#include <femp/base/error_location.h>
#include <femp/base/input_checks.h>
#include <femp/base/parameter_table.h>
#include <femp/base/progress_watchdog.h>
#include <femp/grid/cell_state.h>
#include <femp/solid/fe_zone_depth.h>
#include <femp/solid/saved_fe_zone.h>
#include <femp/solid/solid_sub_cycle.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <sstream>
#include <unordered_map>

namespace femp
{
  namespace
  {
    const char *face_names[6] = {"x-", "x+", "y-", "y+", "z-", "z+"};

    std::vector<std::string>
    parse_faces(const std::string &text,
                const std::string &parameter,
                const int          dim)
    {
      std::vector<std::string> faces;
      for (auto f : Utilities::split_string_list(text, ','))
        {
          f = Utilities::trim(f);
          if (f.empty())
            continue;
          bool ok = false;
          for (int i = 0; i < 2 * dim; ++i)
            ok = ok || f == face_names[i];
          require(
            ok,
            parameter,
            f,
            dim == 2 ?
              "it must be a comma-separated list of faces x-, x+, y-, y+" :
              "it must be a comma-separated list of faces x-, x+, "
              "y-, y+, "
              "z-, z+");
          faces.push_back(f);
        }
      return faces;
    }
  } // namespace

  template <int dim>
  void
  SolidSubCycle<dim>::Parameters::add_parameters(ParameterTable &table)
  {
    ParameterHandler &prm = table.handler();
    table.enter_subsection("Solid");
    table.add("Time step",
              time_step,
              Patterns::Double(0.),
              "Solid step, s; 0 chooses the safety factor times the "
              "elastic limit h / (sqrt(dim) c), c = sqrt(M / (s rho)) "
              "with the largest P-wave modulus M of the E(T) table and "
              "the mass-scaling factor s. A step above the limit is "
              "refused. Range [0, inf).");
    table.add("Safety factor",
              safety_factor,
              Patterns::Double(0., 1.),
              "Courant number C of the automatic solid step, "
              "dimensionless: the step is C times the elastic limit "
              "(see 'Time step'). With material points the stresses "
              "depend on C and the mass-scaling factor s through "
              "sqrt(s) / C (the transfer loss per unit time; "
              "doc/speed_accuracy.md). Range (0, 1].");
    table.add("Safety factor after solidification",
              safety_factor_solidified,
              Patterns::Double(0., 1.),
              "With the melt flow only: the Courant number of the "
              "automatic solid step once the laser's path has ended "
              "and the workpiece has solidified (the metal attached "
              "to the substrate below the solidus; detached spatter "
              "may still be liquid). At that "
              "moment the mass-scaling factor s is multiplied by "
              "(this / Safety factor)^2, which keeps sqrt(s) / C and "
              "with it the stresses (see 'Safety factor'), and the "
              "solid step grows by (this / Safety factor)^2 (C "
              "times sqrt(s)), and 'Small "
              "mass cutoff' by (this / Safety factor)^2 (light nodes "
              "are stable only above a mass fraction ~ C^2); the "
              "cooling that follows costs that much fewer solid "
              "steps. 0 "
              "(default) keeps 'Safety factor' to the end. Range 0 "
              "or [Safety factor, 1]; needs 'Time step = 0' and "
              "'Mass scaling = fixed' (doc/solid.md \"Cooling after "
              "the workpiece has solidified\").");
    table.add("Mass scaling factor",
              mass_scaling,
              Patterns::Double(1.),
              "Factor s >= 1 on the inertial mass of points and FE "
              "nodes (gravity keeps the true mass): the stable step "
              "grows by sqrt(s). Only for quasi-static scenes: watch "
              "the column kinetic_to_elastic (K / U_el) of the energy "
              "file, which stays below about 1e-3 in a quasi-static "
              "run (doc/speed_accuracy.md, section 1). With 'Mass "
              "scaling = adaptive' the starting factor, which must "
              "lie in [Minimum factor, Maximum factor]. Range [1, "
              "inf).");
    table.add("Mass scaling",
              adaptive_scaling,
              {{false, "fixed"}, {true, "adaptive"}},
              "fixed: the inertial mass is scaled by 'Mass scaling "
              "factor' throughout. adaptive: after every temperature "
              "step in which the solid stepped, the factor s is set "
              "from the ratio r = K / U_el of the mean kinetic energy "
              "of those solid steps to the stored elastic energy "
              "U_el = sum V sigma : C(T)^-1 : sigma / 2 (points and "
              "elements): s_new = s r_max / r, at most 2 s, rounded "
              "down to a power of 2^(1/4) and limited to [Minimum "
              "factor, Maximum factor]; velocities are kept, the "
              "solid step follows sqrt(s) and the kinetic energy "
              "jump is booked in the energy file (doc/speed_accuracy.md, "
              "section 3). Needs 'Time step = 0'.");
    table.add("Mass scaling after solidification",
              adaptive_after_solidification,
              {{false, "fixed"}, {true, "adaptive"}},
              "With the melt flow only. fixed: the factor stays as it is "
              "(or as 'Safety factor after solidification' sets it). "
              "adaptive: quasi-static cooling. Once the laser's path has "
              "ended and the workpiece has solidified (the moment of "
              "'Safety factor after solidification', after its switch if "
              "set), the adaptive controller of 'Mass scaling = adaptive' "
              "takes over from the factor in use: after every temperature "
              "step in which the solid stepped the factor follows K / U_el "
              "to 'Adaptive mass scaling/Maximum kinetic energy ratio', at "
              "most doubling per step, within [the factor at the switch, "
              "'Adaptive mass scaling/Maximum factor after "
              "solidification'], and the solid step grows with its square "
              "root as the cooling slows. Needs 'Time step = 0' and 'Mass "
              "scaling = fixed' (doc/solid.md \"Quasi-static cooling\").");
    table.enter_subsection("Adaptive mass scaling");
    table.add("Maximum kinetic energy ratio",
              max_kinetic_ratio,
              Patterns::Double(),
              "Target r_max of the ratio of kinetic to stored elastic "
              "energy K / U_el of the solid (dimensionless); used "
              "with 'Mass scaling = adaptive'. Range (0, 1].");
    table.add("Minimum factor",
              min_factor,
              Patterns::Double(),
              "Smallest mass-scaling factor of the adaptive "
              "controller (dimensionless); range [1, Maximum "
              "factor].");
    table.add("Maximum factor",
              max_factor,
              Patterns::Double(),
              "Largest mass-scaling factor of the adaptive "
              "controller (dimensionless); range [Minimum factor, "
              "1e12].");
    table.add("Maximum factor after solidification",
              max_factor_solidified,
              Patterns::Double(),
              "Largest mass-scaling factor of the controller with 'Mass "
              "scaling after solidification = adaptive' "
              "(dimensionless); range [the factor at the switch, 1e12]: "
              "at least 'Mass scaling factor' times ('Safety factor "
              "after solidification' / 'Safety factor')^2 when that is "
              "set.");
    table.add("Finite-element damping after solidification",
              fe_damping_solidified,
              Patterns::Double(),
              "With 'Mass scaling after solidification = adaptive': the "
              "fraction beta of their velocity that the nodes of the "
              "finite-element zone (not its transition nodes) lose at "
              "every solid step after the switch (dimensionless); range "
              "[0, 0.1]; 0: none. Nothing else damps a vibration of the "
              "zone, and a change of the factor at kept velocities scales "
              "its kinetic energy with the factor, so that the controller "
              "can hold the factor low; the kinetic energy taken out is "
              "booked in the energy file with transfer_dissipation "
              "(doc/solid.md \"Quasi-static cooling\").");
    table.add("Finite-element nodes at a raise after solidification",
              fe_momentum_at_raise,
              {{false, "velocity kept"}, {true, "momentum kept"}},
              "With 'Mass scaling after solidification = adaptive': what "
              "the nodes of the finite-element zone (not its transition "
              "nodes) keep when the controller raises the factor from s "
              "to s_new after the switch. 'velocity kept' (default): "
              "their kinetic energy grows by s_new / s, as that of the "
              "points. 'momentum kept': their velocities are divided by "
              "s_new / s, so that their kinetic energy falls by that "
              "ratio and the raises do not feed a vibration of the zone "
              "(a lowering keeps the velocities either way); the kinetic "
              "energy taken out is booked in the energy file with "
              "transfer_dissipation (doc/solid.md \"Quasi-static "
              "cooling\").");
    table.leave_subsection();
    table.add("Light nodes",
              light_nodes,
              {{LightNodes::mass_floor, "mass floor"},
               {LightNodes::no_force, "no force"}},
              "Used only with the melt flow (Physics/Melt flow and "
              "Solid stress both true): how the solid's grid update "
              "treats nodes of small mass, which appear round solid "
              "fragments that solidified where the flow left them "
              "(a point near a cell face gives the opposite face's "
              "nodes a tiny mass but a full shape-function gradient, "
              "and their explicit update is unstable). 'mass floor': "
              "each node is accelerated as if its mass were at least "
              "C^2 / (4 dim) times the row sum of its stiffness over "
              "c^2 (C the safety factor in use), the mass at which "
              "the solid step is stable for it; the work of the part "
              "of the force that it does not take is booked in the "
              "energy file as withheld_work. 'no force': nodes below "
              "'Small mass cutoff' take no force and keep their "
              "velocity (fragments held by heavier nodes are then "
              "strained without bound). doc/solid.md \"Small node "
              "masses\".");
    table.add("Small mass cutoff",
              small_mass_cutoff,
              Patterns::Double(),
              "Used only with the melt flow and 'Light nodes = no "
              "force': grid nodes whose inertial mass is below this "
              "fraction of a full cell's node "
              "(rho h^dim / 2^dim times the mass scaling) take no "
              "force in the solid's grid update (the work the force "
              "would have done is booked in the energy file as "
              "withheld_work), so that points left by the flow near "
              "a cell face (solidified fragments) do not make the "
              "explicit update unstable; 0 is off. "
              "Dimensionless, range [0, 1) (doc/solid.md \"Small "
              "node masses\").");
    if (table.declaring())
      prm.declare_entry(
        "Fixed faces",
        "",
        Patterns::Anything(),
        "Domain faces whose grid nodes are fixed (zero "
        "velocity): a comma-separated list of x-, x+, y-, y+, "
        "z-, z+; empty for none. Faces not listed here or under "
        "'Roller faces' are traction-free.");
    if (table.declaring())
      prm.declare_entry("Roller faces",
                        "",
                        Patterns::Anything(),
                        "Domain faces whose grid nodes cannot move normal to "
                        "the face (rollers); same format as 'Fixed faces'.");
    table.add("Energy file",
              energy_file,
              Patterns::Anything(),
              "CSV file (in the output directory) with the solid "
              "energies after every solid step: external work, stress "
              "work, kinetic, hourglass, balance, kinetic/internal "
              "ratio, hourglass-mode energy, and the booked "
              "exchanges: MPM transfer dissipation, kinetic energy "
              "removed by melting and added by solidification, and "
              "the re-map work of the MUSL update (J, 2D: J/m; "
              "doc/solid.md), then the mass-scaling factor, the ratio "
              "K / U_el of the kinetic to the stored elastic energy "
              "(at the end of the last temperature step) and the "
              "kinetic energy booked for changes of the factor "
              "(adaptive mass scaling); empty for none.");
    table.add("Row interval",
              row_interval,
              Patterns::Double(0),
              "Simulated time between two rows of the 'Energy file' "
              "and the 'Probe file', s; range [0, inf): a row is "
              "written after the solid step that reaches or passes "
              "each multiple of it; 0 writes a row after every solid "
              "step. The energy accounts are summed at every step "
              "either way; a row costs one pass over the FE elements "
              "(the hourglass energy) and global sums, which long "
              "runs with millions of solid steps need not pay each "
              "step.");
    table.add("Probe file",
              probe_file,
              Patterns::Anything(),
              "CSV file (in the output directory) with sigma_xx (Pa) "
              "and T (K) at the probe points after every solid step.");
    if (table.declaring())
      prm.declare_entry("Probe points",
                        "",
                        Patterns::Anything(),
                        "Points 'x,y[,z]; x,y[,z]; ...' (m) whose cell stress "
                        "and temperature are written to the probe file; empty "
                        "for none.");
    table.leave_subsection();
  }

  template <int dim>
  void
  SolidSubCycle<dim>::Parameters::declare_parameters(ParameterHandler &prm)
  {
    Parameters     defaults;
    ParameterTable table(prm, ParameterTable::Mode::declare);
    defaults.add_parameters(table);
  }

  template <int dim>
  void
  SolidSubCycle<dim>::Parameters::parse_parameters(ParameterHandler &prm)
  {
    ParameterTable table(prm, ParameterTable::Mode::parse);
    add_parameters(table);
    prm.enter_subsection("Solid");
    prm.enter_subsection("Adaptive mass scaling");
    prm.leave_subsection();
    fixed_faces = parse_faces(prm.get("Fixed faces"), "Solid/Fixed faces", dim);
    roller_faces =
      parse_faces(prm.get("Roller faces"), "Solid/Roller faces", dim);
    probes.clear();
    for (const auto &s :
         Utilities::split_string_list(prm.get("Probe points"), ';'))
      if (!Utilities::trim(s).empty())
        probes.push_back(parse_point<dim>(s, "Solid/Probe points"));
    prm.leave_subsection();
    require(safety_factor > 0,
            "Solid/Safety factor",
            safety_factor,
            "it must lie in (0, 1]");
    if (safety_factor_solidified != 0)
      {
        const std::string name = "Solid/Safety factor after solidification";
        require(safety_factor_solidified >= safety_factor &&
                  safety_factor_solidified <= 1,
                name,
                safety_factor_solidified,
                "it must be 0 (keep 'Safety factor') or lie in [Safety "
                "factor, 1] = [" +
                  num(safety_factor) + ", 1]");
        require(time_step == 0,
                name,
                safety_factor_solidified,
                "it sets the automatic step: it needs 'Solid/Time step = 0' "
                "(now " +
                  num(time_step) + " s)");
        require(!adaptive_scaling,
                name,
                safety_factor_solidified,
                "it changes the mass-scaling factor itself: it needs "
                "'Solid/Mass scaling = fixed', not adaptive");
      }
    require(small_mass_cutoff >= 0 && small_mass_cutoff < 1,
            "Solid/Small mass cutoff",
            small_mass_cutoff,
            "it must lie in [0, 1) (a fraction of a full node's mass)");
    const std::string ams = "Solid/Adaptive mass scaling/";
    require(max_kinetic_ratio > 0 && max_kinetic_ratio <= 1,
            ams + "Maximum kinetic energy ratio",
            max_kinetic_ratio,
            "it must lie in (0, 1]");
    require(min_factor >= 1,
            ams + "Minimum factor",
            min_factor,
            "it must lie in [1, Maximum factor]");
    require(max_factor >= min_factor && max_factor <= 1e12,
            ams + "Maximum factor",
            max_factor,
            "it must lie in [Minimum factor, 1e12] (Minimum factor = " +
              num(min_factor) + ")");
    if (adaptive_after_solidification)
      {
        const std::string name = "Solid/Mass scaling after solidification";
        require(!adaptive_scaling,
                name,
                "adaptive",
                "with 'Solid/Mass scaling = adaptive' the controller runs "
                "from the start: it needs 'Solid/Mass scaling = fixed'");
        require(time_step == 0,
                name,
                "adaptive",
                "the step follows the factor: it needs 'Solid/Time step = 0' "
                "(now " +
                  num(time_step) + " s)");
        const double c        = safety_factor_solidified > safety_factor ?
                                  safety_factor_solidified / safety_factor :
                                  1.;
        const double s_switch = mass_scaling * c * c;
        require(max_factor_solidified >= s_switch * (1 - 1e-12) &&
                  max_factor_solidified <= 1e12,
                ams + "Maximum factor after solidification",
                max_factor_solidified,
                "it must lie in [the factor at the switch, 1e12] = [" +
                  num(s_switch) +
                  ", 1e12] ('Mass scaling factor' times ('Safety factor "
                  "after solidification' / 'Safety factor')^2 when that "
                  "is set)");
      }
    require(fe_damping_solidified >= 0 && fe_damping_solidified <= 0.1,
            ams + "Finite-element damping after solidification",
            fe_damping_solidified,
            "it must lie in [0, 0.1]");
    require(!fe_momentum_at_raise || adaptive_after_solidification,
            ams + "Finite-element nodes at a raise after solidification",
            "momentum kept",
            "it acts at the raises of the quasi-static cooling: it needs "
            "'Solid/Mass scaling after solidification = adaptive'");
    if (adaptive_scaling)
      {
        require(mass_scaling >= min_factor && mass_scaling <= max_factor,
                "Solid/Mass scaling factor",
                mass_scaling,
                "with 'Solid/Mass scaling = adaptive' the starting factor "
                "must lie in [Minimum factor, Maximum factor] = [" +
                  num(min_factor) + ", " + num(max_factor) + "]");
        require(time_step == 0,
                "Solid/Time step",
                time_step,
                "with 'Solid/Mass scaling = adaptive' the step follows the "
                "factor: it must be 0 (automatic)");
      }
  }

  template <int dim>
  double
  SolidSubCycle<dim>::Parameters::stable_limit(const SolidMaterial &m,
                                               const double         h,
                                               const double         s) const
  {
    const double c  = std::sqrt(m.max_p_wave_modulus() /
                               ((s > 0 ? s : mass_scaling) * m.density()));
    const double b1 = m.bulk_viscosity;
    return h / (std::sqrt(double(dim)) * c) * (std::sqrt(1 + b1 * b1) - b1);
  }

  template <int dim>
  void
  SolidSubCycle<dim>::Parameters::check(
    const SolidMaterial                            &m,
    const typename BackgroundGrid<dim>::Parameters &g) const
  {
    const double       limit = stable_limit(m, g.cell_size);
    std::ostringstream s;
    s << "it exceeds the elastic stable limit h / (sqrt(dim) c) (sqrt(1 + "
         "b1^2) "
         "- b1) = "
      << limit << " s (h = " << g.cell_size << " m, largest P-wave modulus "
      << m.max_p_wave_modulus() << " Pa, density " << m.density()
      << " kg/m^3, mass scaling " << mass_scaling
      << "); use 0 (automatic) or a smaller step";
    require(time_step <= limit, "Solid/Time step", time_step, s.str());
    for (const auto &x : probes)
      for (int d = 0; d < dim; ++d)
        require(x[d] >= g.lower_corner[d] && x[d] <= g.upper_corner[d],
                "Solid/Probe points",
                x,
                "every point must lie in the domain");
  }

  template <int dim>
  SolidSubCycle<dim>::SolidSubCycle(
    const Parameters                         &prm,
    const typename SolidFEM<dim>::Parameters &fem_prm,
    const SolidMaterial                      &material,
    const BackgroundGrid<dim>                &grid,
    MaterialPoints<dim>                      &points)
      : prm(prm)
      , mat(material)
      , grid(grid)
      , comm(grid.communicator())
      , mpm(grid, material, points)
      , fem(fem_prm.enabled ?
              std::make_unique<SolidFEM<dim>>(fem_prm, grid, material) :
              nullptr)
      , region(grid)
  {
    scaling = MassScalingController(prm.mass_scaling,
                                    prm.max_kinetic_ratio,
                                    prm.min_factor,
                                    prm.max_factor);
    safety  = prm.safety_factor;
  }

  template <int dim>
  void
  SolidSubCycle<dim>::initialize(const std::vector<double> &T,
                                 const std::string         &directory)
  {
    nodes.resize(grid.n_local_nodes());
    if (mass_floor)
      nodes.stiffness.assign(grid.n_local_nodes(), 0.);
    safety               = prm.safety_factor;
    cooling_step         = false;
    adaptive_from        = 0;
    dt_solid             = prm.time_step > 0 ? prm.time_step :
                                               safety * prm.stable_limit(mat, grid.h());
    const auto face_bits = set_boundary_flags();
    scaling.reset();
    if (fem)
      fem->setup(fe_setup_factor > 0 ? fe_setup_factor : scaling.factor(),
                 face_bits,
                 prm.gravity,
                 T);
    else
      no_fe_zone.assign(grid.n_local(), 0);
    find_active_nodes();

    T_solid = T;
    T_prev  = T;
    T_next  = T;
    t_solid = t_prev = 0;
    steps            = 0;
    mpm.gather(zone_mask(), scaling.factor());
    const double K0 = Utilities::MPI::sum(mpm.kinetic_energy() +
                                            (fem ? fem->kinetic_energy() : 0.),
                                          comm);
    n_points_global = Utilities::MPI::sum(double(mpm.n_points()), comm);
    ledger.start(K0, Utilities::MPI::sum(mpm.kinetic_energy(), comm));

    rebuild_live(nullptr, 0.);
    open_output_files(directory);
  }

  template <int dim>
  std::array<std::uint8_t, 2 * dim>
  SolidSubCycle<dim>::set_boundary_flags()
  {
    // Boundary flags of the nodes of owned cells.
    constrained.assign(grid.n_local_nodes(), 0);
    const auto &ns = grid.node_strides();
    const auto &lo = grid.box_lower();
    for (const auto n : grid.owned_cell_nodes())
      {
        std::array<int, dim> ijk;
        std::size_t          r = n;
        for (int d = dim - 1; d >= 0; --d)
          {
            ijk[d] = lo[d] + static_cast<int>(r / ns[d]);
            r %= ns[d];
          }
        for (int f = 0; f < 2 * dim; ++f)
          {
            const int  d = f / 2;
            const bool on =
              (f % 2 == 0) ? ijk[d] == 0 : ijk[d] == int(grid.n_cells()[d]);
            if (!on)
              continue;
            for (const auto &name : prm.fixed_faces)
              if (name == face_names[f])
                constrained[n] |= (1u << dim) - 1;
            for (const auto &name : prm.roller_faces)
              if (name == face_names[f])
                constrained[n] |= 1u << d;
          }
      }
    // FE zone; velocity components fixed per domain face.
    std::array<std::uint8_t, 2 * dim> face_bits{};
    for (int f = 0; f < 2 * dim; ++f)
      {
        for (const auto &name : prm.fixed_faces)
          if (name == face_names[f])
            face_bits[f] |= (1u << dim) - 1;
        for (const auto &name : prm.roller_faces)
          if (name == face_names[f])
            face_bits[f] |= 1u << (f / 2);
      }
    return face_bits;
  }

  template <int dim>
  void
  SolidSubCycle<dim>::find_active_nodes()
  {
    // The transition nodes among the nodes of owned cells, then the nodes
    // and cells a step visits (solid_active_region.h).
    const auto               &lo = grid.box_lower();
    std::vector<std::uint8_t> owned_node(grid.n_local_nodes(), 0);
    for (const auto n : grid.owned_cell_nodes())
      owned_node[n] = 1;
    grid_transition.clear();
    const auto &size = grid.box_size();
    for (std::size_t t = 0; t < n_transition(); ++t)
      {
        const auto &ijk = fem->transition_node(t);
        bool        in  = true;
        for (int d = 0; d < dim; ++d)
          in = in && ijk[d] >= lo[d] && ijk[d] <= lo[d] + size[d];
        if (!in)
          continue;
        const std::size_t n = grid.local_node_index(ijk);
        if (!owned_node[n])
          continue;
        grid_transition.emplace_back(t, n);
      }
    tr_buffer.assign(SolidFEM<dim>::tr_width * n_transition(), 0.);
    tr_fgrid.assign(dim * n_transition(), 0.);
    region.setup(zone_mask(), grid_transition, prm.probes, comm);
  }

  template <int dim>
  void
  SolidSubCycle<dim>::rebuild_live(const std::vector<double> *T, const double w)
  {
    region.rebuild(
      mpm.nodes_reached(),
      mpm.cells_reached(),
      [&](const std::uint32_t n) {
        nodes.mass[n] = 0;
        for (int d = 0; d < dim; ++d)
          nodes.momentum[d][n] = nodes.force[d][n] = nodes.velocity[d][n] = 0;
      },
      [&](const std::uint32_t c) {
        if (T)
          T_next[c] = T_prev[c] + w * ((*T)[c] - T_prev[c]);
      });
    regathered = false;
  }

  template <int dim>
  void
  SolidSubCycle<dim>::extend_live(const std::vector<double> &T, const double w)
  {
    region.extend(mpm.nodes_reached(),
                  mpm.cells_reached(),
                  [&](const std::uint32_t c) {
                    T_next[c] = T_prev[c] + w * (T[c] - T_prev[c]);
                  });
  }

  template <int dim>
  void
  SolidSubCycle<dim>::open_output_files(const std::string &directory)
  {
    csv_directory = directory;
    if (!directory.empty() && Utilities::MPI::this_mpi_process(comm) == 0)
      {
        if (!prm.energy_file.empty())
          {
            energy_out = std::make_unique<std::ofstream>(directory + "/" +
                                                         prm.energy_file);
            AssertThrow(*energy_out,
                        ExcMessage("cannot write " + directory + "/" +
                                   prm.energy_file));
            *energy_out
              << "time,step,external_work,internal_work,kinetic,"
                 "hourglass,balance,kinetic_to_internal,hourglass_mode,"
                 "transfer_dissipation,removed_by_melting,"
                 "added_by_solidification,remap_work,mass_scaling,"
                 "kinetic_to_elastic,mass_scaling_kinetic_jump,"
                 "withheld_work\n";
          }
        if (!prm.probe_file.empty() && !prm.probes.empty())
          {
            probe_out =
              std::make_unique<std::ofstream>(directory + "/" + prm.probe_file);
            AssertThrow(*probe_out,
                        ExcMessage("cannot write " + directory + "/" +
                                   prm.probe_file));
            *probe_out << "time";
            for (std::size_t i = 0; i < prm.probes.size(); ++i)
              *probe_out << ",sigma_xx_" << i << ",T_" << i;
            *probe_out << "\n";
          }
      }
  }

  template <int dim>
  void
  SolidSubCycle<dim>::advance(const double               t,
                              const std::vector<double> &T,
                              const bool                 final,
                              const NodalForces         *external_forces)
  {
    check_fe_zone_solid(T, t);
    if (fem)
      {
        fem->new_temperatures(T);
        fem->set_external_forces(external_forces);
        // Quasi-static cooling: the zone's nodes damped after the switch.
        fem->set_node_damping(adaptive_from > 0 ? prm.fe_damping_solidified :
                                                  0.);
      }
    // Same decision on every rank (gather_points() is collective).
    const bool gathered = t_solid < t * (1 - 1e-12) &&
                          (final || t_solid + dt_solid <= t * (1 + 1e-12));
    if (gathered)
      {
        gather_points();
        rebuild_live(nullptr, 0.);
      }
    progress::phase("solid sub-steps");
    while (t_solid < t * (1 - 1e-12))
      {
        double t_next = t_solid + dt_solid;
        // A sub-step too small to move the time on would loop forever
        // (collective: dt_solid and the times are the same on every rank).
        if (!(t_next > t_solid))
          throw CollectiveError(
            InputError(prm.time_step > 0 ? "Solid/Time step" :
                                           "Solid/Material/Young's modulus",
                       num(prm.time_step > 0 ? prm.time_step :
                                               mat.max_p_wave_modulus()),
                       "the solid sub-step " + num(dt_solid) +
                         " s makes no progress at t = " + num(t_solid) +
                         " s (it is below the round-off of the time): the "
                         "elastic limit h/(sqrt(dim) c) is far too small "
                         "for this run; check the stiffness, the density "
                         "and their units")
              .what());
        progress::substep(steps + 1, dt_solid);
        if (t_next > t * (1 + 1e-12))
          {
            if (!final)
              break;
            t_next = t;
          }
        // Linear interpolation of the cell temperatures in [t_prev, t].
        const double w = t > t_prev ? (t_next - t_prev) / (t - t_prev) : 1.;
        // (Cells of the FE zone: the elements interpolate their own.) Only
        // the cells that hold points (live_cells): the others follow at
        // the end of the advance.
        for (const auto c : region.live_cells())
          T_next[c] = T_prev[c] + w * (T[c] - T_prev[c]);
        step(t_next - t_solid, w, external_forces);
        // Cells and nodes that points reached in the step (their cells'
        // temperature of this step into T_next).
        if (regathered)
          rebuild_live(&T, w);
        else
          extend_live(T, w);
        last_w = w;
        T_solid.swap(T_next);
        scaling.add_step(ledger.kinetic(), t_next - t_solid);
        const bool row = row_due(t_solid, t_next);
        t_solid        = t_next;
        if (row)
          write_rows();
      }
    if (gathered) // collective
      {
        measure_and_adapt_scaling((prm.adaptive_scaling || adaptive_from > 0) &&
                                  !final);
        mpm.scatter();
      }
    // The temperature of the last step at the cells without points (as if
    // interpolated at every step), for points that solidify there.
    for (const auto c : region.mpm_cells())
      {
        if (gathered && !region.is_live_cell(c))
          T_solid[c] = T_prev[c] + last_w * (T[c] - T_prev[c]);
        T_prev[c] = T[c];
      }
    t_prev = t;
  }

  template <int dim>
  void
  SolidSubCycle<dim>::step(const double       dt,
                           const double       w,
                           const NodalForces *external_forces)
  {
    particles_to_grid(external_forces);                   // 1. P2G
    const double merge_loss = merge_transition_nodes(dt); // 2. transition
    sum_grid_partials();
    // Transfer dissipation, P2G part: point kinetic energy at the start of
    // the step minus that of the points' grid momenta.
    double transfer =
      mpm.kinetic_energy() - grid_point_kinetic(false) + merge_loss;
    const double withheld = update_grid_momentum(dt); // 3. grid update
    // G2P part (completed below): grid kinetic energy of the points' mass
    // after the update (nodes.mass is still the point mass here).
    transfer += grid_point_kinetic(true);
    set_transition_velocities();
    const double ext_power = external_power(external_forces);
    const auto   fe_energy = grid_to_points(dt); // 3., 4. G2P, FE nodes
    if (fem) // kinetic energy the damping of the FE nodes took out
      transfer += fem->damped_energy();
    const auto remap = remap_work_of_step(dt);
    set_grid_velocities();

    // 5. Stresses (eq. 5).
    double work = mpm.update_stresses(nodes, dt, T_solid, T_next);
    if (fem)
      work += fem->update_elements(dt, w);
    ++steps;
    book_energies(dt,
                  ext_power,
                  fe_energy,
                  transfer,
                  work,
                  remap[0],
                  withheld,
                  {{remap[1] + fe_energy[2], remap[2] + fe_energy[3]}});
  }

  template <int dim>
  void
  SolidSubCycle<dim>::particles_to_grid(const NodalForces *external_forces)
  {
    // 1. Mass, momentum and forces of the points to the grid (eqs. 11-13),
    // partial sums of this rank, on the grid nodes of MPM cells.
    for (const auto n : region.live_nodes())
      {
        nodes.mass[n] = 0;
        for (int d = 0; d < dim; ++d)
          nodes.momentum[d][n] = nodes.force[d][n] = 0;
        if (mass_floor)
          nodes.stiffness[n] = 0;
      }
    mpm.p2g(nodes, prm.gravity);
    if (external_forces)
      for (int d = 0; d < dim; ++d)
        for (const auto n : region.live_nodes())
          nodes.force[d][n] += (*external_forces)[d][n];
  }

  template <int dim>
  double
  SolidSubCycle<dim>::merge_transition_nodes(const double dt)
  {
    // 2. Transition nodes (eqs. 14-17): partial grid and FE sums of this
    // rank, summed over all ranks in one reduction; every rank then holds
    // the totals and computes the same grid and FE velocities there.
    constexpr unsigned int W          = SolidFEM<dim>::tr_width;
    double                 merge_loss = 0;
    if (n_transition() > 0)
      {
        std::fill(tr_buffer.begin(), tr_buffer.end(), 0.);
        for (const auto &[t, n] : grid_transition)
          {
            tr_buffer[W * t] += nodes.mass[n];
            for (int d = 0; d < dim; ++d)
              {
                tr_buffer[W * t + 1 + d] += nodes.momentum[d][n];
                tr_buffer[W * t + 1 + dim + d] += nodes.force[d][n];
              }
          }
        fem->add_transition_partials(tr_buffer);
        if (Utilities::MPI::n_mpi_processes(comm) > 1)
          MPI_Allreduce(MPI_IN_PLACE,
                        tr_buffer.data(),
                        tr_buffer.size(),
                        MPI_DOUBLE,
                        MPI_SUM,
                        comm);
        // Merging at the transition nodes (booked with the transfer): the
        // points' grid momentum and the FE node momentum become one
        // velocity, an inelastic exchange that loses 1/2 mu |v_g - v_i|^2,
        // mu = m_g m_FE / (m_g + m_FE). The buffer holds the global sums:
        // counted on the first rank.
        if (Utilities::MPI::this_mpi_process(comm) == 0)
          for (std::size_t t = 0; t < n_transition(); ++t)
            {
              const double mg = tr_buffer[W * t], mf = fem->transition_mass(t);
              if (mg <= 0 || mf <= 0)
                continue;
              for (int d = 0; d < dim; ++d)
                if (!(fem->transition_constraint(t) & (1u << d)))
                  {
                    const double dv = tr_buffer[W * t + 1 + d] / mg -
                                      fem->transition_velocity(t)[d];
                    merge_loss += 0.5 * mg * mf / (mg + mf) * dv * dv;
                  }
            }
        const double *u0 = fem->transition_velocity(0);
        tr_u.assign(u0, u0 + dim * n_transition());
        fem->update_transition(tr_buffer, dt, tr_v, tr_a);
      }
    return merge_loss;
  }

  template <int dim>
  void
  SolidSubCycle<dim>::sum_grid_partials()
  {
    grid.sum_shared_nodes(nodes.mass);
    for (int d = 0; d < dim; ++d)
      {
        grid.sum_shared_nodes(nodes.momentum[d]);
        grid.sum_shared_nodes(nodes.force[d]);
      }
    if (mass_floor)
      grid.sum_shared_nodes(nodes.stiffness);
    // The grid (point) force at the transition nodes, for the re-map work.
    for (const auto &[t, n] : grid_transition)
      for (int d = 0; d < dim; ++d)
        tr_fgrid[dim * t + d] = nodes.force[d][n];
  }

  template <int dim>
  double
  SolidSubCycle<dim>::update_grid_momentum(const double dt)
  {
    // 3. Grid momentum update with boundary conditions; force -> f / m;
    // transition nodes from step 2.
    double withheld = 0;
    // The light-node mass floor (set_mass_floor()): kappa times the
    // node's stiffness row sum.
    const double kappa = mass_floor ? safety * safety / (4. * dim) : 0.;
    for (const auto n : region.live_nodes())
      {
        const double m       = nodes.mass[n];
        const double m_floor = mass_floor ? kappa * nodes.stiffness[n] : 0.;
        for (int d = 0; d < dim; ++d)
          {
            if (m <= 0 || (constrained[n] & (1u << d)))
              {
                nodes.force[d][n] = nodes.momentum[d][n] = 0;
                nodes.velocity[d][n]                     = 0;
                continue;
              }
            if (m < m_floor)
              {
                // A node below its floor is accelerated as if it had that
                // mass: of its force f (internal, external and gravity) it
                // applies the part m / m_floor, while the stress rate of
                // the points around it sees the node's velocity in full.
                // The work of the withheld part over the step, dt (1 - m /
                // m_floor) f (v_start + v_end) / 2 (the mid-step velocity,
                // as the kinetic energy of an explicit update sees a
                // force), is booked (Energies::withheld), each node on the
                // rank that counts it (a transition node, counted_as >= 0,
                // takes the merged update of step 2).
                const double f = nodes.force[d][n], a = f / m_floor;
                if (region.counted_as(n) == -1)
                  withheld += dt * (1 - m / m_floor) * f *
                              (nodes.momentum[d][n] / m + 0.5 * dt * a);
                nodes.momentum[d][n] += dt * m * a;
                nodes.force[d][n]    = a;
                nodes.velocity[d][n] = nodes.momentum[d][n] / m;
                continue;
              }
            if (m < small_mass) // off (0) without the melt flow
              {
                // A node lighter than the cutoff takes no force (internal,
                // external and gravity) and keeps its velocity, while the
                // stress rate of the points around it sees that velocity:
                // the work the withheld force would have done over the
                // step, dt f v (the velocity does not change), is booked
                // (Energies::withheld), each node on the rank that counts
                // it (a transition node, counted_as >= 0, takes the merged
                // update of step 2).
                if (region.counted_as(n) == -1)
                  withheld += dt * nodes.force[d][n] * nodes.momentum[d][n] / m;
                nodes.force[d][n]    = 0;
                nodes.velocity[d][n] = nodes.momentum[d][n] / m;
                continue;
              }
            nodes.momentum[d][n] += dt * nodes.force[d][n];
            nodes.force[d][n] /= m;
            nodes.velocity[d][n] = nodes.momentum[d][n] / m;
          }
      }
    return withheld;
  }

  template <int dim>
  void
  SolidSubCycle<dim>::set_transition_velocities()
  {
    // Transition nodes: merged mass, velocity and acceleration of step 2.
    constexpr unsigned int W = SolidFEM<dim>::tr_width;
    for (const auto &[t, n] : grid_transition)
      {
        nodes.mass[n] = tr_buffer[W * t] + fem->transition_mass(t);
        for (int d = 0; d < dim; ++d)
          {
            nodes.velocity[d][n] = tr_v[dim * t + d];
            nodes.force[d][n]    = tr_a[dim * t + d];
          }
      }
  }

  template <int dim>
  double
  SolidSubCycle<dim>::external_power(const NodalForces *external_forces) const
  {
    double ext_power = 0;
    if (external_forces) // partial forces: the rank sum is the total
      for (int d = 0; d < dim; ++d)
        for (const auto n : region.live_nodes()) // velocity 0 at the others
          ext_power += (*external_forces)[d][n] * nodes.velocity[d][n];
    return ext_power;
  }

  template <int dim>
  std::array<double, 4>
  SolidSubCycle<dim>::grid_to_points(const double dt)
  {
    // 3. and 4. Points and FE nodes (eqs. 15-17), MUSL re-map of the point
    // momenta (in the same loop as G2P), grid velocities.
    for (int d = 0; d < dim; ++d)
      for (const auto n : region.live_nodes())
        nodes.momentum[d][n] = 0;
    mpm.g2p(nodes, dt);
    const std::array<double, 4> fe_energy =
      fem ? fem->update_nodes(dt) : std::array<double, 4>{{0., 0., 0., 0.}};
    for (int d = 0; d < dim; ++d)
      grid.sum_shared_nodes(nodes.momentum[d]);
    for (const auto &[t, n] : grid_transition)
      for (int d = 0; d < dim; ++d)
        nodes.momentum[d][n] +=
          fem->transition_mass(t) * fem->transition_velocity(t)[d];
    return fe_energy;
  }

  template <int dim>
  std::array<double, 3>
  SolidSubCycle<dim>::remap_work_of_step(const double dt) const
  {
    constexpr unsigned int W = SolidFEM<dim>::tr_width;
    // Re-map work (booked, doc/solid.md "Energies"): the nodal forces f_I
    // (= m_I times the acceleration in nodes.force) do the work
    // dt f_I . (v_start + v_end) / 2 on the grid, but the step ends with the
    // re-mapped velocities, and the stress rate sees those: the work of f_I
    // on the velocity that the re-map takes back, dt/2 f_I . (v_I - v_remap),
    // is energy the MUSL update creates (large at nodes with a small share
    // of point mass, whose velocity jumps by dt f/m). Each node counted on
    // one rank.
    // At a transition node the FE elements see the FE velocity, not the
    // re-mapped one: their forces f_FE (without the hourglass part) and the
    // hourglass force f_HG accelerate the merged velocity from v_m to v_I,
    // while the element stress and hourglass rates see v_i = v_I +
    // dt f_HG/m_FE (eq. 17), and the FE velocity of the last step, u, jumps
    // to v_m in the merge. Their work on both jumps,
    // dt/2 (f_FE + f_HG) . (v_I - v_i + v_m - u), is booked here too (the
    // grid force f_g keeps the re-map jump); without it the balance of the
    // elastic shock test was 0.12 (doc/solid.md).
    // In the same loop the sums for the leapfrog's half-step term
    // (SolidEnergies::half_step) of the grid nodes: f_I . v_I and
    // f_I . a_I, a_I = f_I / m_I the acceleration of the update, so that
    // dv_I = dt a_I and v_old = v_I - dv_I (transition nodes with their
    // merged mass, velocity and acceleration).
    double remap_work = 0, fv = 0, fa = 0;
    for (const auto &[n, t] : region.live_counted()) // no mass at the others
      if (nodes.mass[n] > 0)
        for (int d = 0; d < dim; ++d)
          if (!(constrained[n] & (1u << d)))
            {
              const double f  = nodes.mass[n] * nodes.force[d][n];
              const double vI = nodes.velocity[d][n];
              const double vr = nodes.momentum[d][n] / nodes.mass[n];
              fv += f * vI;
              fa += f * nodes.force[d][n];
              if (t < 0)
                {
                  remap_work += 0.5 * dt * f * (vI - vr);
                  continue;
                }
              const double *b  = &tr_buffer[W * t];
              const double  fg = tr_fgrid[dim * t + d];
              const double  mf = fem->transition_mass(t);
              const double  u  = tr_u[dim * t + d];
              const double  vm = (b[1 + d] + mf * u) / (b[0] + mf);
              remap_work += 0.5 * dt *
                            (fg * (vI - vr) +
                             (f - fg + b[1 + 2 * dim + d]) *
                               (vI - fem->transition_velocity(t)[d] + vm - u));
            }
    // sum m v_old . dv and sum m dv . dv (SolidFEM::update_nodes()).
    return {{remap_work, dt * (fv - dt * fa), dt * dt * fa}};
  }

  template <int dim>
  void
  SolidSubCycle<dim>::set_grid_velocities()
  {
    for (const auto n : region.live_nodes())
      for (int d = 0; d < dim; ++d)
        nodes.velocity[d][n] =
          (nodes.mass[n] > 0 && !(constrained[n] & (1u << d))) ?
            nodes.momentum[d][n] / nodes.mass[n] :
            0.;
  }

  template <int dim>
  void
  SolidSubCycle<dim>::book_energies(const double                 dt,
                                    const double                 ext_power,
                                    const std::array<double, 4> &fe_energy,
                                    const double                 transfer,
                                    const double                 work,
                                    const double                 remap_work,
                                    const double                 withheld,
                                    const std::array<double, 2> &half_step)
  {
    // Energies and the blow-up check (one reduction per step).
    const double local_ext =
      ext_power + mpm.gravity_power(prm.gravity) + fe_energy[1];
    // sums[8]: a point volume or element Jacobian <= 0 on this rank.
    double sums[12] = {
      mpm.kinetic_energy(),
      work,
      dt * local_ext,
      mpm.point_lost() ? 1. : 0.,
      double(mpm.n_left_rank()),
      transfer,
      fe_energy[0],
      remap_work,
      mpm.volume_collapsed() || (fem && fem->element_failed()) ? 1. : 0.,
      withheld,
      half_step[0],
      half_step[1]};
    Utilities::MPI::sum(ArrayView<const double>(sums, 12),
                        comm,
                        ArrayView<double>(sums, 12));
    ledger.book_step(sums[0],
                     sums[6],
                     sums[1],
                     sums[2],
                     sums[5],
                     sums[7],
                     sums[9],
                     dt,
                     sums[10],
                     sums[11]);
    const bool blown = !ledger.finite();
    if (!blown && sums[8] > 0)
      stop_inverted(dt);
    if (blown || sums[3] > 0)
      {
        Point<dim> where;
        Point<1>   depth(-1.);
        bool       found = false;
        if (blown)
          found =
            mpm.find_non_finite(where) || (fem && fem->find_non_finite(where));
        else if (mpm.point_lost())
          where = mpm.escaped_point(), depth[0] = mpm.escaped_depth(),
          found = true;
        share_location(found, where, comm);
        share_location(found, depth, comm);
        std::ostringstream s;
        s << "solid: ";
        if (blown)
          s << "the solution became non-finite (unstable: check "
               "'Solid/Time step' and 'Solid/Hourglass coefficient')";
        else if (depth[0] < 0)
          s << "a material point left the domain";
        else
          {
            // Deeper than a point that crossed a face of the zone and is
            // held on it (SolidMPM::hold_on_zone_face()).
            s << "a material point entered the finite-element zone ";
            if (std::isnan(depth[0]))
              s << "deeper than its cell (no face of that cell borders a "
                   "cell outside the zone)";
            else
              s << depth[0] << " m deep (its distance to the nearest cell "
                << "outside the zone; a point less than half a point "
                << "spacing, " << mpm.zone_hold_distance()
                << " m, inside is held on the zone's face)";
          }
        s << " at solid step " << steps << ", time " << t_solid + dt
          << " s, near x = " << where;
        throw CollectiveError(s.str()); // the sums are global
      }
    if (sums[4] > 0) // a point entered a cell of another rank
      {
        // Points that left a rank were not counted in sums[0]: count the
        // kinetic energy again after the resort, and every point.
        mpm.resort();
        regathered = true;
        // Members carried into a detached drop's cell leave the solid
        // there (SolidMPM::set_aside_cells()): counted and booked as at
        // an exchange.
        const auto aside    = mpm.set_aside_by_last_gather();
        double     after[4] = {mpm.kinetic_energy(),
                               double(mpm.n_points()),
                               aside[0],
                               aside[1]};
        Utilities::MPI::sum(ArrayView<const double>(after, 4),
                            comm,
                            ArrayView<double>(after, 4));
        ledger.book_resort(sums[0], after[0], after[3], sums[6]);
        n_set_aside += after[2];
        check_point_count(after[1],
                          n_points_global - after[2],
                          "re-sorting",
                          t_solid + dt);
        n_points_global = after[1];
      }
  }

  template <int dim>
  void
  SolidSubCycle<dim>::stop_inverted(const double dt) const
  {
    // The first collapsed point, else the first inverted or distorted
    // element, of the lowest rank that has one (collective: every rank
    // throws).
    Point<dim> where;
    double     value     = 0;
    bool       distorted = false;
    const bool point     = mpm.find_collapsed(where, value);
    const bool found =
      point || (fem && fem->find_failed(where, value, distorted));
    const unsigned int me   = Utilities::MPI::this_mpi_process(comm);
    const unsigned int root = Utilities::MPI::min(found ? me : 1u << 30, comm);
    // buf[1]: 1 a point, 2 a distorted element, 0 an inverted one.
    double buf[dim + 2] = {value, point ? 1. : distorted ? 2. : 0.};
    for (int d = 0; d < dim; ++d)
      buf[2 + d] = where[d];
    if (root < (1u << 30))
      MPI_Bcast(buf, dim + 2, MPI_DOUBLE, root, comm);
    for (int d = 0; d < dim; ++d)
      where[d] = buf[2 + d];
    std::ostringstream s;
    s << "solid: ";
    if (buf[1] == 1.)
      s << "a material point collapsed (its volume V (1 + tr L dt) became "
        << buf[0] << " m^" << dim << ", not positive)";
    else if (buf[1] == 2.)
      s << "the hourglass modes of a finite element distorted its corners "
           "by "
        << buf[0]
        << " (the change of a corner's volume ratio; 'Solid FEM/Hourglass "
           "distortion limit' is "
        << (fem ? fem->parameters().hourglass_distortion_limit : 0.) << ")";
    else
      s << "a finite element inverted (its lowest corner Jacobian ratio "
           "det(dx/dX) became "
        << buf[0] << ")";
    s << " at solid step " << steps << ", time " << t_solid + dt
      << " s, near x = " << where
      << " m. The solid step is too large for the deformation there, or "
         "hourglass modes grew: use a smaller 'Solid/Safety factor' (or "
         "'Solid/Time step'), more 'Solid/Bulk viscosity', or a larger "
         "'Solid FEM/Hourglass coefficient'";
    // A point that solidified faster than the mass-scaled solid's P-wave
    // crosses cells in a solid step: the likelier cause.
    const auto [v_in, c] = solidification_speed();
    if (v_in > c)
      s << ". But first: a point entered the solid by solidifying at " << v_in
        << " m/s (the melt flow's velocity), " << v_in / c
        << " times the P-wave speed of the mass-scaled solid, sqrt(M / (s "
           "rho)) = "
        << c << " m/s, and moves " << v_in * dt_solid / grid.h()
        << " cells in a solid step; use a smaller 'Solid/Mass scaling "
           "factor' (s)";
    throw CollectiveError(s.str()); // the flag was reduced over all ranks
  }

  template <int dim>
  double
  SolidSubCycle<dim>::grid_point_kinetic(const bool updated) const
  {
    double k = 0;
    for (const auto &[n, t] : region.live_counted()) // no mass at the others
      {
        const double m = nodes.mass[n];
        if (m <= 0)
          continue;
        double v2 = 0;
        for (int d = 0; d < dim; ++d)
          if (!updated)
            v2 += (constrained[n] & (1u << d)) ?
                    0. :
                    nodes.momentum[d][n] * nodes.momentum[d][n] / (m * m);
          else
            {
              const double v = t < 0 ? nodes.velocity[d][n] : tr_v[dim * t + d];
              v2 += v * v;
            }
        k += 0.5 * m * v2;
      }
    return k;
  }

  template <int dim>
  void
  SolidSubCycle<dim>::check_point_count(const double       n_now,
                                        const double       n_expected,
                                        const std::string &where,
                                        const double       time) const
  {
    if (n_now == n_expected)
      return;
    std::ostringstream s;
    s << "solid: " << n_expected - n_now << " material point(s) lost in "
      << where << " at solid step " << steps << ", time " << time << " s ("
      << n_expected << " expected, " << n_now
      << " found): a point left the solid without melting, e.g. into a cell "
         "of the finite-element zone that its rank does not see";
    throw std::runtime_error(s.str());
  }

  template <int dim>
  void
  SolidSubCycle<dim>::share_points_with_flow(const bool flow_affine)
  {
    set_flow_owns_fluid_points(true, flow_affine);
    if (prm.light_nodes == Parameters::LightNodes::mass_floor)
      set_mass_floor(true);
    else
      set_small_mass_cutoff(prm.small_mass_cutoff);
  }

  template <int dim>
  void
  SolidSubCycle<dim>::set_small_mass_cutoff(const double fraction)
  {
    // A node of mass fraction eps of a full node's, next to a point whose
    // stiffness it feels in full (shape-function gradient ~ 1/h), is
    // stable for eps above about C^2 / (4 dim), twice that with the
    // coupling to its neighbours: the cutoff set for 'Safety factor'
    // grows with the square of the Courant number in use (the cooling
    // step, doc/solid.md "Cooling after the workpiece has solidified").
    small_mass_fraction = fraction;
    const double c      = safety / prm.safety_factor;
    small_mass          = fraction * c * c * scaling.factor() * mat.density() *
                 std::pow(grid.h(), dim) / (1u << dim);
  }

  template <int dim>
  void
  SolidSubCycle<dim>::set_mass_floor(const bool on)
  {
    mass_floor = on;
    mpm.set_stiffness_rows(on);
    if (on)
      nodes.stiffness.assign(nodes.mass.size(), 0.); // again by initialize()
    else
      nodes.stiffness.clear();
  }

  template <int dim>
  void
  SolidSubCycle<dim>::find_state_changes()
  {
    // (Flow and solid together, doc/solid.md.) States change only in the
    // temperature step; the flow changes velocities of fluid points only,
    // so the exchange found here is what the next gather would have found,
    // with the melted points' velocities as they left the solid. If the
    // solid takes no step in this temperature step (its step longer than
    // the temperature step), the next call finds the exchange again,
    // relative to the same gather.
    if (region.mpm_cells().empty())
      return;
    pending_exchange      = mpm.exchange_since_gather();
    have_pending_exchange = true;
  }

  template <int dim>
  void
  SolidSubCycle<dim>::gather_points()
  {
    typename SolidMPM<dim>::Exchange e;
    if (!region.mpm_cells().empty())
      {
        e = have_pending_exchange ? pending_exchange :
                                    mpm.exchange_since_gather();
        // Nothing melted, solidified or lost here, and no point to stop
        // in a detached drop: the gather may keep the arrays of the last
        // one (SolidMPM::gather()).
        mpm.gather(zone_mask(),
                   scaling.factor(),
                   e.n_melted == 0 && e.n_solidified == 0 && e.n_lost == 0 &&
                     e.n_stopped == 0);
      }
    else
      // No MPM cell here (all in the FE zone, e.g. a raised one): no
      // members either; after a resume this forgets the ids of all ranks
      // that load_state() kept, as the run that went on holds none here.
      mpm.gather(zone_mask(), scaling.factor());
    have_pending_exchange = false;
    fastest_solidified    = std::max(fastest_solidified, e.v_solidified);
    // Points set aside in detached drops leave the solid as melted ones
    // do: counted with them, their kinetic energy booked with theirs.
    double sums[8] = {e.n_melted + e.n_set_aside,
                      e.n_solidified,
                      e.n_lost,
                      e.k_melted + e.k_set_aside,
                      e.k_solidified,
                      double(mpm.n_points()),
                      mpm.kinetic_energy(),
                      e.n_set_aside};
    Utilities::MPI::sum(ArrayView<const double>(sums, 8),
                        comm,
                        ArrayView<double>(sums, 8));
    n_set_aside += sums[7];
    if (sums[2] > 0)
      {
        Point<dim> where = e.lost_at;
        share_location(e.n_lost > 0, where, comm);
        std::ostringstream s;
        s << "solid: " << sums[2]
          << " material point(s) entered the finite-element zone before solid "
             "step "
          << steps + 1 << ", time " << t_solid << " s, e.g. at x = " << where;
        throw std::runtime_error(s.str());
      }
    check_point_count(sums[5],
                      n_points_global - sums[0] + sums[1],
                      "the gather of the solid points (after " +
                        std::to_string(int(sums[0])) + " melted, " +
                        std::to_string(int(sums[1])) + " solidified)",
                      t_solid);
    n_points_global = sums[5];
    // The points' kinetic energy changes by what the melted points took
    // out and the solidified ones brought (booked; any other change shows
    // in the balance).
    ledger.book_exchange(sums[3], sums[4], sums[6]);
  }

  template <int dim>
  std::array<double, 2>
  SolidSubCycle<dim>::solidification_speed() const
  {
    return {{Utilities::MPI::max(fastest_solidified, comm),
             std::sqrt(mat.max_p_wave_modulus() /
                       (scaling.factor() * mat.density()))}};
  }

  template <int dim>
  void
  SolidSubCycle<dim>::before_points_removed(
    const std::vector<types::particle_index> &ids)
  {
    // The members as they are now: a member that melted since the last
    // gather is booked as melted here, before it goes (the next gather
    // could no longer find it), and the count is that of the solid points.
    gather_points();
    double a[2] = {double(mpm.count_members(ids)), mpm.kinetic_energy()};
    Utilities::MPI::sum(ArrayView<const double>(a, 2),
                        comm,
                        ArrayView<double>(a, 2));
    removing    = a[0];
    removing_K0 = a[1];
  }

  template <int dim>
  double
  SolidSubCycle<dim>::points_removed()
  {
    if (removing < 0)
      return 0;
    const double n = removing;
    removing       = -1;
    // Nothing moved or changed state since the gather in
    // before_points_removed(): the gather finds the members less the
    // removed ones (check_point_count()), and the kinetic energy falls by
    // theirs, which leaves the solid as a melted point's does.
    n_points_global -= n;
    gather_points();
    const double K1 = Utilities::MPI::sum(mpm.kinetic_energy(), comm);
    ledger.book_exchange(removing_K0 - K1, 0., K1);
    n_removed += n;
    return n;
  }

  template <int dim>
  typename SolidSubCycle<dim>::Energies
  SolidSubCycle<dim>::energies(const bool with_hourglass_mode) const
  {
    std::array<double, 2> hg{{0., 0.}};
    if (fem)
      hg = fem->hourglass_energy(with_hourglass_mode);
    Utilities::MPI::sum(ArrayView<const double>(hg.data(), 2),
                        comm,
                        ArrayView<double>(hg.data(), 2));
    return ledger.energies(hg[0], hg[1], scaling.state().kinetic_jump);
  }

  template <int dim>
  std::vector<std::array<double, 2>>
  SolidSubCycle<dim>::probe(const std::vector<Point<dim>> &x) const
  {
    std::vector<double> v(3 * x.size(), 0.);
    for (std::size_t i = 0; i < x.size(); ++i)
      {
        double fe_sxx, fe_T;
        if (fem && fem->probe(x[i], fe_sxx, fe_T)) // element of this rank
          {
            v[3 * i] = fe_sxx, v[3 * i + 1] = fe_T, v[3 * i + 2] = 1;
            continue;
          }
        const auto ijk = grid.cell_of(x[i]);
        if (!grid.in_box(ijk))
          continue;
        const auto idx = grid.local_index(ijk);
        if (grid.cell_status()[idx] != BackgroundGrid<dim>::owned ||
            zone_mask()[idx])
          continue;
        const auto [sxx, n] = mpm.cell_stress_xx(idx);
        v[3 * i]            = sxx;
        v[3 * i + 2]        = n > 0;
        v[3 * i + 1]        = T_solid[idx];
      }
    Utilities::MPI::sum(v, comm, v);
    std::vector<std::array<double, 2>> r(x.size());
    for (std::size_t i = 0; i < x.size(); ++i)
      r[i] = {{v[3 * i], v[3 * i + 1]}};
    return r;
  }

  template <int dim>
  void
  SolidSubCycle<dim>::cell_stress_fields(std::vector<double> &sxx,
                                         std::vector<double> &vm) const
  {
    std::vector<std::vector<double>> f;
    cell_fields(f);
    sxx.swap(f[0]);
    vm.swap(f[3]);
  }

  template <int dim>
  std::vector<std::string>
  SolidSubCycle<dim>::cell_field_names()
  {
    return {"sigma_xx", "sigma_yy", "sigma_zz", "von_mises", "plastic_strain"};
  }

  template <int dim>
  void
  SolidSubCycle<dim>::cell_fields(std::vector<std::vector<double>> &f) const
  {
    f.assign(5, std::vector<double>(grid.n_local(), 0.));
    std::vector<double> count(grid.n_local(), 0.);
    mpm.add_cell_fields(f, count);
    for (const auto c : grid.owned_cells())
      if (count[c] > 0)
        for (auto &field : f)
          field[c] /= count[c];
    if (fem)
      fem->cell_fields(f);
  }

  template <int dim>
  void
  SolidSubCycle<dim>::check_fe_zone_solid(const std::vector<double> &T,
                                          const double               t) const
  {
    if (!region.guard_fe_zone())
      return;
    const double T_s   = mat.melt_temperature();
    double       T_max = -std::numeric_limits<double>::infinity();
    for (const auto c : region.fe_cells())
      T_max = std::max(T_max, T[c]);
    T_max = Utilities::MPI::max(T_max, comm);
    if (!(T_max >= T_s))
      return;
    // The deepest element at or above the solidus: its position (cell
    // centre; ties: largest x, then y) and the hottest zone temperature.
    const double            h = grid.h();
    std::array<double, dim> where;
    where.fill(-std::numeric_limits<double>::infinity());
    double z_low = std::numeric_limits<double>::infinity();
    for (const auto c : region.fe_cells())
      if (T[c] >= T_s)
        z_low = std::min(z_low, grid.cell_center(c)[dim - 1]);
    z_low = Utilities::MPI::min(z_low, comm);
    for (const auto c : region.fe_cells())
      if (T[c] >= T_s &&
          std::abs(grid.cell_center(c)[dim - 1] - z_low) < 1e-3 * h)
        {
          const Point<dim> x = grid.cell_center(c);
          if (x[0] > where[0] ||
              (dim == 3 && x[0] == where[0] && x[1] > where[1]))
            for (int d = 0; d < dim; ++d)
              where[d] = x[d];
        }
    // Largest x first, then the largest y among the ranks with that x.
    const double x_max = Utilities::MPI::max(where[0], comm);
    if (where[0] != x_max)
      where.fill(-std::numeric_limits<double>::infinity());
    for (int d = 1; d < dim; ++d)
      where[d] = Utilities::MPI::max(where[d], comm);
    where[0] = x_max;
    const double top =
      grid.origin()[dim - 1] +
      std::floor((z_low - 0.5 * h - grid.origin()[dim - 1]) / h + 1e-9) * h -
      2 * h;
    std::ostringstream s;
    s << "the finite element at (";
    for (int d = 0; d < dim; ++d)
      s << (d ? ", " : "") << where[d];
    s << ") m reached the solidus " << T_s << " K at t = " << t
      << " s (hottest element " << T_max
      << " K): the FE zone must stay solid (paper sec. 2.1). Set 'Solid "
         "FEM/Zone upper corner' to 'auto' or lower its top to at most "
      << top << " m (two cells below the deepest molten element)";
    throw FeZoneMelted(s.str());
  }

  template <int dim>
  double
  SolidSubCycle<dim>::fe_elements_off_rank() const
  {
    return Utilities::MPI::sum(fem ? double(fem->n_elements_off_rank()) : 0.,
                               comm);
  }

  template <int dim>
  std::array<double, 2>
  SolidSubCycle<dim>::sizes() const
  {
    return {{Utilities::MPI::sum(double(mpm.n_points()), comm),
             Utilities::MPI::sum(fem ? double(fem->n_elements()) : 0., comm)}};
  }

  template <int dim>
  std::vector<double>
  SolidSubCycle<dim>::zone_top_lift() const
  {
    if (!fem)
      return {};
    const FeZone<dim> &zone = fem->fe_zone();
    const auto        &lo = zone.first_cell(), &n = zone.n_cells();
    const auto        &N = grid.n_cells();
    // The top of each column of the bounding box: one above its highest
    // zone cell (-1: none).
    std::size_t n_col = 1;
    for (int d = 0; d < dim - 1; ++d)
      n_col *= n[d];
    std::vector<int> col_top(n_col, -1);
    const auto      &mask = zone.mask();
    for (std::size_t k = 0; k < mask.size(); ++k)
      if (mask[k])
        col_top[k % n_col] =
          std::max(col_top[k % n_col], lo[dim - 1] + int(k / n_col) + 1);
    // The transition nodes by their lexicographic index in the grid.
    auto node_key = [&](const std::array<int, dim> &ijk) {
      std::uint64_t id = 0;
      for (int d = dim - 1; d >= 0; --d)
        id = id * (N[d] + 1) + ijk[d];
      return id;
    };
    std::unordered_map<std::uint64_t, std::size_t> tr;
    for (std::size_t t = 0; t < fem->n_transition(); ++t)
      tr[node_key(fem->transition_node(t))] = t;
    constexpr unsigned int nf = 1u << (dim - 1);
    std::vector<double>    lift(nf * n_col, 0.);
    for (std::size_t c = 0; c < n_col; ++c)
      {
        if (col_top[c] < 0)
          continue;
        for (unsigned int a = 0; a < nf; ++a)
          {
            std::array<int, dim> ijk;
            std::size_t          r = c;
            for (int d = 0; d < dim - 1; ++d)
              {
                ijk[d] = lo[d] + int(r % n[d]) + int((a >> d) & 1u);
                r /= n[d];
              }
            ijk[dim - 1]  = col_top[c];
            const auto it = tr.find(node_key(ijk));
            // A top on the domain's top face has no transition nodes.
            if (it == tr.end())
              return {};
            lift[nf * c + a] =
              fem->transition_displacement(it->second)[dim - 1];
          }
      }
    return lift;
  }

  template <int dim>
  std::array<double, 2>
  SolidSubCycle<dim>::hand_over_rows(const double new_top)
  {
    AssertThrow(fem,
                ExcMessage("the hand-over to finite elements needs an FE "
                           "zone ('Solid FEM/Use finite elements = true')"));
    // The cells between the zone's top and the new one, inside the zone's
    // horizontal extent.
    const auto &z   = fem->fe_zone();
    const int   top = static_cast<int>(
      std::round((new_top - grid.origin()[dim - 1]) / grid.h()));
    const auto &lo = z.first_cell(), &n = z.n_cells();
    AssertThrow(top > lo[dim - 1] + n[dim - 1] &&
                  top <= int(grid.n_cells()[dim - 1]),
                ExcMessage("FE zone hand-over: the new top " +
                           std::to_string(new_top) +
                           " m must be a grid line above the zone's top and "
                           "inside the domain"));
    std::size_t n_row = 1;
    for (int d = 0; d < dim - 1; ++d)
      n_row *= n[d];
    std::vector<std::array<int, dim>> cells;
    for (int k = lo[dim - 1] + n[dim - 1]; k < top; ++k)
      for (std::size_t i = 0; i < n_row; ++i)
        {
          std::array<int, dim> c;
          std::size_t          r = i;
          for (int d = 0; d < dim - 1; ++d)
            c[d] = lo[d] + int(r % n[d]), r /= n[d];
          c[dim - 1] = k;
          cells.push_back(c);
        }
    return hand_over_cells(cells);
  }

  template <int dim>
  std::array<double, 2>
  SolidSubCycle<dim>::hand_over_cells(
    const std::vector<std::array<int, dim>> &cells)
  {
    AssertThrow(fem,
                ExcMessage("the hand-over to finite elements needs an FE "
                           "zone ('Solid FEM/Use finite elements = true')"));
    // The points' state as the particles hold it after the last advance,
    // with what melted or solidified since booked.
    gather_points();
    const auto &z = fem->fe_zone();
    const auto &N = grid.n_cells();
    // The owned cells among the new ones.
    std::vector<std::uint8_t>  mark(grid.n_local(), 0);
    std::vector<std::uint32_t> owned;
    for (const auto &ijk : cells)
      {
        for (int d = 0; d < dim; ++d)
          AssertThrow(ijk[d] >= 0 && ijk[d] < int(N[d]),
                      ExcMessage("FE zone hand-over: a cell outside the grid"));
        AssertThrow(!z.contains_cell(ijk),
                    ExcMessage("FE zone hand-over: a cell of the zone is "
                               "handed over again"));
        if (!grid.in_box(ijk))
          continue;
        const auto c = grid.local_index(ijk);
        if (grid.cell_status()[c] != BackgroundGrid<dim>::owned || mark[c])
          continue;
        mark[c] = 1;
        owned.push_back(c);
      }
    // Each new element: the mean over its cell's solid points (the
    // arithmetic of cell_fields()).
    std::vector<std::array<double, 8>> sums(grid.n_local());
    for (auto &a : sums)
      a.fill(0.);
    mpm.add_cell_state(mark, sums);
    std::vector<std::pair<std::uint64_t, std::array<double, 7>>> seeds;
    bool                                                         empty = false;
    Point<dim>                                                   where;
    for (const auto c : owned)
      {
        const auto &a   = sums[c];
        const auto  ijk = grid.global_index(c);
        if (!(a[7] > 0))
          {
            if (!empty)
              for (int d = 0; d < dim; ++d)
                where[d] = grid.origin()[d] + (ijk[d] + 0.5) * grid.h();
            empty = true;
            continue;
          }
        std::uint64_t key = 0;
        for (int d = dim - 1; d >= 0; --d)
          key = key * N[d] + ijk[d];
        std::array<double, 7> m;
        for (unsigned int k = 0; k < 7; ++k)
          m[k] = a[k] / a[7];
        seeds.emplace_back(key, m);
      }
    share_location(empty, where, comm);
    if (Utilities::MPI::max(empty ? 1 : 0, comm) > 0)
      {
        std::ostringstream s;
        s << "solid: the hand-over to finite elements finds a cell without "
             "solid material points at x = "
          << where << " m: only cells of solid metal can become finite "
          << "elements";
        throw CollectiveError(s.str());
      }
    const double K0    = Utilities::MPI::sum(mpm.kinetic_energy(), comm);
    const double added = fem->add_cells(cells, seeds, T_solid);
    find_active_nodes();
    mpm.gather(zone_mask(), scaling.factor());
    rebuild_live(nullptr, 0.);
    const double K1     = Utilities::MPI::sum(mpm.kinetic_energy(), comm);
    const double n1     = Utilities::MPI::sum(double(mpm.n_points()), comm);
    const double handed = n_points_global - n1;
    n_points_global     = n1;
    // The handed points' kinetic energy leaves the points' account like
    // that of melted points (the new nodes start at rest).
    ledger.book_exchange(K0 - K1, 0., K1);
    return {{added, handed}};
  }

  template <int dim>
  double
  SolidSubCycle<dim>::fe_zone_mass() const
  {
    return fem ? fem->mass() : 0.;
  }

  template <int dim>
  double
  SolidSubCycle<dim>::largest_rank_points() const
  {
    return Utilities::MPI::max(double(mpm.n_points()), comm);
  }

  template <int dim>
  bool
  SolidSubCycle<dim>::row_due(const double t_old, const double t_new) const
  {
    // Stateless (a resumed run decides the same): a row when the step
    // crosses a multiple of the interval.
    if (prm.row_interval <= 0)
      return true;
    const auto k = [&](const double t) {
      return std::floor(t / prm.row_interval * (1 + 1e-12));
    };
    return k(t_new) > k(t_old);
  }

  template <int dim>
  void
  SolidSubCycle<dim>::write_rows()
  {
    if (!prm.energy_file.empty() || !prm.probes.empty())
      {
        // Collective parts first, on every rank.
        const bool want_energy = !prm.energy_file.empty();
        Energies   e;
        if (want_energy)
          e = energies();
        std::vector<std::array<double, 2>> p;
        if (!prm.probes.empty())
          p = probe(prm.probes);
        if (energy_out)
          *energy_out << std::setprecision(10) << t_solid << "," << steps << ","
                      << e.external << "," << e.internal << "," << e.kinetic
                      << "," << e.hourglass << "," << e.balance() << ","
                      << e.kinetic / std::max(std::abs(e.internal), 1e-300)
                      << "," << e.hourglass_mode << "," << e.transfer << ","
                      << e.melted << "," << e.solidified << "," << e.remap
                      << "," << scaling.factor() << ","
                      << scaling.state().last_ratio << "," << e.scaling_jump
                      << "," << e.withheld << "\n";
        if (probe_out)
          {
            *probe_out << std::setprecision(10) << t_solid;
            for (const auto &q : p)
              *probe_out << "," << q[0] << "," << q[1];
            *probe_out << "\n";
          }
        // A row that cannot be written (disk full, file system gone) stops
        // the run naming the file, instead of losing the series quietly.
        AssertThrow(!energy_out || *energy_out,
                    ExcMessage("cannot write the solid energy file '" +
                               prm.energy_file +
                               "' (Solid/Energy file): "
                               "disk full or file system gone?"));
        AssertThrow(!probe_out || *probe_out,
                    ExcMessage("cannot write the solid probe file '" +
                               prm.probe_file +
                               "' (Solid/Probe file): "
                               "disk full or file system gone?"));
      }
  }

  template <int dim>
  void
  SolidSubCycle<dim>::save_state(StateWriter &out) const
  {
    // The sub-step clock and the energy accounts (global: the same on every
    // rank).
    out.put(t_solid);
    out.put(t_prev);
    out.put(dt_solid);
    out.put(steps);
    for (const double a : ledger.saved_values())
      out.put(a);
    out.put(n_points_global);
    // Temperatures of the last sub-step, of the last advance() (the start
    // of the next interpolation) and the spare buffer of the sub-steps.
    save_cell_fields(out, grid, {&T_solid, &T_prev, &T_next});
    // Lengths of the CSV files (rank 0 writes them; flushed so that the
    // size on disk is what they hold).
    auto size = [&](const std::unique_ptr<std::ofstream> &f,
                    const std::string                    &name) {
      std::uint64_t n = 0;
      if (f)
        {
          f->flush();
          std::error_code ec;
          n = std::filesystem::file_size(csv_directory + "/" + name, ec);
          AssertThrow(!ec && *f,
                      ExcMessage("cannot measure the solid CSV "
                                 "file '" +
                                 name +
                                 "' for the "
                                 "checkpoint"));
        }
      return n;
    };
    out.put(size(energy_out, prm.energy_file));
    out.put(size(probe_out, prm.probe_file));
    mpm.save_state(out);
    if (fem)
      fem->save_state(out);
    else
      SolidFEM<dim>::save_no_zone(out);
    // The mass-scaling factor (adaptive mass scaling changes it) and its
    // measurement over the current solid phase.
    for (const double a : scaling.saved_values())
      out.put(a);
    // Added last, so that checkpoints written without it still load (as 0).
    out.put(ledger.withheld());
    // After it, likewise: the factor the quasi-static cooling took over
    // from (0: not switched).
    out.put(adaptive_from);
    // Then the state of the leapfrog's half-step term, which the energy
    // check takes off the balance.
    for (const double a : ledger.half_step_values())
      out.put(a);
  }

  template <int dim>
  void
  SolidSubCycle<dim>::save_fe_zone(StateWriter &out) const
  {
    out.put(fem ? fem->top() : 0.);
    out.put(fem ? fem->setup_mass_scaling() : 0.);
    // The zone's cells: the bounding box and its mask.
    std::vector<std::int32_t> box;
    std::vector<std::uint8_t> mask;
    if (fem)
      {
        const auto &z = fem->fe_zone();
        for (int d = 0; d < dim; ++d)
          box.push_back(z.first_cell()[d]);
        for (int d = 0; d < dim; ++d)
          box.push_back(z.n_cells()[d]);
        mask = z.mask();
      }
    out.put_vector(box);
    out.put_vector(mask);
  }

  template <int dim>
  SavedFeZone<dim>
  read_saved_fe_zone(std::vector<StateReader> &parts)
  {
    // The same on every rank: the first part's.
    SavedFeZone<dim> saved;
    saved.top    = parts[0].get<double>();
    saved.factor = parts[0].get<double>();
    // The zone's cells (a checkpoint written without them holds a box up
    // to the top).
    std::vector<std::int32_t> box;
    if (!parts[0].at_end())
      {
        box        = parts[0].get_vector<std::int32_t>();
        saved.mask = parts[0].get_vector<std::uint8_t>();
      }
    if (box.size() == 2 * dim)
      {
        std::size_t n_all = 1;
        for (int d = 0; d < dim; ++d)
          {
            saved.first[d] = box[d];
            saved.n[d]     = box[dim + d];
            n_all *= saved.n[d];
          }
        AssertThrow(saved.mask.size() == n_all,
                    ExcMessage("checkpoint: the FE zone's cells are damaged"));
        saved.has_cells = true;
      }
    return saved;
  }

  template SavedFeZone<2>
  read_saved_fe_zone<2>(std::vector<StateReader> &);
  template SavedFeZone<3>
  read_saved_fe_zone<3>(std::vector<StateReader> &);

  template <int dim>
  void
  SolidSubCycle<dim>::resume_fe_zone(std::vector<StateReader> &parts)
  {
    const auto saved = read_saved_fe_zone<dim>(parts);
    if (!fem)
      return; // the header's check refused a checkpoint with a zone
    if (saved.has_cells)
      fem->set_cells(
        FeZone<dim>(saved.first, saved.n, saved.mask, grid.origin(), grid.h()));
    else
      fem->set_top(saved.top);
    fe_setup_factor = saved.factor;
  }

  template <int dim>
  void
  SolidSubCycle<dim>::set_fe_zone(const FeZone<dim> &zone)
  {
    AssertThrow(fem,
                ExcMessage("an FE zone of cells needs the FE zone on "
                           "('Solid FEM/Use finite elements = true')"));
    fem->set_cells(zone);
  }

  template <int dim>
  void
  SolidSubCycle<dim>::measure_and_adapt_scaling(const bool adapt)
  {
    // The quasi-static gauge (doc/speed_accuracy.md, sections 1 and 3):
    // the mean kinetic energy of the advance's steps over the elastic
    // energy stored at its end (cell temperatures of the last step).
    const double u = Utilities::MPI::sum(mpm.elastic_energy(T_solid) +
                                           (fem ? fem->elastic_energy() : 0.),
                                         comm);
    scaling.measure(u, ledger.kinetic());
    check_energy_created(u);
    if (!adapt)
      return;
    const double s      = scaling.factor();
    const double target = scaling.target();
    if (target != s)
      set_mass_scaling(target,
                       prm.fe_momentum_at_raise && adaptive_from > 0 &&
                         target > s);
  }

  template <int dim>
  void
  SolidSubCycle<dim>::check_energy_created(const double elastic_energy)
  {
    // A solid step above the stable limit can grow a mode that stays
    // finite (no point collapses, no element inverts: the material points
    // of doc/stability.md at 1.5 x the limit); its only trace is energy
    // that no booked source supplied, a positive balance. Correct runs
    // leave a negative or round-off balance (dissipation that is not
    // booked), at most 1e-3 of the stored elastic energy in the scenes
    // measured; with the melt flow the booking of points that solidify
    // with a velocity leaves positive residues of up to a tenth of the
    // energies exchanged. A quarter of the stored elastic and kinetic
    // energies, the external work and the booked exchanges (transfer,
    // melting, solidification, re-map, scaling jumps) together is taken
    // as the sign of an instability.
    // The balance is taken with the kinetic energy at the whole step
    // (SolidEnergies::whole_step_balance()): the central-difference update
    // books the works over a step against the kinetic energy at the whole
    // step, 1/2 m v_{n-1/2} . v_{n+1/2}, not at the half-step velocity the
    // energy file keeps. With the half-step kinetic energy a body starting
    // from rest under a constant load shows half the work of its first
    // step as created (1/2 m (g dt)^2 of m g^2 dt^2, a third of the scale
    // after one step, a fifth after two): a false stop where an advance
    // holds one or two solid steps. With the whole-step kinetic energy
    // that balance is round-off at every step, and a linear elastic body
    // leaves -dt^2/2 v . K v <= 0 at a constant step (K its stiffness).
    // Global sums: every rank decides the same.
    const auto   e       = energies(false);
    const double created = e.whole_step_balance();
    const double scale   = elastic_energy + e.kinetic + std::abs(e.external) +
                         std::abs(e.transfer) + e.melted + e.solidified +
                         std::abs(e.remap) + std::abs(e.scaling_jump) +
                         std::abs(e.withheld);
    last_check = {{created, scale}};
    if (!(scale > 0) || !(created > energy_created_limit * scale))
      return;
    std::ostringstream s;
    s << "solid: the energy balance shows " << created
      << " J created (more than " << energy_created_limit
      << " of the stored elastic, kinetic and external energies and the "
         "booked exchanges, "
      << scale << " J) by solid step " << steps << ", time " << t_solid
      << " s: the solid went unstable without becoming non-finite (a step "
         "too large for the state, e.g. near its stable limit with the melt "
         "flow). Use a smaller 'Solid/Safety factor' (or 'Solid/Time step'); "
         "the energy file shows where the balance grew";
    // Where: the fastest solid point of all ranks (collective: every rank
    // is here, the decision above is global).
    const auto all = Utilities::MPI::all_gather(comm, mpm.fastest_member());
    const auto f   = *std::max_element(all.begin(),
                                     all.end(),
                                     [](const auto &a, const auto &b) {
                                       return a[0] < b[0];
                                     });
    if (f[0] >= 0)
      {
        s << ". The fastest solid point (" << f[0] << " m/s) is at (";
        for (int d = 0; d < dim; ++d)
          s << (d ? ", " : "") << f[1 + d];
        s << ") m, with " << f[1 + dim]
          << " solid points in its cell, their mass " << f[2 + dim]
          << " of a full cell's";
      }
    throw CollectiveError(s.str()); // the sums are global
  }

  template <int dim>
  void
  SolidSubCycle<dim>::load_state(std::vector<StateReader> &parts,
                                 const std::string        &directory)
  {
    double        a[10];
    std::uint64_t energy_size = 0, probe_size = 0;
    for (std::size_t f = 0; f < parts.size(); ++f)
      {
        StateReader &in = parts[f];
        const auto   ts = in.get<double>(), tp = in.get<double>(),
                   dts = in.get<double>();
        const auto n   = in.get<unsigned int>();
        for (double &x : a)
          x = in.get<double>();
        if (f > 0)
          continue;
        t_solid = ts, t_prev = tp, dt_solid = dts, steps = n;
        ledger.restore(a);
        n_points_global = a[9];
      }
    load_cell_fields(parts, grid, {&T_solid, &T_prev, &T_next});
    for (std::size_t f = 0; f < parts.size(); ++f)
      {
        const auto e = parts[f].get<std::uint64_t>();
        const auto p = parts[f].get<std::uint64_t>();
        if (f == 0)
          energy_size = e, probe_size = p;
      }
    mpm.load_state(parts);
    if (fem)
      fem->load_state(parts);
    else
      SolidFEM<dim>::load_no_zone(parts);
    {
      double b[5] = {};
      for (std::size_t f = 0; f < parts.size(); ++f)
        for (std::size_t i = 0; i < 5; ++i)
          {
            const double x = parts[f].get<double>();
            if (f == 0)
              b[i] = x;
          }
      // The MPM side restored its factor with its state; the FE zone's
      // masses and the small-mass threshold follow the factor from the one
      // of the setup.
      if (fem)
        fem->set_mass_scaling(b[0]);
      scaling.restore({{b[0], b[1], b[2], b[3], b[4]}});
      // The Courant number in use is the one the checkpoint's step was
      // taken with (it may be the one after solidification).
      if (prm.time_step == 0)
        safety = dt_solid / prm.stable_limit(mat, grid.h(), scaling.factor());
      set_small_mass_cutoff(small_mass_fraction);
    }
    // Not in checkpoints written before they were kept: 0.
    ledger.restore_withheld(0);
    ledger.restore_half_step({{0, 0, 0, 0}});
    adaptive_from = 0;
    for (std::size_t f = 0; f < parts.size(); ++f)
      {
        if (!parts[f].at_end())
          {
            const double x = parts[f].get<double>();
            if (f == 0)
              ledger.restore_withheld(x);
          }
        if (!parts[f].at_end())
          {
            const double x = parts[f].get<double>();
            if (f == 0)
              adaptive_from = x;
          }
        if (!parts[f].at_end())
          {
            std::array<double, 4> h;
            for (double &x : h)
              x = parts[f].get<double>();
            if (f == 0)
              ledger.restore_half_step(h);
          }
      }
    // A checkpoint written without the quasi-static cooling, resumed with
    // it: the controller takes over at the next switch test.
    if (!prm.adaptive_after_solidification)
      adaptive_from = 0;
    if (adaptive_from > 0)
      scaling.set_range(adaptive_from,
                        std::max(adaptive_from, prm.max_factor_solidified));
    // Switched once each part of the switch that is set has been done.
    const bool c2_done = !(prm.safety_factor_solidified > prm.safety_factor) ||
                         safety > prm.safety_factor * (1 + 1e-6);
    const bool adaptive_done =
      !prm.adaptive_after_solidification || adaptive_from > 0;
    cooling_step = prm.cools_after_solidification() && c2_done && adaptive_done;
    have_pending_exchange = false;

    // The CSV files: drop the rows after the checkpoint, then append.
    csv_directory = directory;
    std::string error;
    if (!directory.empty() && Utilities::MPI::this_mpi_process(comm) == 0)
      {
        namespace fs = std::filesystem;
        auto reopen  = [&](std::unique_ptr<std::ofstream> &f,
                          const std::string              &name,
                          const std::uint64_t             size) {
          const std::string file = directory + "/" + name;
          std::error_code   ec;
          if (!fs::exists(file) || fs::file_size(file, ec) < size)
            {
              error = "the solid's time series '" + file +
                      "' is missing or shorter than at the checkpoint (" +
                      std::to_string(size) +
                      " bytes); resume into the output directory of the run "
                       "that wrote the checkpoint";
              return;
            }
          fs::resize_file(file, size, ec);
          f = std::make_unique<std::ofstream>(file, std::ios::app);
          if (ec || !*f)
            error = "cannot truncate and reopen '" + file + "'";
        };
        if (!prm.energy_file.empty())
          reopen(energy_out, prm.energy_file, energy_size);
        if (error.empty() && !prm.probe_file.empty() && !prm.probes.empty())
          reopen(probe_out, prm.probe_file, probe_size);
      }
    if (Utilities::MPI::min(int(error.empty()), comm) == 0)
      throw InputError("Checkpoint/Resume from",
                       directory,
                       Utilities::MPI::broadcast(comm, error, 0));
  }

  template <int dim>
  std::string
  SolidSubCycle<dim>::use_cooling_step()
  {
    const double c2 = prm.safety_factor_solidified;
    if (cooling_step)
      return "";
    std::ostringstream m;
    if (c2 > safety)
      {
        // The stresses depend on s and C through sqrt(s) / C
        // (doc/speed_accuracy.md, "The solid's safety factor"): s grows by
        // (C2 / C)^2, and the step, C sqrt(s), by (C2 / C)^2 as well.
        const double s_old = scaling.factor(), c_old = safety,
                     dt_old = dt_solid;
        const double r      = c2 / c_old;
        safety              = c2;
        set_mass_scaling(s_old * r * r);
        m << "safety factor " << c_old << " -> " << c2 << ", mass scaling "
          << s_old << " -> " << scaling.factor() << " (sqrt(s)/C kept at "
          << std::sqrt(scaling.factor()) / safety << "), solid step " << dt_old
          << " -> " << dt_solid << " s";
        if (mass_floor)
          m << ", light-node mass floor x " << r * r;
        else
          m << ", small-mass cutoff " << small_mass_fraction << " -> "
            << small_mass_fraction * r * r;
      }
    if (prm.adaptive_after_solidification && !(adaptive_from > 0))
      {
        // Quasi-static cooling (doc/solid.md): the controller takes over
        // from the factor in use, which is also its lower bound (the
        // accuracy of the fixed setting is the floor).
        adaptive_from = scaling.factor();
        scaling.set_range(adaptive_from,
                          std::max(adaptive_from, prm.max_factor_solidified));
        m << (m.tellp() > 0 ? "; " : "") << "mass scaling adaptive from "
          << adaptive_from << " to at most "
          << std::max(adaptive_from, prm.max_factor_solidified)
          << " (K / U_el at most " << prm.max_kinetic_ratio << "), solid step "
          << dt_solid << " s";
      }
    cooling_step = true;
    return m.str();
  }

  template <int dim>
  void
  SolidSubCycle<dim>::set_mass_scaling(const double s,
                                       const bool   keep_fe_momentum)
  {
    // Velocities kept (the kinematic velocity of the thermal expansion
    // does not depend on s); the kinetic energy follows the mass, and the
    // jump is booked so that the balance still closes. With
    // keep_fe_momentum the FE nodes' velocities are first divided by
    // s / s_old: the kinetic energy this takes out at the old masses is
    // booked with the transfer dissipation (as the damping of the FE
    // nodes), and the jump at the kept (reduced) velocities follows.
    if (keep_fe_momentum && fem)
      ledger.take_fe_kinetic(
        -Utilities::MPI::sum(fem->scale_node_velocities(scaling.factor() / s),
                             comm));
    const double r = scaling.change_to(s, ledger.kinetic());
    ledger.scale_kinetic(r);
    mpm.set_mass_scaling(s);
    if (fem)
      fem->set_mass_scaling(s);
    set_small_mass_cutoff(small_mass_fraction); // from the factor, not by r
    dt_solid = safety * prm.stable_limit(mat, grid.h(), s);
  }

  template class SolidSubCycle<2>;
  template class SolidSubCycle<3>;
} // namespace femp
