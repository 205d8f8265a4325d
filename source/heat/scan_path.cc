// femp: readers for adamantine's 'segment' and 'event_series' scan paths and
// AdditiveFOAM's 'scanPath' files (formats in include/femp/heat/scan_path.h
// and doc/inputs.md); they give the segments of the laser path of eq. (1).
#include <femp/base/input_checks.h>
#include <femp/base/parameter_file.h>
#include <femp/heat/scan_path.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace femp
{
  namespace
  {
    const std::string parameter = "Laser/Scan path file";

    /// A line of the file, split at blanks and commas.
    struct Line
    {
      unsigned int             number = 0;
      std::string              text;
      std::vector<std::string> fields;
    };

    std::vector<std::string>
    split_fields(const std::string &text)
    {
      std::vector<std::string> fields;
      std::string              current;
      for (const char c : text)
        if (c == ' ' || c == '\t' || c == ',' || c == '\r')
          {
            if (!current.empty())
              fields.push_back(current);
            current.clear();
          }
        else
          current += c;
      if (!current.empty())
        fields.push_back(current);
      return fields;
    }

    /// All lines of @p file (blank lines and, after any header, lines
    /// starting with '#' are dropped by the readers).
    std::vector<Line>
    read_lines(const std::string &file)
    {
      std::ifstream in(file);
      require(static_cast<bool>(in), parameter, file, unopened_file(file));
      std::vector<Line> lines;
      std::string       text;
      unsigned int      n = 0;
      while (std::getline(in, text))
        lines.push_back({++n, text, split_fields(text)});
      return lines;
    }

    bool
    is_blank_or_comment(const Line &line)
    {
      return line.fields.empty() || line.fields[0][0] == '#';
    }

    std::string
    where(const std::string &file, const Line &line)
    {
      return file + ", line " + std::to_string(line.number) + ": '" +
             line.text + "'";
    }

    /// The numbers of a data line; it must hold exactly @p n of them.
    std::vector<double>
    numbers(const std::string &file,
            const Line        &line,
            const unsigned int n,
            const std::string &layout)
    {
      std::vector<double> v;
      bool                ok = line.fields.size() == n;
      for (unsigned int i = 0; ok && i < n; ++i)
        {
          std::size_t used = 0;
          try
            {
              v.push_back(std::stod(line.fields[i], &used));
            }
          catch (const std::exception &)
            {
              used = 0;
            }
          ok = used == line.fields[i].size() && std::isfinite(v.back()) &&
               std::abs(v.back()) <= 1e30;
        }
      require(ok,
              parameter,
              where(file, line),
              "each line must hold the " + std::to_string(n) + " numbers '" +
                layout + "', finite and at most 1e30 in magnitude (SI)");
      return v;
    }

    double
    distance(const std::array<double, 3> &a, const std::array<double, 3> &b)
    {
      return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) +
                       (a[1] - b[1]) * (a[1] - b[1]) +
                       (a[2] - b[2]) * (a[2] - b[2]));
    }

    /// Append the piece from @p from to @p to lasting @p duration, dropping
    /// pieces of zero duration (they only place the beam).
    void
    append(std::vector<ScanPathPiece>  &path,
           const std::array<double, 3> &from,
           const std::array<double, 3> &to,
           const double                 power,
           double                      &t,
           const double                 duration)
    {
      if (duration > 0)
        path.push_back({from, to, power, t, t + duration});
      t += duration;
    }

    /// adamantine 'segment' and AdditiveFOAM: 'mode x y z power parameter'.
    /// The two differ in the header, the power (factor or W), the start
    /// (first spot or the origin) and in what a spot does with a new point
    /// (adamantine moves the beam there during the dwell, AdditiveFOAM puts
    /// it there at once).
    std::vector<ScanPathPiece>
    read_mode_lines(const std::string &file,
                    const bool         adamantine,
                    const double       nominal_power,
                    const double       start_time)
    {
      const std::vector<Line> lines  = read_lines(file);
      const std::string       layout = adamantine ?
                                         "mode x y z power_factor parameter" :
                                         "mode x y z power parameter";
      std::size_t             first  = 1; // AdditiveFOAM: one header line
      unsigned int            count  = std::numeric_limits<unsigned int>::max();
      if (adamantine)
        {
          // Line 1: title; line 2: number of segments; line 3: column names.
          require(lines.size() >= 3,
                  parameter,
                  file,
                  "an adamantine 'segment' file starts with 3 header lines, "
                  "the second holding the number of segments");
          std::size_t used = 0;
          long        n    = -1;
          try
            {
              n = std::stol(lines[1].fields.empty() ? "" : lines[1].fields[0],
                            &used);
            }
          catch (const std::exception &)
            {
            }
          require(n > 0 && lines[1].fields.size() == 1 &&
                    used == lines[1].fields[0].size(),
                  parameter,
                  where(file, lines[1]),
                  "the second line of an adamantine 'segment' file must hold "
                  "the number of segments (a positive integer)");
          count = n;
          first = 3;
        }
      std::vector<ScanPathPiece> path;
      std::array<double, 3>      at{{0., 0., 0.}};
      double                     t      = start_time;
      unsigned int               n_read = 0;
      for (std::size_t i = first; i < lines.size() && n_read < count; ++i)
        {
          if (is_blank_or_comment(lines[i]))
            continue;
          const auto                  v = numbers(file, lines[i], 6, layout);
          const std::array<double, 3> p{{v[1], v[2], v[3]}};
          const double power = adamantine ? v[4] * nominal_power : v[4];
          require(v[0] == 0 || v[0] == 1,
                  parameter,
                  where(file, lines[i]),
                  "the mode must be 0 (line) or 1 (spot)");
          require(v[4] >= 0,
                  parameter,
                  where(file, lines[i]),
                  "the power must be non-negative");
          if (adamantine && n_read == 0)
            {
              require(v[0] == 1,
                      parameter,
                      where(file, lines[i]),
                      "an adamantine scan path must begin with a spot (mode "
                      "1), which places the beam");
              at = p;
            }
          if (v[0] == 1)
            {
              require(v[5] >= 0,
                      parameter,
                      where(file, lines[i]),
                      "a spot's dwell time (last column, s) must be "
                      "non-negative");
              if (!adamantine)
                at = p;
              append(path, at, p, power, t, v[5]);
            }
          else
            {
              require(v[5] > 0,
                      parameter,
                      where(file, lines[i]),
                      "a line's speed (last column, m/s) must be positive");
              append(path, at, p, power, t, distance(at, p) / v[5]);
            }
          at = p;
          ++n_read;
        }
      require(!adamantine || n_read == count,
              parameter,
              file,
              "the header announces " + std::to_string(count) +
                " segments but the file holds " + std::to_string(n_read));
      return path;
    }

    /// adamantine 'event_series': 'time x y z power_factor'; the beam moves
    /// from one event to the next with the earlier event's power factor,
    /// and sits at the first event's point, off, until its time.
    std::vector<ScanPathPiece>
    read_event_series(const std::string &file,
                      const double       nominal_power,
                      const double       start_time)
    {
      std::vector<ScanPathPiece> path;
      std::array<double, 3>      at{{0., 0., 0.}};
      double                     t_last = 0, power = 0;
      bool                       first = true;
      for (const Line &line : read_lines(file))
        {
          if (is_blank_or_comment(line))
            continue;
          const auto v = numbers(file, line, 5, "time x y z power_factor");
          const std::array<double, 3> p{{v[1], v[2], v[3]}};
          require(v[4] >= 0,
                  parameter,
                  where(file, line),
                  "the power factor must be non-negative");
          require(first ? v[0] >= 0 : v[0] >= t_last,
                  parameter,
                  where(file, line),
                  "the event times must be non-negative and non-decreasing");
          if (first)
            at = p;
          double t = start_time + t_last;
          append(path, at, p, power, t, v[0] - t_last);
          at     = p;
          t_last = v[0];
          power  = v[4] * nominal_power;
          first  = false;
        }
      return path;
    }
  } // namespace

  std::vector<ScanPathPiece>
  read_scan_path_pieces(const std::string   &file,
                        const ScanPathFormat format,
                        const double         nominal_power,
                        const double         start_time)
  {
    std::vector<ScanPathPiece> path;
    switch (format)
      {
        case ScanPathFormat::adamantine_segment:
          path = read_mode_lines(file, true, nominal_power, start_time);
          break;
        case ScanPathFormat::additivefoam:
          path = read_mode_lines(file, false, nominal_power, start_time);
          break;
        case ScanPathFormat::adamantine_event_series:
          path = read_event_series(file, nominal_power, start_time);
          break;
        case ScanPathFormat::femp:
          throw std::logic_error("femp: the 'femp' scan path format is read "
                                 "by Laser itself");
      }
    require(!path.empty(),
            parameter,
            file,
            "it must contain at least one segment of positive duration");
    return path;
  }

  template <int dim>
  std::vector<typename Laser<dim>::Segment>
  to_laser_segments(const std::vector<ScanPathPiece> &pieces,
                    const std::string                &file)
  {
    if (dim == 2)
      {
        // A 2D scene is the vertical plane y = const of a 3D path.
        double y_min = pieces[0].start[1], y_max = y_min;
        for (const auto &s : pieces)
          for (const auto &p : {s.start, s.end})
            {
              y_min = std::min(y_min, p[1]);
              y_max = std::max(y_max, p[1]);
            }
        require(y_max - y_min <= 1e-9,
                parameter,
                file + " (y from " + num(y_min) + " to " + num(y_max) + " m)",
                "a 2D scene is one vertical plane (x, z) of a 3D path, so "
                "every point of the path must have the same y (within 1 nm); "
                "run this path in a 3D scene, or give a path along x");
      }
    std::vector<typename Laser<dim>::Segment> path;
    for (const auto &s : pieces)
      {
        Point<dim> a, b;
        a[0] = s.start[0];
        b[0] = s.end[0];
        if (dim == 3)
          {
            a[1] = s.start[1];
            b[1] = s.end[1];
          }
        a[dim - 1]           = s.start[2];
        b[dim - 1]           = s.end[2];
        const double seconds = s.t_end - s.t_begin;
        path.push_back(
          {a, b, a.distance(b) / seconds, s.power, s.t_begin, s.t_end});
      }
    return path;
  }

  template std::vector<Laser<2>::Segment>
  to_laser_segments<2>(const std::vector<ScanPathPiece> &, const std::string &);
  template std::vector<Laser<3>::Segment>
  to_laser_segments<3>(const std::vector<ScanPathPiece> &, const std::string &);
} // namespace femp
