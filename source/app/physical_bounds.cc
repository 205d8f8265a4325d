// femp: physical plausibility of a scene before any work (see the header).
// The step limits are those the modules use: IncompressibleFlow's
// material_limits() (eqs. 3-4), SolidSubCycle's stable_limit() (eqs.
// 11-17), the explicit temperature step of eq. (1) for a full metal cell.
#include <deal.II/base/utilities.h>

#include <femp/app/physical_bounds.h>
#include <femp/app/physics_switches.h>
#include <femp/app/run_checks.h>
#include <femp/app/simulation_control.h>
#include <femp/base/input_checks.h>
#include <femp/base/material.h>
#include <femp/base/parameter_lookup.h>
#include <femp/flow/incompressible_flow.h>
#include <femp/heat/laser.h>
#include <femp/solid/constitutive.h>
#include <femp/solid/solid_sub_cycle.h>

#include <cmath>
#include <cstdlib>
#include <sstream>

namespace femp
{
  namespace
  {
    unsigned int
    run_limit_substeps(const dealii::ParameterHandler &prm, const bool flow)
    {
      const auto limits = RunLimits::Parameters::of(prm);
      return flow ? limits.max_flow_substeps : limits.max_solid_substeps;
    }

    /// Entries whose values are names, not numbers.
    bool
    holds_names(const std::string &name)
    {
      for (const char *word :
           {"file", "Directory", "directory", "Resume from", "format"})
        if (name.find(word) != std::string::npos)
          return true;
      return false;
    }
  } // namespace

  void
  check_number_magnitudes(const dealii::ParameterHandler &prm)
  {
    // Every entry with its value, as the short listing writes them.
    std::ostringstream listing;
    prm.print_parameters(listing, dealii::ParameterHandler::ShortPRM);
    std::istringstream       in(listing.str());
    std::vector<std::string> sections;
    std::string              line;
    while (std::getline(in, line))
      {
        line = dealii::Utilities::trim(line);
        if (line.rfind("subsection ", 0) == 0)
          sections.push_back(dealii::Utilities::trim(line.substr(11)));
        else if (line == "end" && !sections.empty())
          sections.pop_back();
        else if (line.rfind("set ", 0) == 0)
          {
            const auto eq = line.find('=');
            if (eq == std::string::npos)
              continue;
            std::string path;
            for (const auto &s : sections)
              path += s + "/";
            const std::string name =
              dealii::Utilities::trim(line.substr(4, eq - 4));
            const std::string value =
              dealii::Utilities::trim(line.substr(eq + 1));
            if (holds_names(name))
              continue;
            // The numbers of lists, tables, points and expressions: tokens
            // between separators that read as a number as a whole.
            std::string token;
            for (std::size_t i = 0; i <= value.size(); ++i)
              {
                const char c = i < value.size() ? value[i] : ' ';
                if (std::string(",:; \t()=<>*/").find(c) == std::string::npos)
                  {
                    token += c;
                    continue;
                  }
                if (token.empty())
                  continue;
                char        *end = nullptr;
                const double x   = std::strtod(token.c_str(), &end);
                if (end == token.c_str() + token.size())
                  require(std::isfinite(x) && std::abs(x) <= largest_magnitude,
                          path + name,
                          value,
                          "the number '" + token + "' in it is " +
                            (std::isfinite(x) ?
                               "beyond " + num(largest_magnitude) :
                               std::string("not finite")) +
                            " in magnitude: every number of a scene must be "
                            "finite and at most 1e30 in SI units (no "
                            "quantity of a powder-bed scene comes near it, "
                            "and products of such numbers would overflow "
                            "the double precision the schemes compute in); "
                            "check the unit");
                token.clear();
              }
          }
      }
  }

  void
  check_physical_relations(const dealii::ParameterHandler &prm_in)
  {
    auto        &prm = const_cast<dealii::ParameterHandler &>(prm_in);
    const double Ts  = parameter_double(prm, "Material", "Solidus temperature");
    const double Tl = parameter_double(prm, "Material", "Liquidus temperature");
    const double Tv =
      parameter_double(prm, "Material", "Evaporation temperature");
    const auto physics = PhysicsSwitches::of(prm);
    // The evaporation temperature matters where the scene evaporates:
    // the surface loss of eq. (1) and the recoil pressure of the flow.
    const bool evaporates =
      (physics.heat_transfer &&
       parameter_double(prm, "Heat transfer", "Evaporation coefficient") > 0 &&
       parameter_double(prm, "Material", "Latent heat of evaporation") > 0) ||
      (physics.melt_flow &&
       parameter_double(prm, "Melt flow", "Recoil coefficient") > 0);
    require(!evaporates || !(Tl > Ts) || Tv > Tl,
            "Material/Evaporation temperature",
            Tv,
            "it must lie above the liquidus temperature " + num(Tl) +
              " K: a metal boils only once it is liquid (at or below the "
              "liquidus the evaporation loss and the recoil pressure would "
              "act on solid metal and run away; without evaporation set "
              "'Heat transfer/Evaporation coefficient = 0' and 'Melt "
              "flow/Recoil coefficient = 0')");
    // The front-wall piston's film is expelled by the recoil pressure.
    if (physics.heat_transfer &&
        parameter_bool(prm, "Heat transfer", "Front wall piston") &&
        !(physics.melt_flow &&
          parameter_double(prm, "Melt flow", "Recoil coefficient") > 0))
      throw InputError("Heat transfer/Front wall piston",
                       "true",
                       "it needs the recoil pressure that expels the film: "
                       "Physics/Melt flow = true and Melt flow/Recoil "
                       "coefficient > 0; or false");
    // The front-wall expulsion moves the melt at the Bernoulli speed of
    // the recoil pressure of the cells' temperature.
    if (physics.melt_flow &&
        parameter_bool(prm, "Melt flow", "Front wall expulsion") &&
        !(physics.heat_transfer &&
          parameter_double(prm, "Melt flow", "Recoil coefficient") > 0))
      throw InputError("Melt flow/Front wall expulsion",
                       "true",
                       "it needs the recoil pressure that expels the melt: "
                       "Physics/Heat transfer = true and Melt flow/Recoil "
                       "coefficient > 0; or false");
    const double Tref =
      parameter_double(prm, "Heat transfer", "Reference temperature");
    require(!evaporates || Tref < Tv,
            "Heat transfer/Reference temperature",
            Tref,
            "the ambient must be colder than the evaporation temperature " +
              num(Tv) + " K");
    const double rho   = parameter_double(prm, "Material", "Density");
    const double rho_g = parameter_double(prm, "Material", "Gas density");
    require(!(rho > 0) || rho_g < rho,
            "Material/Gas density",
            rho_g,
            "the gas must be lighter than the metal (Material/Density = " +
              num(rho) + " kg/m^3)");
    // A beam far narrower than a cell: its melt pool cannot be resolved,
    // whatever the deposit does (between min_beam_cells and one cell the
    // Gaussian is averaged over each cell, so that none of it is lost).
    const double rb = parameter_double(prm, "Laser", "Beam radius");
    const double h  = parameter_double(prm, "Background grid", "Cell size");
    std::ostringstream s;
    s << "it must be at least " << min_beam_cells
      << " of the cell size (h = " << h
      << " m): the grid cannot resolve a narrower beam; refine "
         "'Background grid/Cell size' or check the unit (m). A beam "
         "narrower than a cell is deposited as its average over each "
         "cell, so that the absorbed power is kept";
    require(!(h > 0) || parameter_double(prm, "Laser", "Power") == 0 ||
              rb >= min_beam_cells * h,
            "Laser/Beam radius",
            rb,
            s.str());
  }

  namespace
  {
    /// Refuse @p n sub-steps of @p scheme per temperature step above
    /// @p bound, naming the parameter that sets the sub-step.
    void
    require_substeps(const double       n,
                     const unsigned int bound,
                     const std::string &bound_name,
                     const std::string &parameter,
                     const double       value,
                     const std::string &why,
                     const double       step,
                     const double       dt_T)
    {
      std::ostringstream s;
      s << "it sets " << why << " of " << step << " s, which needs about " << n
        << " sub-steps per temperature step of " << dt_T << " s, more than '"
        << bound_name << "' = " << bound
        << ": the run would make no visible progress in simulated time; "
           "check the value and its unit";
      require(n <= bound, parameter, value, s.str());
    }

    template <int dim>
    void
    check_step_floors_dim(dealii::ParameterHandler &prm)
    {
      SimulationControl::Parameters time;
      time.parse_parameters(prm);
      Material mat;
      mat.parse_parameters(prm);
      const double h = parameter_double(prm, "Background grid", "Cell size");
      const auto   physics = PhysicsSwitches::of(prm);
      const bool   heat    = physics.heat_transfer;
      const bool   flow    = physics.melt_flow;
      const bool   solid   = physics.solid_stress;
      const double g       = physics.gravity;
      if (!(h > 0) || !(time.end_time > 0))
        return; // the modules refuse these
      // The temperature step: prescribed, or the stable explicit step of a
      // cell full of metal, h^2 rho c / (2 dim lambda), at its smallest
      // over the tables (the projection counts the fewest sub-steps).
      double dt_T = time.time_step;
      if (dt_T <= 0 && heat)
        dt_T = time.safety_factor * h * h * mat.density *
               mat.specific_heat.min_value() /
               (2 * dim * mat.conductivity.max_value());
      // A prescribed step above the stable limit of every metal cell is
      // refused by its own check, with its own message.
      if (heat && time.time_step > 0 &&
          time.time_step > h * h * mat.density * mat.specific_heat.max_value() /
                             (2 * dim * mat.conductivity.min_value()))
        return;

      // The laser is seen at the start of each temperature step: a path
      // whose beam is on for less than one step in all would deposit its
      // energy in one step or in none (a laser line of 0 in the report).
      if (heat && dt_T > 0)
        {
          typename Laser<dim>::Parameters lp;
          lp.parse_parameters(prm);
          const Laser<dim> laser(lp);
          double           on = 0;
          for (const auto &seg : laser.segments())
            if (seg.power > 0)
              on += seg.t_end - seg.t_begin;
          const bool         line = lp.scan_path_file.empty();
          std::ostringstream why;
          why << "the laser is on for " << on << " s in all, less than one "
              << "temperature step (about " << dt_T
              << " s): it would deposit its energy in one step or in none; "
              << (line ? "lower the speed or check its unit (m/s)" :
                         "check the speeds of its lines (m/s)");
          require(!(on > 0) || on >= dt_T,
                  line ? "Laser/Scan speed" : "Laser/Scan path file",
                  line ? num(lp.scan_speed) : lp.scan_path_file,
                  why.str());
        }

      if (flow)
        {
          typename IncompressibleFlow<dim>::Parameters fp;
          fp.parse_parameters(prm);
          auto l = IncompressibleFlow<dim>::material_limits(fp, h, mat.density);
          // At rest, the gravity wave limits the convective step.
          l.convective              = g > 0 ? fp.cfl * h / std::sqrt(g * h) :
                                              std::numeric_limits<double>::infinity();
          const double       wanted = fp.time_step > 0 ? fp.time_step : l.min();
          const double       dt     = dt_T > 0 ? dt_T : wanted;
          const double       n      = std::ceil(dt / wanted * (1 - 1e-12));
          const unsigned int bound  = run_limit_substeps(prm, true);
          const std::string  name   = "Run limits/Maximum flow sub-steps";
          if (fp.time_step > 0)
            require_substeps(n,
                             bound,
                             name,
                             "Melt flow/Time step",
                             fp.time_step,
                             "the flow sub-step",
                             wanted,
                             dt);
          else if (l.governing() == 1)
            require_substeps(n,
                             bound,
                             name,
                             "Melt flow/Viscosity",
                             fp.viscosity,
                             "the viscous limit h^2 rho/(2 dim mu) of the "
                             "flow sub-step (a molten metal has about 1e-3 "
                             "to 1e-2 Pa s)",
                             wanted,
                             dt);
          else if (l.governing() == 2)
            require_substeps(n,
                             bound,
                             name,
                             "Melt flow/Surface tension",
                             fp.surface_tension,
                             "the capillary limit sqrt(rho h^3/(2 pi sigma)) "
                             "of the flow sub-step (a molten metal has about "
                             "0.5 to 2 N/m)",
                             wanted,
                             dt);
          else
            require_substeps(n,
                             bound,
                             name,
                             "Physics/Gravity",
                             g,
                             "the gravity-wave limit cfl h/sqrt(g h) of the "
                             "flow sub-step (on Earth g = 9.81 m/s^2)",
                             wanted,
                             dt);
        }
      if (solid && dt_T > 0)
        {
          SolidMaterial sm(mat);
          sm.parse_parameters(prm);
          typename SolidSubCycle<dim>::Parameters sp;
          sp.parse_parameters(prm);
          const double limit = sp.stable_limit(sm, h);
          const double dt_s =
            sp.time_step > 0 ? sp.time_step : sp.safety_factor * limit;
          const double n = std::ceil(dt_T / dt_s * (1 - 1e-12));
          if (sp.time_step > 0)
            require_substeps(n,
                             run_limit_substeps(prm, false),
                             "Run limits/Maximum solid sub-steps",
                             "Solid/Time step",
                             sp.time_step,
                             "the solid sub-step",
                             dt_s,
                             dt_T);
          else
            {
              std::ostringstream why;
              why << "with the largest P-wave modulus "
                  << sm.max_p_wave_modulus() << " Pa and density "
                  << sm.density() << " kg/m^3 the elastic limit h/(sqrt(dim) "
                  << "c) of the solid sub-step (a metal has a Young's "
                     "modulus of about 1e10 to 5e11 Pa; 'Solid/Mass scaling "
                     "factor' raises the step)";
              require_substeps(n,
                               unsigned(run_limit_substeps(prm, false)),
                               "Run limits/Maximum solid sub-steps",
                               "Solid/Material/Young's modulus",
                               sm.max_p_wave_modulus(),
                               why.str(),
                               dt_s,
                               dt_T);
            }
        }
    }
  } // namespace

  void
  check_step_floors(dealii::ParameterHandler &prm)
  {
    if (prm.get_integer("Dimension") == 2)
      check_step_floors_dim<2>(prm);
    else
      check_step_floors_dim<3>(prm);
  }
} // namespace femp
