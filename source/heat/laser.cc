// femp: Gaussian laser source of eq. (1) and its scan path (segments read
// from the prm file or from a scan-path file).
#include <femp/base/input_checks.h>
#include <femp/base/parameter_file.h>
#include <femp/base/parameter_table.h>
#include <femp/heat/laser.h>
#include <femp/heat/scan_path.h>

#include <fstream>
#include <sstream>

namespace femp
{
  const Choices<ScanPathFormat> &
  scan_path_format_choices()
  {
    static const Choices<ScanPathFormat> choices = {
      {ScanPathFormat::femp, "femp"},
      {ScanPathFormat::adamantine_segment, "adamantine_segment"},
      {ScanPathFormat::adamantine_event_series, "adamantine_event_series"},
      {ScanPathFormat::additivefoam, "additivefoam"}};
    return choices;
  }

  template <int dim>
  void
  Laser<dim>::Parameters::add_parameters(ParameterTable &table)
  {
    ParameterHandler &prm = table.handler();
    table.enter_subsection("Laser");
    table.add("Power",
              power,
              Patterns::Double(0.),
              "Laser power P, W (in 2D: W per m of depth); range [0, inf).");
    table.add("Absorptivity",
              absorptivity,
              Patterns::Double(0., 1.),
              "Absorbed fraction eta of the laser power; range [0, 1].");
    table.add("Beam radius",
              beam_radius,
              Patterns::Double(0.),
              "1/e^2 radius r_b of the Gaussian beam, m; range (0, inf).");
    table.add("Scan speed",
              scan_speed,
              Patterns::Double(0.),
              "Speed of the beam along the line from 'Start point' to "
              "'End point', m/s; range (0, inf).");
    if (table.declaring())
      prm.declare_entry(
        "Start point",
        "1e-4, 2e-4, 0",
        Patterns::List(Patterns::Double(), 1, 3),
        "Horizontal position of the beam axis at the start time, "
        "m (the vertical coordinate is ignored).");
    if (table.declaring())
      prm.declare_entry("End point",
                        "9e-4, 2e-4, 0",
                        Patterns::List(Patterns::Double(), 1, 3),
                        "Horizontal position where the line scan ends and the "
                        "laser switches off, m.");
    table.add("Start time",
              start_time,
              Patterns::Double(0.),
              "Time at which the laser switches on, s; range [0, inf).");
    table.add("Scan path file",
              scan_path_file,
              Patterns::Anything(),
              "Optional file that replaces the single line: one segment "
              "per line, 'x0 y0 x1 y1 speed power' (3D) or 'x0 x1 speed "
              "power' (2D), m, m/s, W; power 0 moves the beam with the "
              "laser off. Segments follow each other in time from "
              "'Start time'. Lines starting with # are comments. A "
              "relative path is looked for next to the scene file (or "
              "included file) that sets it, then in the working "
              "directory; given with --set, in the working directory.");
    table.add("Scan path format",
              scan_path_format,
              scan_path_format_choices(),
              "Format of 'Scan path file': 'femp' (above), "
              "'adamantine_segment', 'adamantine_event_series' "
              "(adamantine's scan paths, power = factor x 'Power') "
              "or 'additivefoam' (AdditiveFOAM's scanPath, power in "
              "W, W/m in 2D). These hold x, y, z (m), dwells and "
              "jumps; a 2D scene takes (x, z) of a path at constant "
              "y. Times count from 'Start time'. See doc/inputs.md.");
    table.leave_subsection();
  }

  template <int dim>
  void
  Laser<dim>::Parameters::declare_parameters(ParameterHandler &prm)
  {
    Parameters     defaults;
    ParameterTable table(prm, ParameterTable::Mode::declare);
    defaults.add_parameters(table);
  }

  template <int dim>
  void
  Laser<dim>::Parameters::parse_parameters(ParameterHandler &prm)
  {
    ParameterTable table(prm, ParameterTable::Mode::parse);
    add_parameters(table);
    prm.enter_subsection("Laser");
    start_point = parse_point<dim>(prm.get("Start point"), "Laser/Start point");
    end_point   = parse_point<dim>(prm.get("End point"), "Laser/End point");
    prm.leave_subsection();
    require(beam_radius > 0,
            "Laser/Beam radius",
            beam_radius,
            "it must be positive (m)");
    require(scan_speed > 0,
            "Laser/Scan speed",
            scan_speed,
            "it must be positive (m/s)");
  }

  template <int dim>
  Laser<dim>::Laser(const Parameters &p)
      : prm(p)
      , inv_rb2(1. / (p.beam_radius * p.beam_radius))
  {
    double t   = prm.start_time;
    auto   add = [&](Point<dim> a, Point<dim> b, double speed, double power) {
      a[dim - 1] = b[dim - 1] = 0;
      const double len        = a.distance(b);
      path.push_back({a, b, speed, power, t, t + len / speed});
      t += len / speed;
    };
    if (prm.scan_path_file.empty())
      add(prm.start_point, prm.end_point, prm.scan_speed, prm.power);
    else if (prm.scan_path_format != ScanPathFormat::femp)
      path = read_scan_path<dim>(prm.scan_path_file,
                                 prm.scan_path_format,
                                 prm.power,
                                 prm.start_time);
    else
      {
        std::ifstream in(prm.scan_path_file);
        require(static_cast<bool>(in),
                "Laser/Scan path file",
                prm.scan_path_file,
                unopened_file(prm.scan_path_file));
        std::string line;
        unsigned    line_no = 0;
        while (std::getline(in, line))
          {
            ++line_no;
            const auto first = line.find_first_not_of(" \t\r");
            if (first == std::string::npos || line[first] == '#')
              continue;
            std::istringstream s(line);
            Point<dim>         a, b;
            double             speed = 0, power = -1;
            for (int d = 0; d < dim - 1; ++d)
              s >> a[d];
            for (int d = 0; d < dim - 1; ++d)
              s >> b[d];
            s >> speed >> power;
            require(!s.fail() && speed > 0 && power >= 0,
                    "Laser/Scan path file",
                    prm.scan_path_file + ", line " + std::to_string(line_no) +
                      ": '" + line + "'",
                    "each line must hold " + std::to_string(2 * (dim - 1) + 2) +
                      " numbers: start and end coordinates (m), a positive "
                      "speed (m/s) and a non-negative power (W)");
            add(a, b, speed, power);
          }
        require(!path.empty(),
                "Laser/Scan path file",
                prm.scan_path_file,
                "it must contain at least one segment");
      }
  }

  template <int dim>
  void
  Laser<dim>::check_path_inside(const Point<dim> &lower,
                                const Point<dim> &upper) const
  {
    const std::string name = prm.scan_path_file.empty() ?
                               std::string("Laser/End point") :
                               std::string("Laser/Scan path file");
    // Paths read in other formats carry their height (layer) too.
    const int n_checked = prm.scan_path_file.empty() ||
                              prm.scan_path_format == ScanPathFormat::femp ?
                            dim - 1 :
                            dim;
    for (const auto &s : path)
      for (const auto &p : {s.start, s.end})
        for (int d = 0; d < n_checked; ++d)
          {
            std::ostringstream v;
            v << p;
            require(p[d] >= lower[d] && p[d] <= upper[d],
                    name,
                    v.str(),
                    "the scan path must stay inside the " +
                      std::string(d < dim - 1 ? "horizontal" : "vertical") +
                      " extent of the domain (coordinate " + std::to_string(d) +
                      " in [" + num(lower[d]) + ", " + num(upper[d]) + "] m)");
          }
  }

  template <int dim>
  bool
  Laser<dim>::position(const double t, Point<dim> &axis, double &power) const
  {
    for (const auto &s : path)
      if (t >= s.t_begin && t < s.t_end)
        {
          const double w = (t - s.t_begin) / (s.t_end - s.t_begin);
          axis           = s.start + w * (s.end - s.start);
          power          = s.power;
          return s.power > 0;
        }
    return false;
  }

  template class Laser<2>;
  template class Laser<3>;
} // namespace femp
