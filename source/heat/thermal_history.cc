// femp: thermal history for microstructure codes (melt events, cooling
// rate, G and R per cell of the grid); see include/femp/heat/thermal_history.h.
#include <deal.II/base/mpi.h>

#include <femp/base/parameter_table.h>
#include <femp/grid/cell_state.h>
#include <femp/heat/thermal_history.h>

#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace femp
{
  template <int dim>
  void
  ThermalHistory<dim>::Parameters::add_parameters(ParameterTable &table)
  {
    table.enter_subsection("Output");
    table.add(
      "Thermal history",
      enabled,
      "Record every melt event of every metal cell (times of the liquidus "
      "rise, liquidus and solidus fall, s; cooling rate K/s, gradient G K/m "
      "and isotherm speed R m/s at the liquidus fall) and write them per "
      "rank to thermal_history_<rank>.csv (ExaCA layout x,y,z,tm,tl,cr) and "
      "thermal_history_full_<rank>.csv in 'Directory' at the end of the "
      "run. false costs nothing.");
    table.leave_subsection();
  }

  template <int dim>
  void
  ThermalHistory<dim>::Parameters::declare_parameters(ParameterHandler &prm)
  {
    Parameters     defaults;
    ParameterTable table(prm, ParameterTable::Mode::declare);
    defaults.add_parameters(table);
  }

  template <int dim>
  void
  ThermalHistory<dim>::Parameters::parse_parameters(ParameterHandler &prm)
  {
    ParameterTable table(prm, ParameterTable::Mode::parse);
    add_parameters(table);
    prm.enter_subsection("Output");
    prm.leave_subsection();
  }

  template <int dim>
  ThermalHistory<dim>::ThermalHistory(const BackgroundGrid<dim> &grid,
                                      const double               solidus,
                                      const double               liquidus,
                                      const std::vector<double> &T,
                                      const std::vector<double> &alpha,
                                      const double               time)
      : grid(grid)
      , T_s(solidus)
      , T_l(liquidus)
      , t_old(time)
      , T_old(T)
  {
    const auto &owned = grid.owned_cells();
    state.assign(owned.size(), 0);
    melt_time.assign(owned.size(), time);
    open_event.assign(owned.size(), -1);
    for (std::size_t k = 0; k < owned.size(); ++k)
      if (alpha[owned[k]] > 0 && T[owned[k]] > T_l)
        state[k] = 1;
  }

  template <int dim>
  double
  ThermalHistory<dim>::gradient(const std::vector<double> &T,
                                const std::vector<double> &alpha,
                                const std::size_t          idx) const
  {
    // Central differences between metal neighbours, one-sided where one
    // neighbour is missing.
    const auto &status = grid.cell_status();
    double      g2     = 0;
    for (int d = 0; d < dim; ++d)
      {
        const std::size_t s = grid.strides()[d];
        const bool        minus =
          status[idx - s] != BackgroundGrid<dim>::outside && alpha[idx - s] > 0;
        const bool plus =
          status[idx + s] != BackgroundGrid<dim>::outside && alpha[idx + s] > 0;
        double dT = 0;
        if (minus && plus)
          dT = 0.5 * (T[idx + s] - T[idx - s]);
        else if (plus)
          dT = T[idx + s] - T[idx];
        else if (minus)
          dT = T[idx] - T[idx - s];
        g2 += dT * dT;
      }
    return std::sqrt(g2) / grid.h();
  }

  template <int dim>
  void
  ThermalHistory<dim>::observe(const std::vector<double> &T,
                               const std::vector<double> &alpha,
                               const double               time)
  {
    const double dt    = time - t_old;
    const auto  &owned = grid.owned_cells();
    // Time at which T passes Tc between the old and the new value.
    auto crossing = [&](const double a, const double b, const double Tc) {
      return t_old + dt * (a - Tc) / (a - b);
    };
    for (std::size_t k = 0; k < owned.size(); ++k)
      {
        const std::size_t idx = owned[k];
        const double      a = T_old[idx], b = T[idx];
        T_old[idx] = b;
        if (!(alpha[idx] > 0) || dt <= 0)
          continue;
        if (state[k] != 1 && b > T_l)
          {
            // Melted (again).
            melt_time[k]  = a > T_l ? t_old : crossing(a, b, T_l);
            state[k]      = 1;
            open_event[k] = -1;
          }
        else if (state[k] == 1 && b <= T_l)
          {
            // Solidification starts: liquidus on the way down.
            const double cr = (a - b) / dt;
            finished.push_back({static_cast<std::uint32_t>(idx),
                                melt_time[k],
                                crossing(a, b, T_l),
                                -1.,
                                cr,
                                gradient(T, alpha, idx)});
            open_event[k] = finished.size() - 1;
            state[k]      = 2;
          }
        if (state[k] == 2 && b <= T_s)
          {
            finished[open_event[k]].ts = a > T_s ? crossing(a, b, T_s) : t_old;
            state[k]                   = 0;
            open_event[k]              = -1;
          }
      }
    t_old = time;
  }

  template <int dim>
  void
  ThermalHistory<dim>::write(const std::string &directory) const
  {
    const unsigned int rank =
      Utilities::MPI::this_mpi_process(grid.communicator());
    const std::string tag = std::to_string(rank) + ".csv";
    std::ofstream     exaca(directory + "/thermal_history_" + tag);
    std::ofstream     full(directory + "/thermal_history_full_" + tag);
    exaca << "x,y,z,tm,tl,cr\n" << std::setprecision(9);
    full << "x,y,z,tm,tl,ts,cr,G,R\n" << std::setprecision(9);
    for (const auto &e : finished)
      {
        const Point<dim>   c = grid.cell_center(e.cell);
        std::ostringstream xyz;
        xyz << std::setprecision(9) << c[0] << ',' << (dim == 3 ? c[1] : 0.)
            << ',' << c[dim - 1];
        exaca << xyz.str() << ',' << e.tm << ',' << e.tl << ','
              << e.cooling_rate << '\n';
        full << xyz.str() << ',' << e.tm << ',' << e.tl << ',' << e.ts << ','
             << e.cooling_rate << ',' << e.gradient << ','
             << (e.gradient > 0 ? e.cooling_rate / e.gradient : 0.) << '\n';
      }
  }

  template <int dim>
  void
  ThermalHistory<dim>::save_state(StateWriter &out) const
  {
    out.put(t_old);
    out.put<std::uint64_t>(finished.size());
    for (const auto &e : finished)
      {
        out.put(global_cell_number(grid, grid.global_index(e.cell)));
        out.put(e.tm);
        out.put(e.tl);
        out.put(e.ts);
        out.put(e.cooling_rate);
        out.put(e.gradient);
      }
    const auto                &owned = grid.owned_cells();
    std::vector<std::uint64_t> keys(owned.size());
    std::vector<double>        T(owned.size());
    for (std::size_t k = 0; k < owned.size(); ++k)
      {
        keys[k] = global_cell_number(grid, grid.global_index(owned[k]));
        T[k]    = T_old[owned[k]];
      }
    out.put_vector(keys);
    out.put_vector(T);
    out.put_vector(state);
    out.put_vector(melt_time);
    out.put_vector(open_event);
  }

  template <int dim>
  void
  ThermalHistory<dim>::load_state(std::vector<StateReader> &parts)
  {
    const auto               &owned = grid.owned_cells();
    std::vector<std::int64_t> k_of(grid.n_local(), -1);
    for (std::size_t k = 0; k < owned.size(); ++k)
      k_of[owned[k]] = k;
    finished.clear();
    for (auto &in : parts)
      {
        t_old = in.get<double>();
        // Events of owned cells, in the saved order.
        std::vector<std::int64_t> new_index(in.get<std::uint64_t>(), -1);
        for (auto &n : new_index)
          {
            const auto idx = owned_local_index(grid, in.get<std::uint64_t>());
            Event      e;
            e.tm           = in.get<double>();
            e.tl           = in.get<double>();
            e.ts           = in.get<double>();
            e.cooling_rate = in.get<double>();
            e.gradient     = in.get<double>();
            if (idx >= 0)
              {
                e.cell = idx;
                n      = finished.size();
                finished.push_back(e);
              }
          }
        const auto keys = in.get_vector<std::uint64_t>();
        const auto T    = in.get_vector<double>();
        const auto s    = in.get_vector<std::uint8_t>();
        const auto tm   = in.get_vector<double>();
        const auto open = in.get_vector<std::int64_t>();
        for (std::size_t i = 0; i < keys.size(); ++i)
          {
            const auto idx = owned_local_index(grid, keys[i]);
            if (idx < 0)
              continue;
            const auto k  = k_of[idx];
            T_old[idx]    = T[i];
            state[k]      = s[i];
            melt_time[k]  = tm[i];
            open_event[k] = open[i] >= 0 ? new_index[open[i]] : -1;
          }
      }
  }

  template class ThermalHistory<2>;
  template class ThermalHistory<3>;
} // namespace femp
