// femp: the shape of a laser track for the user: the height of the metal's
// top surface along the track's centre line and across the track at chosen
// positions x, and the width and height of the re-solidified bead above the
// original substrate top (doc/cases.md, "Bead shape").
//
// Surface height of a grid column (cells with the same horizontal index):
// the highest crossing of alpha = 1/2 along the vertical, by linear
// interpolation between the centres of the cells k (alpha >= 1/2) and k + 1
// (alpha < 1/2) above it:
//   z_s = z_k + h (alpha_k - 1/2) / (alpha_k - alpha_{k+1});
// the top of the domain if the top cell holds metal, the bottom if none.
// Re-solidified bead: a cell whose centre lies above the original substrate
// top, with alpha >= 1/2, in which at least half of the material points are
// solid again after having reached the liquidus (their peak temperature,
// the melt history that the points carry). In a cross-section (the cells of
// one column index i, across y), the bead's
//   width  = (j_max - j_min + 1) h over the columns j that hold a bead cell,
//   height = max over those columns of (z_s - substrate top);
// along the centre line the same numbers are the bead's length and height.
// The values of the columns are gathered on every rank (a sum of each
// cell's value from its owner), so the result does not depend on the
// number of MPI ranks. Not from the paper: a post-processing of the fields
// of its eqs. (1)-(4).
#ifndef femp_track_shape_h
#define femp_track_shape_h

#include <deal.II/base/parameter_handler.h>

#include <femp/base/parameter_table.h>
#include <femp/grid/background_grid.h>
#include <femp/grid/material_points.h>
#include <femp/io/output.h>

#include <fstream>
#include <string>
#include <vector>

namespace femp
{
  using namespace dealii;

  template <int dim>
  class TrackShape
  {
  public:
    /// Subsection 'Output/Track shape'.
    struct Parameters
    {
      AutoSwitch          write = AutoSwitch::automatic;
      std::vector<double> cross_sections; ///< x of each cross-section, m

      /// Declare (the members' values are the defaults) or read the

      /// entries, each listed once.

      void

      add_parameters(ParameterTable &table);

      static void
      declare_parameters(ParameterHandler &prm);
      void
      parse_parameters(ParameterHandler &prm);
      /// True if the files are written (auto: with the melt flow).
      bool
      enabled(const bool melt_flow) const
      {
        return write == AutoSwitch::on ||
               (write == AutoSwitch::automatic && melt_flow);
      }
    };

    /// The columns of one section (the centre line or a cross-section).
    struct Section
    {
      std::string         name;    ///< "centre" or "cross_<n>"
      std::vector<double> x, y;    ///< column centres, m (2D: y unused)
      std::vector<double> surface; ///< z_s, m
      std::vector<int>    bead;    ///< 1 if the column holds a bead cell
      double              width = 0, height = 0; ///< m (centre: length)
    };

    /// @p centre_y: the track's centre line (3D; the column of cells that
    /// contains it); @p substrate_top: the original substrate top, m;
    /// @p default_x: the cross-section when the parameter lists none.
    TrackShape(const Parameters          &prm,
               const BackgroundGrid<dim> &grid,
               const double               centre_y,
               const double               substrate_top,
               const double               default_x);

    /// 1 in the local cells that hold re-solidified metal by the points
    /// (at least half of them solid with peak temperature >= @p
    /// T_liquidus), else 0.
    std::vector<double>
    resolidified_cells(const MaterialPoints<dim> &points,
                       const double               T_liquidus) const;

    /// The sections from the metal fraction @p alpha and the bead-cell
    /// marks @p resolidified (local cell fields; owned values are used).
    /// Collective; the result is the same on every rank.
    std::vector<Section>
    measure(const std::vector<double> &alpha,
            const std::vector<double> &resolidified) const;

    /// Rank 0: write track_shape_<n>.csv (every column of every section)
    /// On resume from a checkpoint at @p time: drop the rows of
    /// track_bead.csv after it and append from there.
    void
    resume(const std::string &directory, const double time)
    {
      if (Utilities::MPI::this_mpi_process(grid.communicator()) == 0)
        reopen_series_at(bead_csv, directory + "/track_bead.csv", time);
    }

    /// and append a row to track_bead.csv (width and height per section)
    /// in @p directory.
    void
    write(const std::string          &directory,
          const unsigned int          n,
          const double                time,
          const std::vector<Section> &sections);

  private:
    const BackgroundGrid<dim> &grid;
    const double               z_top; ///< original substrate top, m
    /// Global column indices (i, j) of each section's columns.
    std::vector<std::vector<std::array<int, 2>>> columns;
    std::vector<std::string>                     names;
    std::ofstream                                bead_csv;

    /// z_s of a column from its alpha values, bottom to top.
    double
    surface_height(const double *alpha) const;
  };
} // namespace femp

#endif
