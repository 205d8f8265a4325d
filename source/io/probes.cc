// femp: the probes of the output: values of cell fields at probe points
// (the containing cell's, or interpolated between cell centres weighted by
// the metal fraction) and the probe lines' CSV files (Output::sample() and
// Output::write_probe_lines(), declared in output.h).
#include <deal.II/base/mpi.h>
#include <deal.II/base/utilities.h>

#include <femp/io/output.h>
#include <femp/io/output_files.h>

#include <cmath>
#include <fstream>
#include <iomanip>

namespace femp
{
  template <int dim>
  std::vector<double>
  Output<dim>::sample(const std::vector<Point<dim>> &points,
                      const std::vector<Field>      &fields) const
  {
    // The owner of the cell that contains a point contributes its values;
    // everybody else adds zeros. With linear interpolation, the owner of
    // each of the 2^dim cells around the point adds its weighted values and
    // weight to a second block (owned cells only: no ghost values needed).
    const std::size_t   nf = fields.size();
    const std::size_t   np = points.size();
    const std::size_t   nw = nf + 1; // weighted sums of the fields and weight
    std::vector<double> v(np * nf + (prm.probe_linear ? np * nw : 0), 0.);
    const auto         &status = grid.cell_status();
    auto                owned  = [&](const std::array<int, dim> &ijk) {
      return grid.in_box(ijk) &&
             status[grid.local_index(ijk)] == BackgroundGrid<dim>::owned;
    };
    const std::vector<double> *alpha = nullptr;
    for (const auto &f : fields)
      if (f.name == "alpha")
        alpha = f.values;
    for (std::size_t i = 0; i < np; ++i)
      {
        const auto ijk = grid.cell_of(points[i]);
        if (owned(ijk))
          for (std::size_t f = 0; f < nf; ++f)
            v[i * nf + f] = (*fields[f].values)[grid.local_index(ijk)];
        if (!prm.probe_linear)
          continue;
        // Lower cell of the centre stencil and the local coordinates; at
        // the domain's faces the stencil shrinks to the boundary cell.
        std::array<int, dim>    lo;
        std::array<double, dim> t;
        for (int d = 0; d < dim; ++d)
          {
            const double s = (points[i][d] - grid.origin()[d]) / grid.h() - 0.5;
            const int    n = grid.n_cells()[d];
            lo[d]          = static_cast<int>(std::floor(s));
            t[d]           = s - lo[d];
            if (lo[d] < 0)
              lo[d] = 0, t[d] = 0;
            if (lo[d] >= n - 1)
              lo[d] = n - 1, t[d] = 0;
          }
        double *const acc = v.data() + np * nf + i * nw;
        for (unsigned int c = 0; c < (1u << dim); ++c)
          {
            std::array<int, dim> cell = lo;
            double               w    = 1;
            for (int d = 0; d < dim; ++d)
              {
                const bool up = (c >> d) & 1;
                cell[d] += up;
                w *= up ? t[d] : 1 - t[d];
              }
            if (w == 0 || !owned(cell))
              continue;
            const auto idx = grid.local_index(cell);
            if (alpha)
              w *= (*alpha)[idx];
            for (std::size_t f = 0; f < nf; ++f)
              acc[f] += w * (*fields[f].values)[idx];
            acc[nf] += w;
          }
      }
    std::vector<double> global(v.size());
    Utilities::MPI::sum(ArrayView<const double>(v),
                        grid.communicator(),
                        ArrayView<double>(global));
    if (prm.probe_linear)
      for (std::size_t i = 0; i < np; ++i)
        {
          const double *const acc = global.data() + np * nf + i * nw;
          if (acc[nf] <= 0)
            continue;
          for (std::size_t f = 0; f < nf; ++f)
            if (fields[f].continuous)
              global[i * nf + f] = acc[f] / acc[nf];
        }
    global.resize(np * nf);
    return global;
  }

  template <int dim>
  void
  Output<dim>::write_probe_lines(const unsigned int        n,
                                 const double              time,
                                 const std::vector<Field> &probe_fields)
  {
    write_probe_lines(Utilities::int_to_string(n, 5), time, probe_fields);
  }

  template <int dim>
  void
  Output<dim>::write_probe_lines(const std::string        &tag,
                                 const double              time,
                                 const std::vector<Field> &probe_fields)
  {
    for (const auto &line : prm.probe_lines)
      {
        std::vector<Point<dim>> pts;
        for (unsigned int i = 0; i < line.n_samples; ++i)
          pts.push_back(line.start + (double(i) / (line.n_samples - 1)) *
                                       (line.end - line.start));
        const auto v = sample(pts, probe_fields);
        if (Utilities::MPI::this_mpi_process(grid.communicator()) != 0)
          continue;
        const std::string file =
          prm.directory + "/probe_line_" + line.name + "_" + tag + ".csv";
        std::ofstream out(file);
        check_stream(out, file);
        out << "# time = " << std::setprecision(8) << time << " s\n";
        out << "s";
        for (int d = 0; d < dim; ++d)
          out << ',' << char('x' + d);
        for (const auto &f : probe_fields)
          out << ',' << f.name;
        out << '\n';
        for (unsigned int i = 0; i < pts.size(); ++i)
          {
            out << pts[i].distance(line.start);
            for (int d = 0; d < dim; ++d)
              out << ',' << pts[i][d];
            for (std::size_t f = 0; f < probe_fields.size(); ++f)
              out << ',' << v[i * probe_fields.size() + f];
            out << '\n';
          }
        out.close();
        check_stream(out, file);
      }
  }

  template std::vector<double>
  Output<2>::sample(const std::vector<Point<2>> &,
                    const std::vector<Field> &) const;
  template std::vector<double>
  Output<3>::sample(const std::vector<Point<3>> &,
                    const std::vector<Field> &) const;
  template void
  Output<2>::write_probe_lines(const unsigned int,
                               const double,
                               const std::vector<Field> &);
  template void
  Output<2>::write_probe_lines(const std::string &,
                               const double,
                               const std::vector<Field> &);
  template void
  Output<3>::write_probe_lines(const std::string &,
                               const double,
                               const std::vector<Field> &);
  template void
  Output<3>::write_probe_lines(const unsigned int,
                               const double,
                               const std::vector<Field> &);
} // namespace femp
