// femp: readers for the scan-path files that AM users already have, turned
// into the list of straight segments that drives the laser source q_laser
// of eq. (1) (include/femp/heat/laser.h). Formats (doc/inputs.md):
//   adamantine_segment       3 header lines (the 2nd: number of segments),
//                            then 'mode x y z power_factor parameter'; mode 1
//                            = spot (parameter: dwell time, s), mode 0 = line
//                            (parameter: speed, m/s); the point is where the
//                            segment ends, power = factor x 'Laser/Power'.
//   adamantine_event_series  'time, x, y, z, power_factor' per line: the beam
//                            reaches (x, y, z) at that time; the factor holds
//                            from this event to the next one.
//   additivefoam             1 header line, then 'mode x y z power parameter'
//                            as above but with the power in W and an implied
//                            start at the origin at time 0; a spot (mode 1)
//                            holds the beam at its point.
// All coordinates in m, times in s (relative to 'Laser/Start time'). A
// segment with zero power is a dwell or a jump with the laser off; the
// vertical coordinate is the layer the segment belongs to.
#ifndef femp_scan_path_h
#define femp_scan_path_h

#include <femp/heat/laser.h>

#include <array>
#include <string>
#include <vector>

namespace femp
{
  /// One straight piece of a 3D scan path as read from a file: the beam
  /// axis moves from @p start to @p end (x, y, z in m) between @p t_begin and
  /// @p t_end (s) with constant power @p power (W; 0: laser off).
  struct ScanPathPiece
  {
    std::array<double, 3> start, end;
    double                power, t_begin, t_end;
  };

  /// Read @p file in @p format (not 'femp', which Laser reads itself). Times
  /// start at @p start_time; adamantine's power factors multiply
  /// @p nominal_power. Pieces of zero duration are dropped. Throws
  /// InputError naming 'Laser/Scan path file', the line and what is wrong.
  std::vector<ScanPathPiece>
  read_scan_path_pieces(const std::string   &file,
                        const ScanPathFormat format,
                        const double         nominal_power,
                        const double         start_time);

  /// femp's laser segments for a scene of dimension @p dim: in 3D (x, y, z)
  /// as read, in 2D (x, z); a 2D scene is one vertical plane y = const, so
  /// a path whose y varies is refused. @p file names the file in messages.
  template <int dim>
  std::vector<typename Laser<dim>::Segment>
  to_laser_segments(const std::vector<ScanPathPiece> &pieces,
                    const std::string                &file);

  /// Both steps: read @p file and map it to @p dim.
  template <int dim>
  std::vector<typename Laser<dim>::Segment>
  read_scan_path(const std::string   &file,
                 const ScanPathFormat format,
                 const double         nominal_power,
                 const double         start_time)
  {
    return to_laser_segments<dim>(
      read_scan_path_pieces(file, format, nominal_power, start_time), file);
  }

  /// Energy the beam emits along @p path (sum of power x duration), J (2D:
  /// J/m).
  template <int dim>
  double
  emitted_energy(const std::vector<typename Laser<dim>::Segment> &path)
  {
    double e = 0;
    for (const auto &s : path)
      e += s.power * (s.t_end - s.t_begin);
    return e;
  }
} // namespace femp

#endif
