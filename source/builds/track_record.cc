// femp: per track and per layer, the bead height and width, the re-melt
// depth and the overlap of neighbouring fusion zones (see the header and
// doc/builds.md, "Tracks and layers").
#include <deal.II/base/mpi.h>
#include <deal.II/base/utilities.h>

#include <femp/builds/track_record.h>
#include <femp/io/output_files.h>

#include <algorithm>
#include <cmath>
#include <iomanip>

namespace femp
{
  template <int dim>
  void
  TrackRecord<dim>::Parameters::add_parameters(ParameterTable &table)
  {
    table.enter_subsection("Build");
    table.add(
      "Track report",
      report,
      {{AutoSwitch::automatic, "auto"},
       {AutoSwitch::on, "true"},
       {AutoSwitch::off, "false"}},
      "Measure every track of the scan path (a run of segments with the "
      "laser on) when the next one starts, or the next layer, or the run "
      "ends: tracks.csv (per track: layer, times, bead height, width, "
      "re-melt depth below the layer's base, overlap with the previous "
      "track of the layer, m), layers.csv (their means per layer) and the "
      "probe lines after each track (probe_line_<name>_track_<n>.csv) and "
      "at the end (probe_line_<name>_end.csv); doc/builds.md \"Tracks and "
      "layers\". auto: with a scan path of more than one track or a layer "
      "schedule.");
    table.leave_subsection();
  }

  template <int dim>
  void
  TrackRecord<dim>::Parameters::declare_parameters(ParameterHandler &prm)
  {
    Parameters     defaults;
    ParameterTable table(prm, ParameterTable::Mode::declare);
    defaults.add_parameters(table);
  }

  template <int dim>
  void
  TrackRecord<dim>::Parameters::parse_parameters(ParameterHandler &prm)
  {
    ParameterTable table(prm, ParameterTable::Mode::parse);
    add_parameters(table);
  }

  template <int dim>
  std::vector<typename TrackRecord<dim>::Track>
  TrackRecord<dim>::find_tracks(
    const std::vector<typename Laser<dim>::Segment> &segments,
    const std::vector<double>                       &layer_starts)
  {
    std::vector<Track> tracks;
    for (std::size_t i = 0; i < segments.size();)
      {
        if (!(segments[i].power > 0))
          {
            ++i;
            continue;
          }
        Track t;
        t.a           = segments[i].start;
        t.t_start     = segments[i].t_begin;
        std::size_t j = i;
        while (j + 1 < segments.size() && segments[j + 1].power > 0)
          ++j;
        t.b     = segments[j].end;
        t.t_end = segments[j].t_end;
        t.layer = 1;
        for (const double s : layer_starts)
          if (s <= t.t_start)
            ++t.layer;
        t.in_layer = (!tracks.empty() && tracks.back().layer == t.layer) ?
                       tracks.back().in_layer + 1 :
                       1;
        tracks.push_back(t);
        i = j + 1;
      }
    // A record closes where the next track starts, or before it where a
    // layer (its recoat) starts in between.
    for (std::size_t k = 0; k + 1 < tracks.size(); ++k)
      {
        tracks[k].t_close = tracks[k + 1].t_start;
        for (const double s : layer_starts)
          if (s > tracks[k].t_start && s < tracks[k].t_close)
            tracks[k].t_close = s;
      }
    return tracks;
  }

  template <int dim>
  TrackRecord<dim>::TrackRecord(const BackgroundGrid<dim> &grid,
                                const std::vector<Track>  &tracks,
                                const double               T_solidus,
                                const std::string         &directory)
      : grid(grid)
      , list(tracks)
      , T_solidus(T_solidus)
      , directory(directory)
      , peak(grid.make_field(0.))
  {
  }

  template <int dim>
  bool
  TrackRecord<dim>::due(const double t_next) const
  {
    return (is_open && list[open_track].t_close < t_next) ||
           (next_track < list.size() && list[next_track].t_start < t_next);
  }

  template <int dim>
  std::vector<typename TrackRecord<dim>::Row>
  TrackRecord<dim>::update(const double               time,
                           const double               t_next,
                           const std::vector<double> &fused,
                           const std::vector<double> &T)
  {
    std::vector<Row> out;
    if (is_open && list[open_track].t_close < t_next)
      out.push_back(close(time, fused, T));
    while (next_track < list.size() && list[next_track].t_start < t_next)
      {
        // Two tracks starting in one step: the first one's record holds
        // nothing but is closed all the same.
        if (is_open)
          out.push_back(close(time, fused, T));
        open_track = next_track++;
        is_open    = true;
        // Metal still molten from an earlier track (at or above the
        // solidus now) is not this track's until it has solidified: marked
        // -1 until then (observe()).
        std::fill(peak.begin(), peak.end(), 0.);
        for (const auto i : grid.owned_cells())
          if (T[i] >= T_solidus)
            peak[i] = -1.;
        if (list[open_track].in_layer == 1)
          {
            base         = surface(global(fused));
            has_previous = false;
          }
      }
    return out;
  }

  template <int dim>
  void
  TrackRecord<dim>::observe(const std::vector<double> &T,
                            const std::vector<double> &alpha)
  {
    if (!is_open)
      return;
    for (const auto i : grid.owned_cells())
      {
        if (peak[i] < 0)
          {
            // Molten since the record opened: this track's once solid.
            if (T[i] >= T_solidus)
              continue;
            peak[i] = 0.;
          }
        if (alpha[i] >= 0.5)
          peak[i] = std::max(peak[i], T[i]);
      }
  }

  template <int dim>
  std::vector<typename TrackRecord<dim>::Row>
  TrackRecord<dim>::finish(const double               time,
                           const std::vector<double> &fused,
                           const std::vector<double> &T)
  {
    std::vector<Row> out;
    if (is_open)
      out.push_back(close(time, fused, T));
    return out;
  }

  template <int dim>
  typename TrackRecord<dim>::Row
  TrackRecord<dim>::close(const double               time,
                          const std::vector<double> &fused,
                          const std::vector<double> &T)
  {
    auto       g_peak = global(peak);
    const auto top    = surface(global(fused));
    Row        r      = measure(open_track,
                    g_peak,
                    has_previous ? previous_peak : std::vector<double>(),
                    base,
                    top,
                    global(T));
    r.t_measured      = time;
    rows.push_back(r);
    write_files();
    previous_peak  = std::move(g_peak);
    previous_track = open_track;
    has_previous   = true;
    is_open        = false;
    return r;
  }

  template <int dim>
  std::vector<double>
  TrackRecord<dim>::global(const std::vector<double> &local) const
  {
    const auto         &N = grid.n_cells();
    std::vector<double> g(grid.n_global_cells(),
                          std::numeric_limits<double>::lowest());
    grid.for_each_owned_cell(
      [&](const std::size_t idx, const std::array<int, dim> &ijk) {
        std::size_t flat = 0;
        for (int d = dim - 1; d >= 0; --d)
          flat = flat * N[d] + ijk[d];
        g[flat] = local[idx];
      });
    const int ierr = MPI_Allreduce(MPI_IN_PLACE,
                                   g.data(),
                                   static_cast<int>(g.size()),
                                   MPI_DOUBLE,
                                   MPI_MAX,
                                   grid.communicator());
    AssertThrowMPI(ierr);
    return g;
  }

  namespace
  {
    // Cell-centred (bi)linear interpolation in the horizontal plane:
    // the lower cell and the weight of the upper one along direction d.
    inline void
    stencil(const double x,
            const double x0,
            const double h,
            const int    n,
            int         &i,
            double      &t)
    {
      const double u = (x - x0) / h - 0.5;
      if (n < 2)
        {
          i = 0;
          t = 0;
          return;
        }
      i = std::min(std::max(static_cast<int>(std::floor(u)), 0), n - 2);
      t = std::min(std::max(u - i, 0.), 1.);
    }
  } // namespace

  template <int dim>
  std::vector<double>
  TrackRecord<dim>::surface(const std::vector<double> &fused) const
  {
    const auto         &N  = grid.n_cells();
    const int           nz = N[dim - 1];
    const double        h  = grid.h();
    const double        z0 = grid.origin()[dim - 1];
    const std::size_t   nc = fused.size() / nz;
    std::vector<double> z(nc, z0);
    for (std::size_t c = 0; c < nc; ++c)
      for (int r = nz - 1; r >= 0; --r)
        {
          const double f = fused[c + nc * r];
          if (f < 0.5)
            continue;
          const double zc = z0 + (r + 0.5) * h;
          if (r == nz - 1)
            z[c] = zc + 0.5 * h;
          else
            {
              const double f1 = fused[c + nc * (r + 1)];
              z[c]            = zc + h * (f - 0.5) / (f - f1);
            }
          break;
        }
    return z;
  }

  template <int dim>
  typename TrackRecord<dim>::Row
  TrackRecord<dim>::measure(const unsigned int         k,
                            const std::vector<double> &g_peak,
                            const std::vector<double> &g_previous,
                            const std::vector<double> &g_base,
                            const std::vector<double> &g_top,
                            const std::vector<double> &g_T) const
  {
    const Track      &tr  = list[k];
    const auto       &N   = grid.n_cells();
    const double      h   = grid.h();
    const Point<dim>  x0  = grid.origin();
    const int         nz  = N[dim - 1];
    const std::size_t nc  = g_peak.size() / nz; // cells per row
    const double      Ts  = T_solidus;
    const double      nan = std::numeric_limits<double>::quiet_NaN();

    Row r;
    r.layer    = tr.layer;
    r.track    = k + 1;
    r.in_layer = tr.in_layer;
    r.t_start  = tr.t_start;
    r.t_end    = tr.t_end;

    // The horizontal axis: unit vector e along the track, n across it.
    double       ex = tr.b[0] - tr.a[0], ey = dim == 3 ? tr.b[1] - tr.a[1] : 0.;
    const double L = std::sqrt(ex * ex + ey * ey);
    r.length       = L;
    if (L > 0)
      ex /= L, ey /= L;
    else
      ex = 1, ey = 0;
    const double nx_ = -ey, ny_ = ex;

    // Value of a global field at horizontal position (x, y) in row kz
    // (kz < 0: a column field).
    auto value = [&](const std::vector<double> &g,
                     const int                  kz,
                     const double               x,
                     const double               y) {
      int    i = 0, j = 0;
      double s = 0, t = 0;
      stencil(x, x0[0], h, N[0], i, s);
      const std::size_t off = kz < 0 ? 0 : nc * kz;
      if (dim == 2)
        {
          const int i1 = N[0] > 1 ? i + 1 : i;
          return (1 - s) * g[off + i] + s * g[off + i1];
        }
      stencil(y, x0[1], h, N[1], j, t);
      const int         i1 = N[0] > 1 ? i + 1 : i, j1 = N[1] > 1 ? j + 1 : j;
      const std::size_t nx = N[0];
      return (1 - t) *
               ((1 - s) * g[off + i + nx * j] + s * g[off + i1 + nx * j]) +
             t * ((1 - s) * g[off + i + nx * j1] + s * g[off + i1 + nx * j1]);
    };
    auto inside = [&](const double x, const double y) {
      if (x < x0[0] || x > x0[0] + N[0] * h)
        return false;
      return dim == 2 || (y >= x0[1] && y <= x0[1] + N[1] * h);
    };
    auto zc = [&](const int kz) { return x0[dim - 1] + (kz + 0.5) * h; };
    // The lowest point of the fusion zone in the column at (x, y): the
    // solidus crossing below the lowest row that reached it (NaN: none).
    auto bottom = [&](const double x, const double y) {
      for (int kz = 0; kz < nz; ++kz)
        {
          const double v = value(g_peak, kz, x, y);
          if (v < Ts)
            continue;
          if (kz == 0)
            return x0[dim - 1];
          const double v0 = value(g_peak, kz - 1, x, y);
          return zc(kz) - h * (v - Ts) / (v - v0);
        }
      return nan;
    };

    // The previous track of the layer, when parallel to this one (a
    // hatch): its overlap.
    bool parallel = false;
    if (dim == 3 && !g_previous.empty() && k > 0)
      {
        const Track &pt = list[k - 1];
        const double px = pt.b[0] - pt.a[0], py = pt.b[1] - pt.a[1];
        const double pl = std::sqrt(px * px + py * py);
        parallel        = pl > 0 && std::abs(px * ex + py * ey) > 0.99 * pl;
      }

    // Sections over the middle half, one per cell size along the track;
    // lateral samples every h / 2 (3D).
    const unsigned int m  = std::max(1, int(std::lround(0.5 * L / h)));
    const double       dw = 0.5 * h;
    const int    J     = dim == 3 ? int(std::ceil((N[0] + N[1]) * h / dw)) : 0;
    double       sum_w = 0, sum_d = 0, sum_h = 0, sum_o = 0;
    unsigned int n_sec = 0;
    double       T_max = 0;
    std::vector<double> v(2 * J + 1), vp(2 * J + 1);
    std::vector<char>   ok(2 * J + 1);
    for (unsigned int q = 0; q < m; ++q)
      {
        const double s  = 0.25 * L + (q + 0.5) * 0.5 * L / m;
        const double cx = tr.a[0] + s * ex;
        const double cy = dim == 3 ? tr.a[1] + s * ey : 0.;
        auto         px = [&](const int j) { return cx + (j - J) * dw * nx_; };
        auto         py = [&](const int j) { return cy + (j - J) * dw * ny_; };
        for (int j = 0; j <= 2 * J; ++j)
          ok[j] = inside(px(j), py(j));
        // The run of samples at or above Ts around sample c0 in @p val:
        // its interpolated ends (false: c0 is below Ts).
        auto run = [&](const std::vector<double> &val,
                       const int                  c0,
                       double                    &lo,
                       double                    &hi) {
          if (c0 < 0 || c0 > 2 * J || !ok[c0] || val[c0] < Ts)
            return false;
          int jl = c0, jh = c0;
          while (jl > 0 && ok[jl - 1] && val[jl - 1] >= Ts)
            --jl;
          while (jh < 2 * J && ok[jh + 1] && val[jh + 1] >= Ts)
            ++jh;
          lo = (jl - J) * dw;
          hi = (jh - J) * dw;
          if (jl > 0 && ok[jl - 1])
            lo -= dw * (val[jl] - Ts) / (val[jl] - val[jl - 1]);
          if (jh < 2 * J && ok[jh + 1])
            hi += dw * (val[jh] - Ts) / (val[jh] - val[jh + 1]);
          return true;
        };
        // Width: the widest row of the fusion zone around the axis, and
        // the overlap with the previous track's zone in the same rows.
        double width = 0, band_lo = 0, band_hi = 0, overlap = 0;
        bool   melted = false;
        int    cp     = -1;
        if (dim == 3 && parallel)
          {
            const Track &pt = list[k - 1];
            const double wp =
              (pt.a[0] - cx) * nx_ + (dim == 3 ? (pt.a[1] - cy) * ny_ : 0.);
            cp = J + int(std::lround(wp / dw));
          }
        for (int kz = 0; kz < nz; ++kz)
          {
            for (int j = 0; j <= 2 * J; ++j)
              if (ok[j])
                {
                  v[j] = value(g_peak, kz, px(j), py(j));
                  if (cp >= 0)
                    vp[j] = value(g_previous, kz, px(j), py(j));
                }
            double lo = 0, hi = 0;
            if (!run(v, J, lo, hi))
              continue;
            if (!melted || hi - lo > width)
              width = hi - lo, band_lo = lo, band_hi = hi;
            melted     = true;
            double plo = 0, phi = 0;
            if (cp >= 0 && run(vp, cp, plo, phi))
              overlap =
                std::max(overlap, std::min(hi, phi) - std::max(lo, plo));
          }
        if (!melted)
          continue;
        ++n_sec;
        sum_w += width;
        sum_o += overlap;
        // Re-melt depth over the band; bead height over its middle half.
        double       depth = -std::numeric_limits<double>::infinity();
        double       bead  = -std::numeric_limits<double>::infinity();
        const double mid   = 0.5 * (band_lo + band_hi);
        for (int j = 0; j <= 2 * J; ++j)
          {
            const double w = (j - J) * dw;
            if (!ok[j] || w < band_lo - 1e-12 * h || w > band_hi + 1e-12 * h)
              continue;
            const double x = px(j), y = py(j);
            const double zb = value(g_base, -1, x, y);
            const double b  = bottom(x, y);
            if (!std::isnan(b))
              depth = std::max(depth, zb - b);
            if (std::abs(w - mid) <= 0.25 * (band_hi - band_lo) + 1e-12 * h)
              bead = std::max(bead, value(g_top, -1, x, y) - zb);
            for (int kz = 0; kz < nz; ++kz)
              if (value(g_peak, kz, x, y) >= Ts)
                T_max = std::max(T_max, value(g_T, kz, x, y));
          }
        sum_d += depth;
        sum_h += bead;
      }
    r.sections = n_sec;
    r.T_max    = T_max;
    if (n_sec == 0)
      {
        r.width = r.remelt_depth = r.bead_height = r.overlap = r.overlap_ratio =
          nan;
        return r;
      }
    r.remelt_depth = sum_d / n_sec;
    r.bead_height  = sum_h / n_sec;
    if (dim == 2)
      r.width = r.overlap = r.overlap_ratio = nan;
    else
      {
        r.width = sum_w / n_sec;
        if (!parallel)
          r.overlap = r.overlap_ratio = nan;
        else
          {
            r.overlap       = sum_o / n_sec;
            r.overlap_ratio = r.width > 0 ? r.overlap / r.width : nan;
          }
      }
    return r;
  }

  template <int dim>
  void
  TrackRecord<dim>::write_files() const
  {
    if (Utilities::MPI::this_mpi_process(grid.communicator()) != 0)
      return;
    {
      const std::string file = directory + "/tracks.csv";
      std::ofstream     out(file);
      check_stream(out, file);
      out << "layer,track,track_in_layer,t_start,t_end,t_measured,length,"
             "bead_height,width,remelt_depth,overlap,overlap_ratio,"
             "T_max_fusion_zone,sections\n";
      out << std::setprecision(6);
      for (const auto &r : rows)
        out << r.layer << ',' << r.track << ',' << r.in_layer << ','
            << r.t_start << ',' << r.t_end << ',' << r.t_measured << ','
            << r.length << ',' << r.bead_height << ',' << r.width << ','
            << r.remelt_depth << ',' << r.overlap << ',' << r.overlap_ratio
            << ',' << r.T_max << ',' << r.sections << '\n';
    }
    // Per layer once all its tracks are measured: means over its tracks
    // (the overlap over those with a previous track), the least re-melt.
    const std::string file = directory + "/layers.csv";
    std::ofstream     out(file);
    check_stream(out, file);
    out << "layer,tracks,t_start,t_end,bead_height,width,remelt_depth,"
           "remelt_depth_min,overlap_ratio\n";
    out << std::setprecision(6);
    const unsigned int n_layers = list.empty() ? 0 : list.back().layer;
    for (unsigned int l = 1; l <= n_layers; ++l)
      {
        unsigned int n = 0, done = 0, n_o = 0;
        double       t0 = 0, t1 = 0, bh = 0, w = 0, d = 0, o = 0;
        double       dmin = std::numeric_limits<double>::infinity();
        for (const auto &t : list)
          n += t.layer == l;
        for (const auto &r : rows)
          if (r.layer == l)
            {
              if (done++ == 0)
                t0 = r.t_start;
              t1 = r.t_end;
              bh += r.bead_height;
              w += r.width;
              d += r.remelt_depth;
              dmin = std::min(dmin, r.remelt_depth);
              if (!std::isnan(r.overlap_ratio))
                o += r.overlap_ratio, ++n_o;
            }
        if (n == 0 || done < n)
          continue;
        out << l << ',' << n << ',' << t0 << ',' << t1 << ',' << bh / n << ','
            << w / n << ',' << d / n << ',' << dmin << ','
            << (n_o > 0 ? o / n_o : std::numeric_limits<double>::quiet_NaN())
            << '\n';
      }
  }

  template <int dim>
  void
  TrackRecord<dim>::save_state(StateWriter &out) const
  {
    out.put(open_track);
    out.put(next_track);
    out.put(is_open);
    out.put(previous_track);
    out.put(has_previous);
    out.put_vector(global(peak));
    out.put_vector(previous_peak);
    out.put_vector(base);
    out.put_vector(rows);
  }

  template <int dim>
  void
  TrackRecord<dim>::load_state(StateReader &in)
  {
    open_track     = in.get<unsigned int>();
    next_track     = in.get<unsigned int>();
    is_open        = in.get<bool>();
    previous_track = in.get<unsigned int>();
    has_previous   = in.get<bool>();
    const auto g   = in.get_vector<double>();
    previous_peak  = in.get_vector<double>();
    base           = in.get_vector<double>();
    rows           = in.get_vector<Row>();
    const auto &N  = grid.n_cells();
    AssertThrow(g.size() == grid.n_global_cells(),
                ExcMessage("the track record of the checkpoint is of "
                           "another grid"));
    grid.for_each_owned_cell(
      [&](const std::size_t idx, const std::array<int, dim> &ijk) {
        std::size_t flat = 0;
        for (int d = dim - 1; d >= 0; --d)
          flat = flat * N[d] + ijk[d];
        peak[idx] = g[flat];
      });
    write_files();
  }

  template class TrackRecord<2>;
  template class TrackRecord<3>;
} // namespace femp
