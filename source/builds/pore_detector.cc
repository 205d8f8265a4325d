// femp: pores of a build (see the header and doc/builds.md, "Porosity"): a
// distributed flood fill of the open cells (gas and unfused powder) from
// the top of the domain; the open sets that it does not reach are pores.
#include <deal.II/base/mpi.h>

#include <femp/base/input_checks.h>
#include <femp/base/parameter_table.h>
#include <femp/builds/pore_detector.h>
#include <femp/io/output.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <map>

namespace femp
{
  template <int dim>
  void
  PoreDetector<dim>::Parameters::add_parameters(ParameterTable &table)
  {
    ParameterHandler &prm = table.handler();
    table.enter_subsection("Porosity");
    table.add(
      "Detect pores",
      detect,
      {{AutoSwitch::automatic, "auto"},
       {AutoSwitch::on, "true"},
       {AutoSwitch::off, "false"}},
      "Find the pores (gas enclosed in the fused metal, doc/builds.md) at "
      "every field output: porosity.csv (count, gas volume, relative "
      "density of the built region), pores.csv (each pore's volume, "
      "equivalent diameter and centroid) and the cell fields pore, "
      "unfused_powder and partially_molten (scenes that carry material "
      "points only). auto: with a layer schedule (Build/Layer schedule).");
    table.add(
      "Fused fraction threshold",
      threshold,
      Patterns::Double(0., 1.),
      "A cell is open (gas or unfused powder, through which the free gas "
      "reaches) when its fused metal fraction alpha (1 - s_p), s_p the "
      "share of its points' volume that is powder that never melted, is "
      "below this value; -. Range (0, 1).");
    table.add("Minimum pore volume",
              min_volume,
              Patterns::Double(0.),
              "Pores whose gas volume is smaller are not listed, "
              "m^3 (2D: m^2); range [0, inf).");
    if (table.declaring())
      prm.declare_entry(
        "Built region bottom",
        "",
        Patterns::Anything(),
        "The relative density is that of the cells whose centre lies at or "
        "above this vertical coordinate (z in 3D, y in 2D), m; empty: the "
        "substrate top (Material points/Substrate top). Range: inside the "
        "domain.");
    table.leave_subsection();
  }

  template <int dim>
  void
  PoreDetector<dim>::Parameters::declare_parameters(ParameterHandler &prm)
  {
    Parameters     defaults;
    ParameterTable table(prm, ParameterTable::Mode::declare);
    defaults.add_parameters(table);
  }

  template <int dim>
  void
  PoreDetector<dim>::Parameters::parse_parameters(ParameterHandler &prm)
  {
    ParameterTable table(prm, ParameterTable::Mode::parse);
    add_parameters(table);
    prm.enter_subsection("Porosity");
    const std::string b = prm.get("Built region bottom");
    prm.leave_subsection();
    require(threshold > 0 && threshold < 1,
            "Porosity/Fused fraction threshold",
            threshold,
            "it must lie in (0, 1)");
    bottom_given = !b.empty();
    if (bottom_given)
      {
        char *end = nullptr;
        bottom    = std::strtod(b.c_str(), &end);
        require(end != b.c_str() && *end == '\0',
                "Porosity/Built region bottom",
                b,
                "it must be empty or a number (m)");
      }
  }

  template <int dim>
  PoreDetector<dim>::PoreDetector(const Parameters          &prm,
                                  const BackgroundGrid<dim> &grid,
                                  const double               default_bottom)
      : prm(prm)
      , grid(grid)
      , bottom(prm.bottom_given ? prm.bottom : default_bottom)
  {
  }

  template <int dim>
  std::pair<std::vector<double>, std::vector<double>>
  PoreDetector<dim>::powder_shares(const BackgroundGrid<dim> &grid,
                                   const MaterialPoints<dim> &points,
                                   const double               T_solidus,
                                   const double               T_liquidus)
  {
    using P = typename MaterialPoints<dim>::PropertyIndex;
    std::vector<double> powder(grid.n_local(), 0.), partial(grid.n_local(), 0.);
    const auto         &cells = points.occupied_cells();
    for (std::size_t c = 0; c < cells.size(); ++c)
      {
        double all = 0, p = 0, m = 0;
        for (const double *v : points.cell_point_properties(c))
          {
            all += v[P::volume];
            if (v[P::state] == MaterialPoints<dim>::powder)
              p += v[P::volume];
            else if (v[P::peak_temperature] >= T_solidus &&
                     v[P::peak_temperature] < T_liquidus)
              m += v[P::volume];
          }
        if (all > 0)
          {
            powder[cells[c].first]  = p / all;
            partial[cells[c].first] = m / all;
          }
      }
    return {powder, partial};
  }

  template <int dim>
  typename PoreDetector<dim>::Result
  PoreDetector<dim>::find(const std::vector<double> &alpha,
                          const std::vector<double> *powder) const
  {
    using Grid          = BackgroundGrid<dim>;
    const auto &st      = grid.strides();
    const auto &status  = grid.cell_status();
    const auto &n       = grid.n_cells();
    const auto  n_local = grid.n_local();
    const auto  share   = [&](const std::size_t i) {
      return powder ? (*powder)[i] : 0.;
    };
    constexpr double closed = -2, free_gas = -1;

    // Labels: closed cells -2, open cells of the top row -1 (the free
    // gas), other open cells their global cell number; a double field for
    // the ghost exchange (exact up to 2^53 cells).
    std::vector<double> label(n_local, closed);
    grid.for_each_owned_cell([&](const std::size_t i, const auto &ijk) {
      if (alpha[i] * (1 - share(i)) >= prm.threshold)
        return;
      if (ijk[dim - 1] == int(n[dim - 1]) - 1)
        label[i] = free_gas;
      else
        {
          double g = 0;
          for (int d = dim - 1; d >= 0; --d)
            g = g * n[d] + ijk[d];
          label[i] = g;
        }
    });

    // Components of the owned open cells (face neighbours), each with the
    // smallest label of its cells, and its contacts with ghost cells.
    std::vector<std::int32_t>                          comp(n_local, -1);
    std::vector<double>                                comp_label;
    std::vector<std::vector<std::uint32_t>>            comp_cells;
    std::vector<std::pair<std::uint32_t, std::size_t>> contacts;
    std::vector<std::uint32_t>                         stack;
    for (const auto start : grid.owned_cells())
      {
        if (label[start] == closed || comp[start] >= 0)
          continue;
        const std::int32_t c = comp_cells.size();
        comp_cells.emplace_back();
        comp_label.push_back(label[start]);
        comp[start] = c;
        stack.push_back(start);
        while (!stack.empty())
          {
            const std::size_t i = stack.back();
            stack.pop_back();
            comp_cells[c].push_back(i);
            comp_label[c] = std::min(comp_label[c], label[i]);
            // Owned cells always have a neighbour entry in the box.
            for (int d = 0; d < dim; ++d)
              for (const std::ptrdiff_t j :
                   {std::ptrdiff_t(i) + st[d], std::ptrdiff_t(i) - st[d]})
                {
                  if (status[j] == Grid::ghost)
                    contacts.emplace_back(c, j);
                  else if (status[j] == Grid::owned && label[j] != closed &&
                           comp[j] < 0)
                    {
                      comp[j] = c;
                      stack.push_back(j);
                    }
                }
          }
      }
    // Pass the smallest labels through the ghost layer until no rank
    // changes one (ghost labels are -2 for closed ghost cells).
    for (;;)
      {
        for (std::size_t c = 0; c < comp_cells.size(); ++c)
          for (const auto i : comp_cells[c])
            label[i] = comp_label[c];
        grid.update_ghosts(label);
        unsigned int changed = 0;
        for (const auto &[c, j] : contacts)
          if (label[j] != closed && label[j] < comp_label[c])
            {
              comp_label[c] = label[j];
              changed       = 1;
            }
        if (Utilities::MPI::max(changed, grid.communicator()) == 0)
          break;
      }

    // Per cell: the label it is counted for (open cells: their own;
    // closed cells: the smallest open label among the 3^dim neighbours),
    // its gas and unfused powder; sums per pore label and over the built
    // region.
    const double V = std::pow(grid.h(), dim);
    // Per label: n_cells, gas, powder, gas * x_d.
    std::map<double, std::array<double, 3 + dim>> sums;
    double built[3] = {0, 0, 0}; // metal, powder in pores, gas in pores
    grid.for_each_owned_cell([&](const std::size_t i, const auto &ijk) {
      double l = label[i];
      if (l == closed && (alpha[i] < 1 || share(i) > 0))
        {
          std::array<int, dim> lo, hi, nb;
          for (int d = 0; d < dim; ++d)
            {
              lo[d] = ijk[d] - 1;
              hi[d] = ijk[d] + 1;
            }
          nb = lo;
          for (bool more = true; more;)
            {
              if (grid.in_box(nb))
                {
                  const double m = label[grid.local_index(nb)];
                  if (m != closed && (l == closed || m < l))
                    l = m;
                }
              int d = 0;
              for (; d < dim; ++d)
                {
                  if (++nb[d] <= hi[d])
                    break;
                  nb[d] = lo[d];
                }
              more = d < dim;
            }
        }
      const double     gas      = (1 - alpha[i]) * V;
      const double     pow      = alpha[i] * share(i) * V;
      const Point<dim> x        = grid.cell_center(i);
      const bool       in_built = x[dim - 1] >= bottom;
      if (in_built)
        built[0] += alpha[i] * (1 - share(i)) * V;
      if (l < 0 || (label[i] == closed && gas <= 0 && pow <= 0))
        return;
      auto &s = sums.try_emplace(l).first->second;
      s[0] += label[i] == closed ? 0 : 1;
      s[1] += gas;
      s[2] += pow;
      for (int d = 0; d < dim; ++d)
        s[3 + d] += gas * x[d];
      if (in_built)
        {
          built[1] += pow;
          built[2] += gas;
        }
    });

    // Gather the sums of every rank, merge by label (the same order on
    // every rank and for every partition).
    std::vector<double> flat;
    for (const auto &[l, s] : sums)
      {
        flat.push_back(l);
        flat.insert(flat.end(), s.begin(), s.end());
      }
    const auto all = Utilities::MPI::all_gather(grid.communicator(), flat);
    std::map<double, std::array<double, 3 + dim>> merged;
    for (const auto &part : all)
      for (std::size_t k = 0; k + 4 + dim <= part.size(); k += 4 + dim)
        {
          auto &s = merged.try_emplace(part[k]).first->second;
          for (int q = 0; q < 3 + dim; ++q)
            s[q] += part[k + 1 + q];
        }

    Result                         r;
    std::map<double, unsigned int> number;
    for (const auto &[l, s] : merged)
      {
        if (s[0] == 0 || s[1] < prm.min_volume)
          continue;
        Pore p;
        p.n_cells = static_cast<unsigned int>(s[0]);
        p.volume  = s[1];
        p.powder  = s[2];
        for (int d = 0; d < dim; ++d)
          p.centroid[d] = s[1] > 0 ? s[3 + d] / s[1] : 0.;
        const double envelope = s[1] + s[2];
        p.diameter            = dim == 3 ? std::cbrt(6 * envelope / M_PI) :
                                           std::sqrt(4 * envelope / M_PI);
        r.pores.push_back(p);
        r.pore_volume += p.volume;
        number[l] = r.pores.size();
      }
    double built_sum[3];
    Utilities::MPI::sum(ArrayView<const double>(built, 3),
                        grid.communicator(),
                        ArrayView<double>(built_sum, 3));
    r.built_metal         = built_sum[0];
    r.built_powder        = built_sum[1];
    r.built_pores         = built_sum[2];
    const double envelope = built_sum[0] + built_sum[1] + built_sum[2];
    r.relative_density =
      envelope > 0 ? (built_sum[0] + built_sum[1]) / envelope : 1.;
    r.pore_number.assign(n_local, 0.);
    for (const auto i : grid.owned_cells())
      if (label[i] >= 0)
        {
          const auto it = number.find(label[i]);
          if (it != number.end())
            r.pore_number[i] = it->second;
        }
    return r;
  }

  template <int dim>
  void
  PoreDetector<dim>::write(const std::string &directory,
                           const unsigned int n,
                           const double       time,
                           const Result      &r)
  {
    if (Utilities::MPI::this_mpi_process(grid.communicator()) != 0)
      return;
    if (!summary_csv.is_open())
      {
        summary_csv.open(directory + "/porosity.csv");
        summary_csv << "time,output,n_pores,pore_volume,pore_powder,"
                       "built_metal,built_pore_volume,relative_density\n";
        pores_csv.open(directory + "/pores.csv");
        pores_csv << "time,output,pore,n_cells,volume,powder,"
                     "equivalent_diameter,x,y"
                  << (dim == 3 ? ",z" : "") << '\n';
      }
    double powder = 0;
    for (const auto &p : r.pores)
      powder += p.powder;
    summary_csv << std::setprecision(8) << time << ',' << n << ','
                << r.pores.size() << ',' << r.pore_volume << ',' << powder
                << ',' << r.built_metal << ',' << r.built_pores << ','
                << r.relative_density << '\n';
    for (std::size_t k = 0; k < r.pores.size(); ++k)
      {
        const auto &p = r.pores[k];
        pores_csv << std::setprecision(8) << time << ',' << n << ',' << k + 1
                  << ',' << p.n_cells << ',' << p.volume << ',' << p.powder
                  << ',' << p.diameter;
        for (int d = 0; d < dim; ++d)
          pores_csv << ',' << p.centroid[d];
        pores_csv << '\n';
      }
    summary_csv.flush();
    pores_csv.flush();
    require(bool(summary_csv) && bool(pores_csv),
            "Output/Directory",
            directory,
            "porosity.csv or pores.csv cannot be written there");
  }

  template <int dim>
  void
  PoreDetector<dim>::resume(const std::string &directory, const double time)
  {
    if (Utilities::MPI::this_mpi_process(grid.communicator()) != 0)
      return;
    reopen_series_at(summary_csv, directory + "/porosity.csv", time);
    reopen_series_at(pores_csv, directory + "/pores.csv", time);
    if (summary_csv.is_open() != pores_csv.is_open())
      {
        summary_csv.close();
        pores_csv.close();
      }
  }

  template class PoreDetector<2>;
  template class PoreDetector<3>;
} // namespace femp
