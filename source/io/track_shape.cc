// femp: the track's surface height, bead width and bead height (see the
// header and doc/cases.md, "Bead shape").
#include <deal.II/base/mpi.h>
#include <deal.II/base/utilities.h>

#include <femp/base/input_checks.h>
#include <femp/base/parameter_table.h>
#include <femp/io/output_files.h>
#include <femp/io/track_shape.h>

#include <iomanip>

namespace femp
{
  template <int dim>
  void
  TrackShape<dim>::Parameters::add_parameters(ParameterTable &table)
  {
    ParameterHandler &prm = table.handler();
    table.enter_subsection("Output");
    table.enter_subsection("Track shape");
    table.add("Write",
              write,
              {{AutoSwitch::automatic, "auto"},
               {AutoSwitch::on, "true"},
               {AutoSwitch::off, "false"}},
              "Write the track's shape at every field output: "
              "track_shape_<n>.csv (the height z_s of the metal's top "
              "surface, alpha = 1/2 interpolated along z, in every "
              "grid column along the track's centre line and across "
              "it at each 'Cross sections' position, with the bead "
              "mark) and one row of track_bead.csv (the re-solidified "
              "bead's length and height on the centre line, width "
              "and height in each cross-section, m; doc/cases.md). "
              "auto: with Physics/Melt flow. The centre line is the "
              "column of cells that contains the start point of the "
              "laser's first segment.");
    if (table.declaring())
      prm.declare_entry("Cross sections",
                        "",
                        Patterns::Anything(),
                        "Positions x (m) of the cross-sections across the "
                        "track (3D), separated by ','; each is the column of "
                        "cells that contains x, inside the domain. Empty: one "
                        "section at the middle of the laser's first segment.");
    table.leave_subsection();
    table.leave_subsection();
  }

  template <int dim>
  void
  TrackShape<dim>::Parameters::declare_parameters(ParameterHandler &prm)
  {
    Parameters     defaults;
    ParameterTable table(prm, ParameterTable::Mode::declare);
    defaults.add_parameters(table);
  }

  template <int dim>
  void
  TrackShape<dim>::Parameters::parse_parameters(ParameterHandler &prm)
  {
    ParameterTable table(prm, ParameterTable::Mode::parse);
    add_parameters(table);
    prm.enter_subsection("Output");
    prm.enter_subsection("Track shape");
    cross_sections.clear();
    for (const auto &s :
         Utilities::split_string_list(prm.get("Cross sections"), ','))
      {
        double x = 0;
        try
          {
            std::size_t end = 0;
            x               = std::stod(s, &end);
            require(end == s.size(),
                    "Output/Track shape/Cross sections",
                    s,
                    "a list of positions x in m, separated by ','");
          }
        catch (const std::logic_error &)
          {
            throw InputError("Output/Track shape/Cross sections",
                             s,
                             "a list of positions x in m, separated by ','");
          }
        cross_sections.push_back(x);
      }
    prm.leave_subsection();
    prm.leave_subsection();
    require(dim == 3 || cross_sections.empty(),
            "Output/Track shape/Cross sections",
            cross_sections.size(),
            "cross-sections need a 3D scene; leave the list empty in 2D");
  }

  template <int dim>
  TrackShape<dim>::TrackShape(const Parameters          &prm,
                              const BackgroundGrid<dim> &grid,
                              const double               centre_y,
                              const double               substrate_top,
                              const double               default_x)
      : grid(grid)
      , z_top(substrate_top)
  {
    const auto  &n  = grid.n_cells();
    const auto  &x0 = grid.origin();
    const double h  = grid.h();
    // Centre line: every i at the row j0 of the centre line (2D: j = 0).
    Point<dim> c = x0;
    if (dim == 3)
      c[1] = centre_y;
    const int j0 = dim == 3 ? grid.cell_of(c)[1] : 0;
    names.push_back("centre");
    columns.emplace_back();
    for (int i = 0; i < int(n[0]); ++i)
      columns.back().push_back({{i, j0}});
    if (dim == 3)
      {
        auto xs = prm.cross_sections;
        if (xs.empty())
          xs.push_back(default_x);
        for (const double x : xs)
          {
            require(x >= x0[0] && x < x0[0] + n[0] * h,
                    "Output/Track shape/Cross sections",
                    x,
                    "each position must lie inside the domain along x, [" +
                      num(x0[0]) + ", " + num(x0[0] + n[0] * h) + ") m");
            Point<dim> p = x0;
            p[0]         = x;
            const int i  = grid.cell_of(p)[0];
            names.push_back("cross_" + std::to_string(names.size()));
            columns.emplace_back();
            for (int j = 0; j < int(n[1]); ++j)
              columns.back().push_back({{i, j}});
          }
      }
  }

  template <int dim>
  std::vector<double>
  TrackShape<dim>::resolidified_cells(const MaterialPoints<dim> &points,
                                      const double T_liquidus) const
  {
    using P = typename MaterialPoints<dim>::PropertyIndex;
    std::vector<double> n_all(grid.n_local(), 0.), n_bead(grid.n_local(), 0.);
    for (const auto &particle : points.particle_handler())
      {
        const auto ijk = grid.cell_of(particle.get_location());
        if (!grid.in_box(ijk))
          continue;
        const auto idx = grid.local_index(ijk);
        const auto v   = particle.get_properties();
        n_all[idx] += 1;
        if (v[P::state] == MaterialPoints<dim>::solid &&
            v[P::peak_temperature] >= T_liquidus)
          n_bead[idx] += 1;
      }
    std::vector<double> mark(grid.n_local(), 0.);
    for (std::size_t i = 0; i < mark.size(); ++i)
      mark[i] = n_all[i] > 0 && 2 * n_bead[i] >= n_all[i] ? 1. : 0.;
    return mark;
  }

  template <int dim>
  double
  TrackShape<dim>::surface_height(const double *alpha) const
  {
    const int    nz = grid.n_cells()[dim - 1];
    const double h  = grid.h();
    const double z0 = grid.origin()[dim - 1];
    for (int k = nz - 1; k >= 0; --k)
      if (alpha[k] >= 0.5)
        {
          if (k == nz - 1)
            return z0 + nz * h;
          const double zc = z0 + (k + 0.5) * h;
          return zc + h * (alpha[k] - 0.5) / (alpha[k] - alpha[k + 1]);
        }
    return z0;
  }

  template <int dim>
  std::vector<typename TrackShape<dim>::Section>
  TrackShape<dim>::measure(const std::vector<double> &alpha,
                           const std::vector<double> &resolidified) const
  {
    // Gather the columns' alpha and bead marks: each owned cell adds its
    // value, the others 0, so the sum is exact on every rank.
    const int    nz    = grid.n_cells()[dim - 1];
    const double h     = grid.h();
    const auto  &x0    = grid.origin();
    std::size_t  n_col = 0;
    for (const auto &s : columns)
      n_col += s.size();
    std::vector<double> a(n_col * nz, 0.), b(n_col * nz, 0.);
    const auto         &status = grid.cell_status();
    std::size_t         offset = 0;
    for (const auto &s : columns)
      {
        for (std::size_t c = 0; c < s.size(); ++c)
          for (int k = 0; k < nz; ++k)
            {
              std::array<int, dim> ijk;
              ijk[0]       = s[c][0];
              ijk[dim - 1] = k;
              if (dim == 3)
                ijk[1] = s[c][1];
              if (!grid.in_box(ijk))
                continue;
              const auto idx = grid.local_index(ijk);
              if (status[idx] != BackgroundGrid<dim>::owned)
                continue;
              a[(offset + c) * nz + k] = alpha[idx];
              b[(offset + c) * nz + k] = resolidified[idx];
            }
        offset += s.size();
      }
    MPI_Allreduce(MPI_IN_PLACE,
                  a.data(),
                  a.size(),
                  MPI_DOUBLE,
                  MPI_SUM,
                  grid.communicator());
    MPI_Allreduce(MPI_IN_PLACE,
                  b.data(),
                  b.size(),
                  MPI_DOUBLE,
                  MPI_SUM,
                  grid.communicator());

    std::vector<Section> result;
    offset = 0;
    for (std::size_t s = 0; s < columns.size(); ++s)
      {
        Section sec;
        sec.name = names[s];
        int lo = -1, hi = -1;
        for (std::size_t c = 0; c < columns[s].size(); ++c)
          {
            const double *ac = &a[(offset + c) * nz];
            const double *bc = &b[(offset + c) * nz];
            sec.x.push_back(x0[0] + (columns[s][c][0] + 0.5) * h);
            sec.y.push_back(dim == 3 ? x0[1] + (columns[s][c][1] + 0.5) * h :
                                       0.);
            sec.surface.push_back(surface_height(ac));
            int bead = 0;
            for (int k = 0; k < nz; ++k)
              if (x0[dim - 1] + (k + 0.5) * h > z_top && ac[k] >= 0.5 &&
                  bc[k] > 0.5)
                bead = 1;
            sec.bead.push_back(bead);
            if (bead)
              {
                if (lo < 0)
                  lo = c;
                hi         = c;
                sec.height = std::max(sec.height, sec.surface.back() - z_top);
              }
          }
        if (lo >= 0)
          sec.width = (hi - lo + 1) * h;
        offset += columns[s].size();
        result.push_back(std::move(sec));
      }
    return result;
  }

  template <int dim>
  void
  TrackShape<dim>::write(const std::string          &directory,
                         const unsigned int          n,
                         const double                time,
                         const std::vector<Section> &sections)
  {
    if (Utilities::MPI::this_mpi_process(grid.communicator()) != 0)
      return;
    const std::string file =
      directory + "/track_shape_" + Utilities::int_to_string(n, 5) + ".csv";
    std::ofstream out(file);
    check_stream(out, file);
    out << "# time = " << std::setprecision(8) << time
        << " s; substrate top z = " << z_top << " m\n"
        << "section,x,y,surface_z,height,bead\n";
    for (const auto &s : sections)
      for (std::size_t c = 0; c < s.surface.size(); ++c)
        out << s.name << ',' << s.x[c] << ',' << s.y[c] << ',' << s.surface[c]
            << ',' << s.surface[c] - z_top << ',' << s.bead[c] << '\n';
    out.close();
    check_stream(out, file);

    const std::string series = directory + "/track_bead.csv";
    if (!bead_csv.is_open())
      {
        bead_csv.open(series);
        bead_csv << "time,centre_length,centre_height";
        for (std::size_t s = 1; s < sections.size(); ++s)
          bead_csv << ",width_x" << std::setprecision(6) << sections[s].x[0]
                   << ",height_x" << sections[s].x[0];
        bead_csv << '\n';
      }
    bead_csv << std::setprecision(8) << time;
    for (const auto &s : sections)
      bead_csv << ',' << s.width << ',' << s.height;
    bead_csv << '\n';
    bead_csv.flush();
    check_stream(bead_csv, series);
  }

  template class TrackShape<2>;
  template class TrackShape<3>;
} // namespace femp
