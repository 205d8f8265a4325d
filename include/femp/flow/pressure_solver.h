// femp: the pressure Poisson equation of the melt flow (paper sec. 2.3,
// eq. 4: the projection of the incompressible material point method;
// doc/flow.md).
//
// The unknowns are the pressures at the centres of the fluid cells; the
// operator is the compact 5-point (7-point) Laplacian, -h^2 lap p, with a
// Neumann condition at walls and solid cells and the Dirichlet value p_s at
// the free surface, at theta h from the fluid centre on each face to a gas
// cell (ghost-fluid method: the face adds 1/theta to the diagonal and
// p_s/theta to the right-hand side). The rows are the owned cells of a band
// within one cell of the fluid; rows of band cells that are not fluid are
// identity rows (p = 0), so that the numbering, the matrix graph and the
// Trilinos ML AMG hierarchy survive changes of the fluid set inside the
// band. CG solves the system, preconditioned by point Jacobi while the
// band is small (no setup: the fluid set, and with it an AMG hierarchy,
// changes at nearly every step of a track) and by the AMG hierarchy
// above 'Melt flow/AMG minimum rows'; the same matrix and preconditioner
// serve the volume correction lap(psi) = c e (IncompressibleFlow, Melt
// flow/Volume correction).
#ifndef femp_pressure_solver_h
#define femp_pressure_solver_h

#include <deal.II/base/index_set.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/timer.h>
#include <deal.II/lac/trilinos_precondition.h>
#include <deal.II/lac/trilinos_sparse_matrix.h>
#include <deal.II/lac/trilinos_vector.h>

#include <femp/base/parameter_table.h>
#include <femp/flow/flow_cells.h>
#include <femp/grid/background_grid.h>

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace femp
{
  using namespace dealii;

  template <int dim>
  class PressureSolver
  {
  public:
    struct Parameters
    {
      double       solver_tolerance = 1e-10; ///< relative CG residual
      unsigned int max_iterations   = 1000;
      /// The CG preconditioner; automatic takes Jacobi for bands of fewer
      /// than amg_minimum_rows rows (all ranks) until a Jacobi solve needs
      /// more than jacobi_iteration_limit iterations (then AMG for the rest
      /// of the run), ML AMG otherwise.
      enum class Preconditioner
      {
        automatic,
        amg,
        jacobi
      };
      Preconditioner preconditioner         = Preconditioner::automatic;
      unsigned int   amg_minimum_rows       = 10000;
      unsigned int   jacobi_iteration_limit = 60;

      /// Declare or read the solver entries of the subsection Melt flow
      /// (the caller has entered it), each from its member.
      void
      add_parameters(ParameterTable &table);
      /// The solver entries of the subsection Melt flow (the caller has
      /// entered it): Solver tolerance, Maximum iterations.
      static void
      declare_parameters(ParameterHandler &prm);
      /// Read them (inside Melt flow) and check their ranges.
      void
      parse_parameters(ParameterHandler &prm);
    };

    struct Statistics
    {
      unsigned int  matrix_rebuilds   = 0; ///< band numbering + graph builds
      unsigned int  amg_setups        = 0; ///< AMG hierarchy builds
      unsigned long cg_iterations     = 0; ///< total over all solves
      unsigned int  last_iterations   = 0;
      unsigned int  max_iterations    = 0;
      unsigned long n_fluid_cells     = 0; ///< global, last system
      unsigned long volume_iterations = 0; ///< CG, volume correction, total
      unsigned int  volume_skipped    = 0; ///< volume solves not converged
      /// The fluid cells of the last system on the rank that owns the most
      /// of them (not saved in checkpoints: 0 after a restart).
      unsigned long n_fluid_cells_busiest = 0;
    };

    /// The fluid cells the system is built on (fields over the local box,
    /// ghosts current).
    struct FluidCells
    {
      const std::vector<double>        &type;     ///< flow_cells::Type per cell
      const std::vector<double>        &type_old; ///< the same, previous step
      const std::vector<std::uint32_t> &fluid;    ///< owned fluid cells
      const std::vector<double>        &band;     ///< 1 within a cell of fluid
      /// Interface distance/h per face 2d+side (FreeSurface).
      const std::array<std::vector<double>, 2 * dim> &theta;
    };

    /// @p volume_correction: whether solve_volume() will be called (it
    /// needs a vector of its own).
    PressureSolver(const Parameters          &prm,
                   const BackgroundGrid<dim> &grid,
                   const bool                 volume_correction,
                   TimerOutput               *timer = nullptr);

    /// Bring the system up to date with the fluid cells @p cells: a new
    /// band numbering and graph when a fluid cell left the band, all band
    /// values when the fluid set or its neighbours changed, else only the
    /// free-surface diagonal; a new AMG hierarchy whenever the fluid set
    /// changed (collective).
    void
    update_system(const FluidCells &cells);

    /// Solve for the cell pressure with the right-hand side
    /// -rho h^2/dt div(u*) (@p divergence per owned fluid cell) plus the
    /// free-surface terms p_s/theta (@p p_surface, when @p capillary); the
    /// result goes to @p p_cell (zero outside the fluid, ghosts exchanged;
    /// left as it is when there is no fluid cell at all). Throws when CG
    /// does not converge with a fresh hierarchy.
    void
    solve_pressure(const FluidCells          &cells,
                   const std::vector<double> &divergence,
                   const std::vector<double> &p_surface,
                   const bool                 capillary,
                   const double               rho,
                   const double               dt,
                   std::vector<double>       &p_cell);

    /// Solve A x = -c e with the pressure matrix and hierarchy (@p
    /// source: -c e per owned fluid cell, in the order of cells.fluid);
    /// @p psi gets x at the fluid cells (ghosts exchanged). False (and @p
    /// psi zero) when CG does not converge.
    bool
    solve_volume(const FluidCells          &cells,
                 const std::vector<double> &source,
                 std::vector<double>       &psi);

    const Statistics &
    statistics() const
    {
      return stats;
    }
    /// Forget the numbering, matrix and preconditioner (the next
    /// update_system() builds them afresh, the next solve starts from
    /// zero) and take the counters @p s (checkpoint and resume).
    void
    restart(const Statistics &s)
    {
      have_matrix     = false;
      jacobi_too_slow = false;
      stats           = s;
    }

  private:
    /// Whether the fluid set or the type of a neighbour changed since the
    /// last system on this rank (not collective: update_system() gathers
    /// the ranks' answers together with their fluid cell counts).
    bool
    fluid_set_changed(const FluidCells &cells) const;
    /// New band numbering, matrix graph and vectors.
    void
    number_band(const FluidCells &cells);
    /// All values of the band rows.
    void
    set_band_values(const FluidCells &cells);
    /// Only the diagonals of the fluid rows (free-surface faces).
    void
    set_diagonal(const FluidCells &cells);
    /// A new ML hierarchy on a copy of the current matrix.
    void
    setup_amg();
    /// CG with the hierarchy; a kept hierarchy that needs more than n + 40
    /// iterations is set up again and the solve repeated.
    void
    run_cg(std::optional<flow_cells::Section> &solve_section);

    const Parameters           prm;
    const BackgroundGrid<dim> &grid;
    const bool                 volume_correction;
    TimerOutput               *timer;

    std::vector<double>               gid;  // global row per cell, -1: none
    std::vector<std::uint32_t>        band; // owned band cells in row order
    std::size_t                       n_fluid_rows           = 0;
    unsigned int                      iterations_after_setup = 1;
    bool                              renumbered             = false;
    bool                              new_hierarchy          = false;
    IndexSet                          owned_rows;
    TrilinosWrappers::SparseMatrix    matrix;
    TrilinosWrappers::SparseMatrix    amg_matrix; // ML's copy at its setup
    TrilinosWrappers::PreconditionAMG amg;
    /// Point Jacobi: dst = src / diag, the product with the stored
    /// reciprocals of the owned rows' diagonal, the same arithmetic as
    /// Ifpack's one Jacobi sweep from zero with damping 1 (deal.II's
    /// PreconditionJacobi), without its per-matrix setup (an Ifpack
    /// object, its maps, vectors and condition estimate, several
    /// collectives at each change of the matrix values).
    struct JacobiPreconditioner
    {
      std::vector<double> inverse_diagonal; ///< per owned row, row order
      void
      vmult(TrilinosWrappers::MPI::Vector       &dst,
            const TrilinosWrappers::MPI::Vector &src) const;
    };
    /// The band of the current system is preconditioned by Jacobi (no
    /// setup) instead of the AMG hierarchy (Parameters::preconditioner).
    bool                 use_jacobi = false;
    JacobiPreconditioner jacobi;
    /// The diagonal of each owned band row as last written to the matrix
    /// (row order), for the Jacobi preconditioner.
    std::vector<double> diagonal;
    /// A Jacobi solve needed more than the limit (auto: AMG from then on).
    bool jacobi_too_slow = false;
    /// The AMG hierarchy was set up on the current band and fluid set.
    bool                          amg_current = false;
    TrilinosWrappers::MPI::Vector solution, rhs, psi_solution;
    bool                          have_matrix = false;

    Statistics stats;
  };
} // namespace femp

#endif
