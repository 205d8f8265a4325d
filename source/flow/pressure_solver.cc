// femp: the pressure Poisson equation of the melt flow on a band of cells
// round the fluid, CG with point Jacobi (small bands) or Trilinos ML AMG,
// and the volume-correction solve
// with the same operator (paper sec. 2.3, eq. 4; doc/flow.md). See
// include/femp/flow/pressure_solver.h.
#include <deal.II/base/mpi.h>
#include <deal.II/lac/exceptions.h>
#include <deal.II/lac/solver_cg.h>
#include <deal.II/lac/solver_control.h>
#include <deal.II/lac/trilinos_sparsity_pattern.h>

#include <femp/base/input_checks.h>
#include <femp/base/parameter_table.h>
#include <femp/flow/pressure_solver.h>

#include <Epetra_CrsMatrix.h>
#include <algorithm>
#include <optional>
#include <sstream>

namespace femp
{
  namespace
  {
    constexpr int gas   = flow_cells::gas;
    constexpr int fluid = flow_cells::fluid;
    using flow_cells::Section;
  } // namespace

  template <int dim>
  void
  PressureSolver<dim>::Parameters::add_parameters(ParameterTable &table)
  {
    table.add("Solver tolerance",
              solver_tolerance,
              Patterns::Double(0.),
              "Relative residual of the pressure CG solve; range (0, 1e-2].");
    table.add("Maximum iterations",
              max_iterations,
              Patterns::Integer(1),
              "Most CG iterations per pressure solve; range [1, inf).");
    table.add("Pressure preconditioner",
              preconditioner,
              {{Preconditioner::automatic, "auto"},
               {Preconditioner::amg, "amg"},
               {Preconditioner::jacobi, "jacobi"}},
              "Preconditioner of the pressure CG solve: 'amg' "
              "(Trilinos ML, a hierarchy set up at each change of "
              "the fluid set), 'jacobi' (the matrix diagonal, no "
              "setup), or 'auto': Jacobi while the band round the "
              "fluid has fewer than 'AMG minimum rows' rows over all "
              "ranks and its solves need at most 'Jacobi iteration "
              "limit' iterations, AMG otherwise (doc/flow.md, \"One "
              "fluid step\", step 4).");
    table.add("AMG minimum rows",
              amg_minimum_rows,
              Patterns::Integer(0),
              "With 'Pressure preconditioner = auto': the smallest "
              "band, in rows (cells) over all ranks, that the AMG "
              "preconditions; range [0, inf), 0: always AMG. Smaller "
              "bands take Jacobi, whose solves need no setup "
              "(doc/flow.md).");
    table.add("Jacobi iteration limit",
              jacobi_iteration_limit,
              Patterns::Integer(1),
              "With 'Pressure preconditioner = auto': a Jacobi solve "
              "that needs more CG iterations than this hands the "
              "pressure to the AMG for the rest of the run (or until "
              "a resume); range [1, inf).");
  }

  template <int dim>
  void
  PressureSolver<dim>::Parameters::declare_parameters(ParameterHandler &prm)
  {
    Parameters     defaults;
    ParameterTable table(prm, ParameterTable::Mode::declare);
    defaults.add_parameters(table);
  }

  template <int dim>
  void
  PressureSolver<dim>::Parameters::parse_parameters(ParameterHandler &prm)
  {
    ParameterTable table(prm, ParameterTable::Mode::parse);
    add_parameters(table);
    require(solver_tolerance > 0 && solver_tolerance <= 1e-2,
            "Melt flow/Solver tolerance",
            solver_tolerance,
            "it must lie in (0, 1e-2]");
  }

  template <int dim>
  PressureSolver<dim>::PressureSolver(const Parameters          &prm,
                                      const BackgroundGrid<dim> &grid,
                                      const bool   volume_correction,
                                      TimerOutput *timer)
      : prm(prm)
      , grid(grid)
      , volume_correction(volume_correction)
      , timer(timer)
  {
    gid = grid.make_field(-1.);
  }

  // The matrix rows are the owned cells of a band: the cells within one
  // of a fluid cell (near1 of FreeSurface; a band of two cells cost more in
  // solves than it saved in setups in the 3D track). Rows of band cells that
  // are not fluid are identity rows (decoupled, p = 0), so the numbering,
  // the graph and the AMG hierarchy survive changes of the fluid set that
  // stay inside the band:
  //  - fluid set and neighbour types unchanged: only the diagonal (theta);
  //  - changed inside the band: all values of the band rows are reset, the
  //    old hierarchy keeps preconditioning the new matrix while CG
  //    converges in at most n + 40 iterations, n those of the first
  //    solve after its setup; else ML is set up again and the solve
  //    repeated;
  //  - a fluid cell outside the band: new band, graph and hierarchy.
  template <int dim>
  void
  PressureSolver<dim>::update_system(const FluidCells &cells)
  {
    const MPI_Comm comm = grid.communicator();
    // What the ranks must agree on, in one collective (a sub-step's system
    // costs little besides its collectives on a small fluid set): per rank
    // its fluid cells, whether its fluid set changed and whether one of
    // its fluid cells has no row (outside the band of the numbering). The
    // counts give the sum and the busiest rank's share (layer_cost.csv
    // weighs the balance of the flow).
    const bool changed_here = fluid_set_changed(cells);
    bool       outside_band = false;
    if (have_matrix)
      for (const auto c : cells.fluid)
        if (gid[c] < 0)
          {
            outside_band = true;
            break;
          }
    const unsigned long        own[3] = {cells.fluid.size(),
                                  changed_here ? 1ul : 0ul,
                                  outside_band ? 1ul : 0ul};
    std::vector<unsigned long> all(3 * Utilities::MPI::n_mpi_processes(comm));
    const int                  ierr = MPI_Allgather(
      own, 3, MPI_UNSIGNED_LONG, all.data(), 3, MPI_UNSIGNED_LONG, comm);
    AssertThrowMPI(ierr);
    bool set_changed = !have_matrix, any_outside = false;
    stats.n_fluid_cells         = 0;
    stats.n_fluid_cells_busiest = 0;
    for (std::size_t r = 0; r < all.size(); r += 3)
      {
        stats.n_fluid_cells += all[r];
        stats.n_fluid_cells_busiest =
          std::max(stats.n_fluid_cells_busiest, all[r]);
        set_changed = set_changed || all[r + 1] != 0;
        any_outside = any_outside || all[r + 2] != 0;
      }
    n_fluid_rows = cells.fluid.size();
    renumbered   = !have_matrix || (set_changed && any_outside);
    if (renumbered)
      number_band(cells);
    if (set_changed)
      set_band_values(cells);
    else
      set_diagonal(cells);
    // A new hierarchy whenever the set of fluid cells changed. Keeping one
    // across set changes inside the band costs more than it saves: in the
    // 0.2 ms 3D track the stale hierarchy needs 50 CG iterations per solve
    // on average and fails its limit in 1509 of 1917 steps (then set up
    // anyway), against 7 with a fresh one (doc/studies/flow.md). With the same
    // set only the free-surface diagonal 1/theta changed, and the kept
    // hierarchy is tried first (run_cg()).
    //
    // Jacobi (auto) on small bands until one of its solves needs more
    // than 'Jacobi iteration limit' iterations, then AMG for the rest of
    // the run: a flow whose fluid set changes seldom, such as a resting
    // drop or a closed cavity, is better served by kept hierarchies.
    use_jacobi = prm.preconditioner == Parameters::Preconditioner::jacobi ||
                 (prm.preconditioner == Parameters::Preconditioner::automatic &&
                  matrix.m() < prm.amg_minimum_rows && !jacobi_too_slow);
    new_hierarchy = !use_jacobi && (renumbered || set_changed || !amg_current);
    if (use_jacobi)
      {
        // No hierarchy: the reciprocals of the current diagonal, at every
        // change of the matrix (a pass over the owned rows). A zero
        // diagonal (a fluid cell closed in by solid: an empty row) gets 0,
        // as in Ifpack's point relaxation: the row is left out of the
        // preconditioner instead of making it infinite.
        jacobi.inverse_diagonal.resize(diagonal.size());
        for (std::size_t i = 0; i < diagonal.size(); ++i)
          jacobi.inverse_diagonal[i] =
            diagonal[i] != 0. ? 1. / diagonal[i] : 0.;
        have_matrix = true;
        amg_current = false;
      }
    else if (new_hierarchy)
      setup_amg();
  }

  template <int dim>
  bool
  PressureSolver<dim>::fluid_set_changed(const FluidCells &cells) const
  {
    const auto &cs          = grid.strides();
    const auto &type        = cells.type;
    const auto &type_old    = cells.type_old;
    bool        set_changed = !have_matrix;
    if (!set_changed)
      for (const auto c : cells.fluid)
        {
          if (type_old[c] != fluid)
            {
              set_changed = true;
              break;
            }
          for (int d = 0; d < dim && !set_changed; ++d)
            set_changed = type_old[c + cs[d]] != type[c + cs[d]] ||
                          type_old[c - cs[d]] != type[c - cs[d]];
          if (set_changed)
            break;
        }
    // Cells that stopped being fluid also change the system.
    if (!set_changed)
      set_changed = cells.fluid.size() != n_fluid_rows;
    return set_changed;
  }

  // The rows of the band are owned: their values are written into the
  // filled Epetra matrix in place and need no compress() (deal.II's
  // compress() would gather off-rank entries, of which there are none,
  // through new Epetra maps and an exporter: a handful of collectives at
  // each change of the values).
  namespace
  {
    // deal.II 9.4 hands out the Epetra matrix as const only; the values
    // of its filled rows may still be replaced.
    Epetra_CrsMatrix &
    owned_rows_of(TrilinosWrappers::SparseMatrix &matrix)
    {
      return const_cast<Epetra_CrsMatrix &>(matrix.trilinos_matrix());
    }

    // The first global row this rank owns (0 where it owns none): the
    // offset of the band's local row order.
    IndexSet::size_type
    first_row(const IndexSet &owned_rows)
    {
      return owned_rows.n_elements() > 0 ? *owned_rows.begin() : 0;
    }

    void
    replace_in_row(Epetra_CrsMatrix                        &A,
                   const TrilinosWrappers::types::int_type  row,
                   const int                                n,
                   const double                            *values,
                   const TrilinosWrappers::types::int_type *columns)
    {
      const int ierr =
        A.Epetra_CrsMatrix::ReplaceGlobalValues(row, n, values, columns);
      AssertThrow(ierr == 0, LACExceptions::ExcTrilinosError(ierr));
    }
  } // namespace

  template <int dim>
  void
  PressureSolver<dim>::JacobiPreconditioner::vmult(
    TrilinosWrappers::MPI::Vector       &dst,
    const TrilinosWrappers::MPI::Vector &src) const
  {
    AssertDimension(std::size_t(dst.end() - dst.begin()),
                    inverse_diagonal.size());
    auto       *d = dst.begin();
    const auto *s = src.begin();
    for (std::size_t i = 0; i < inverse_diagonal.size(); ++i)
      d[i] = inverse_diagonal[i] * s[i];
  }

  template <int dim>
  void
  PressureSolver<dim>::number_band(const FluidCells &cells)
  {
    Section        s(timer, "flow: pressure matrix setup");
    const MPI_Comm comm   = grid.communicator();
    const auto    &cs     = grid.strides();
    const auto    &status = grid.cell_status();
    band.clear();
    for (const auto c : grid.owned_cells())
      if (cells.band[c] != 0 && status[c] != BackgroundGrid<dim>::outside)
        band.push_back(c);
    const types::global_dof_index n_local = band.size();
    // (types::global_dof_index is 32 bits in this deal.II build: the
    // exscan goes through a 64-bit integer.)
    std::uint64_t n_local64 = n_local, offset64 = 0;
    MPI_Exscan(&n_local64, &offset64, 1, MPI_UINT64_T, MPI_SUM, comm);
    if (Utilities::MPI::this_mpi_process(comm) == 0)
      offset64 = 0;
    const types::global_dof_index offset  = offset64;
    const types::global_dof_index n_total = Utilities::MPI::sum(n_local, comm);
    std::fill(gid.begin(), gid.end(), -1.);
    for (std::size_t i = 0; i < band.size(); ++i)
      gid[band[i]] = offset + i;
    grid.update_ghosts(gid);
    owned_rows = IndexSet(n_total);
    owned_rows.add_range(offset, offset + n_local);
    owned_rows.compress();

    // (An empty row range must ask for 0 entries per row: Epetra's
    // size check uses the min/max row of the range.)
    TrilinosWrappers::SparsityPattern sp(owned_rows,
                                         comm,
                                         n_local > 0 ? 2 * dim + 1 : 0);
    for (std::size_t i = 0; i < band.size(); ++i)
      {
        const std::size_t c   = band[i];
        const auto        row = offset + i;
        sp.add(row, row);
        for (int d = 0; d < dim; ++d)
          for (const std::ptrdiff_t o : {-cs[d], cs[d]})
            if (gid[c + o] >= 0)
              sp.add(row, types::global_dof_index(gid[c + o]));
      }
    sp.compress();
    matrix.reinit(sp);
    rhs.reinit(owned_rows, comm);
    solution.reinit(owned_rows, comm);
    if (volume_correction)
      psi_solution.reinit(owned_rows, comm);
    ++stats.matrix_rebuilds;
  }

  template <int dim>
  void
  PressureSolver<dim>::set_band_values(const FluidCells &cells)
  {
    // All values of the band rows: -1 between fluid cells, 0 for the
    // other stored neighbours, identity rows outside the fluid.
    Section     s(timer, "flow: pressure matrix values");
    const auto &cs         = grid.strides();
    const auto &type       = cells.type;
    const auto &theta      = cells.theta;
    const auto  row_offset = first_row(owned_rows);
    auto       &A          = owned_rows_of(matrix);
    diagonal.resize(band.size());
    for (std::size_t i = 0; i < band.size(); ++i)
      {
        const std::size_t                       c   = band[i];
        const TrilinosWrappers::types::int_type row = row_offset + i;
        const bool                              f   = type[c] == fluid;
        TrilinosWrappers::types::int_type       cols[2 * dim + 1];
        double                                  vals[2 * dim + 1];
        unsigned int                            n    = 0;
        double                                  diag = f ? 0. : 1.;
        for (int d = 0; d < dim; ++d)
          for (const int side : {0, 1})
            {
              const std::size_t e  = side ? c + cs[d] : c - cs[d];
              const bool        ef = type[e] == fluid;
              if (f && ef)
                diag += 1;
              else if (f && type[e] == gas)
                diag += 1. / theta[2 * d + side][c];
              if (gid[e] >= 0)
                {
                  cols[n] = TrilinosWrappers::types::int_type(gid[e]);
                  vals[n] = (f && ef) ? -1. : 0.;
                  ++n;
                }
            }
        cols[n] = row;
        vals[n] = diag;
        ++n;
        replace_in_row(A, row, n, vals, cols);
        diagonal[i] = diag;
      }
  }

  template <int dim>
  void
  PressureSolver<dim>::set_diagonal(const FluidCells &cells)
  {
    // Diagonal only: the free-surface faces contribute 1/theta
    // (Dirichlet value at the interface, ghost-fluid method).
    const auto &cs         = grid.strides();
    const auto &type       = cells.type;
    const auto &theta      = cells.theta;
    const auto  row_offset = first_row(owned_rows);
    auto       &A          = owned_rows_of(matrix);
    for (const auto c : cells.fluid)
      {
        double diag = 0;
        for (int d = 0; d < dim; ++d)
          for (const int side : {0, 1})
            {
              const auto t = type[side ? c + cs[d] : c - cs[d]];
              if (t == fluid)
                diag += 1;
              else if (t == gas)
                diag += 1. / theta[2 * d + side][c];
            }
        const auto row = TrilinosWrappers::types::int_type(gid[c]);
        replace_in_row(A, row, 1, &diag, &row);
        diagonal[row - row_offset] = diag;
      }
  }

  // ML keeps a reference to the matrix it was set up with: it gets its
  // own copy, so that a kept hierarchy stays one fixed SPD operator while
  // the values of the system matrix change (with the system matrix
  // itself, the fine-level Chebyshev smoother would run with stale
  // eigenvalue bounds and could stop being a preconditioner).
  template <int dim>
  void
  PressureSolver<dim>::setup_amg()
  {
    Section s(timer, "flow: AMG setup");
    if (owned_rows.size() > 0)
      {
        TrilinosWrappers::PreconditionAMG::AdditionalData data;
        data.elliptic              = true;
        data.higher_order_elements = false;
        data.smoother_sweeps       = 2;
        data.aggregation_threshold = 0.02;
        amg_matrix.copy_from(matrix);
        amg.initialize(amg_matrix, data);
      }
    have_matrix = true;
    amg_current = true;
    ++stats.amg_setups;
  }

  template <int dim>
  void
  PressureSolver<dim>::solve_pressure(const FluidCells          &cells,
                                      const std::vector<double> &divergence,
                                      const std::vector<double> &p_surface,
                                      const bool                 capillary,
                                      const double               rho,
                                      const double               dt,
                                      std::vector<double>       &p_cell)
  {
    if (stats.n_fluid_cells == 0)
      return;
    std::optional<Section> solve_section;
    solve_section.emplace(timer, "flow: pressure solve");
    const double h           = grid.h();
    const auto  &cs          = grid.strides();
    const auto  &type        = cells.type;
    const auto  &theta       = cells.theta;
    const auto  &fluid_cells = cells.fluid;
    const double f           = -rho * h * h / dt;
    rhs                      = 0; // identity rows of the band: p = 0
    // Written in place: the rows are owned (no compress(), see
    // owned_rows_of()).
    const auto row_offset = first_row(owned_rows);
    auto      *b_own      = rhs.begin();
    for (std::size_t i = 0; i < fluid_cells.size(); ++i)
      {
        double b = f * divergence[i];
        if (capillary)
          {
            const std::size_t c = fluid_cells[i];
            for (int d = 0; d < dim; ++d)
              for (const int side : {0, 1})
                if (type[side ? c + cs[d] : c - cs[d]] == gas)
                  b += p_surface[c] / theta[2 * d + side][c];
          }
        b_own[types::global_dof_index(gid[fluid_cells[i]]) - row_offset] = b;
      }
    // Warm start from the previous pressure (same numbering).
    if (renumbered)
      solution = 0;
    run_cg(solve_section);
    std::fill(p_cell.begin(), p_cell.end(), 0.);
    for (std::size_t i = 0; i < fluid_cells.size(); ++i)
      p_cell[fluid_cells[i]] =
        solution(types::global_dof_index(gid[fluid_cells[i]]));
    grid.update_ghosts(p_cell);
  }

  template <int dim>
  void
  PressureSolver<dim>::run_cg(std::optional<Section> &solve_section)
  {
    const double norm = rhs.l2_norm();
    if (norm == 0)
      {
        solution = 0;
        return;
      }
    // With a hierarchy built for other matrix values CG may use at
    // most n + 40 iterations (n: those of the first solve after the
    // setup; 40 iterations cost about one ML setup in the 3D track,
    // fewer than one in 2D); beyond, ML is set up again on the current
    // matrix and the solve restarts from the same initial guess.
    bool                          fresh = new_hierarchy || use_jacobi;
    unsigned int                  total = 0;
    TrilinosWrappers::MPI::Vector guess;
    if (!fresh)
      guess = solution;
    for (;;)
      {
        const unsigned int limit =
          fresh ? prm.max_iterations :
                  std::min(prm.max_iterations, iterations_after_setup + 40);
        SolverControl control(limit, prm.solver_tolerance * norm);
        SolverCG<TrilinosWrappers::MPI::Vector> cg(control);
        try
          {
            if (use_jacobi)
              cg.solve(matrix, solution, rhs, jacobi);
            else
              cg.solve(matrix, solution, rhs, amg);
            total += control.last_step();
            if (use_jacobi &&
                prm.preconditioner == Parameters::Preconditioner::automatic &&
                control.last_step() > prm.jacobi_iteration_limit)
              jacobi_too_slow = true;
            else if (fresh && !use_jacobi)
              iterations_after_setup = std::max(1u, control.last_step());
            break;
          }
        catch (const SolverControl::NoConvergence &e)
          {
            total += e.last_step;
            if (fresh)
              {
                std::ostringstream msg;
                msg << "Melt flow: the pressure CG solve did not converge in "
                    << e.last_step << " iterations (residual "
                    << e.last_residual << ", target " << control.tolerance()
                    << ", " << stats.n_fluid_cells << " fluid cells).";
                throw std::runtime_error(msg.str());
              }
            solve_section.reset();
            setup_amg();
            solve_section.emplace(timer, "flow: pressure solve");
            solution = guess;
            fresh    = true;
          }
      }
    stats.last_iterations = total;
    stats.cg_iterations += total;
    stats.max_iterations = std::max(stats.max_iterations, total);
  }

  template <int dim>
  bool
  PressureSolver<dim>::solve_volume(const FluidCells          &cells,
                                    const std::vector<double> &source,
                                    std::vector<double>       &psi)
  {
    std::fill(psi.begin(), psi.end(), 0.);
    if (stats.n_fluid_cells == 0)
      return true;
    rhs = 0;
    // Written in place, as in solve_pressure().
    const auto row_offset = first_row(owned_rows);
    auto      *b_own      = rhs.begin();
    for (std::size_t i = 0; i < cells.fluid.size(); ++i)
      b_own[types::global_dof_index(gid[cells.fluid[i]]) - row_offset] =
        source[i];
    const double norm = rhs.l2_norm();
    if (norm > 0)
      {
        SolverControl control(prm.max_iterations, prm.solver_tolerance * norm);
        SolverCG<TrilinosWrappers::MPI::Vector> cg(control);
        psi_solution = 0;
        try
          {
            if (use_jacobi)
              cg.solve(matrix, psi_solution, rhs, jacobi);
            else
              cg.solve(matrix, psi_solution, rhs, amg);
            stats.volume_iterations += control.last_step();
          }
        catch (const SolverControl::NoConvergence &e)
          {
            stats.volume_iterations += e.last_step;
            ++stats.volume_skipped;
            return false; // psi = 0: no correction in this step
          }
        for (const auto c : cells.fluid)
          psi[c] = psi_solution(types::global_dof_index(gid[c]));
      }
    grid.update_ghosts(psi);
    return true;
  }

  template class PressureSolver<2>;
  template class PressureSolver<3>;
} // namespace femp
