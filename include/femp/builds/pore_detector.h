// femp: pores of a build (doc/builds.md, "Porosity"): gas enclosed in the
// fused metal (lack of fusion between tracks and layers, keyhole pores),
// found on the background grid from the metal fraction alpha and the share
// of each cell's metal that is unfused powder.
//
//   - open cells: cells whose fused metal fraction alpha (1 - s_p) is below
//     'Porosity/Fused fraction threshold' (s_p: the share of the cell's point
//     volume that is powder that never melted); gas and unfused powder are
//     open, so the gas between the grains of the bed is not a pore;
//   - the free gas: the open cells connected through open face neighbours
//     to the top row of the domain;
//   - a pore: a set of open cells connected through open face neighbours
//     that does not reach the top row (a flood fill: each rank labels its
//     components, then the labels, the smallest global cell number of the
//     component, pass through the ghost layer until no rank changes one;
//     the result does not depend on the partition and a pore across a rank
//     boundary is counted once);
//   - its gas volume: sum of (1 - alpha) V over its cells and over the
//     closed cells around it (the 3^dim neighbours; a closed cell next to
//     several pores or the free gas goes to the one with the smallest
//     label, the free gas first); its unfused powder: alpha s_p V over the
//     same cells; its centroid weighted by the gas volume; its equivalent
//     diameter (6 V / pi)^(1/3) in 3D, (4 A / pi)^(1/2) in 2D;
//   - relative density of the built region (cells whose centre lies at or
//     above 'Built region bottom'): (M + P_s) / (M + P_s + P_g), with M
//     the fused metal alpha (1 - s_p) V outside pores, P_s the unfused
//     powder and P_g the gas of the pores there.
#ifndef femp_pore_detector_h
#define femp_pore_detector_h

#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/point.h>

#include <femp/base/parameter_table.h>
#include <femp/grid/background_grid.h>
#include <femp/grid/material_points.h>

#include <fstream>
#include <string>
#include <vector>

namespace femp
{
  using namespace dealii;

  template <int dim>
  class PoreDetector
  {
  public:
    struct Parameters
    {
      /// Porosity/Detect pores: "auto" (with a layer schedule), "true" or
      /// "false"; only in scenes that carry points.
      AutoSwitch detect = AutoSwitch::automatic;
      /// Porosity/Fused fraction threshold (-): cells below are open.
      double threshold = 0.5;
      /// Porosity/Minimum pore volume (m^3): smaller pores are not listed.
      double min_volume = 0;
      /// Porosity/Built region bottom (m); NaN: the substrate top.
      double bottom       = 0;
      bool   bottom_given = false;

      /// Declare (the members' values are the defaults) or read the

      /// entries, each listed once.

      void

      add_parameters(ParameterTable &table);

      static void
      declare_parameters(ParameterHandler &prm);
      void
      parse_parameters(ParameterHandler &prm);
      /// Whether the detector runs ('auto': @p builds, a scene with a
      /// layer schedule).
      bool
      enabled(const bool builds) const
      {
        return detect == AutoSwitch::on ||
               (detect == AutoSwitch::automatic && builds);
      }
    };

    struct Pore
    {
      unsigned int n_cells  = 0; ///< open cells of the pore
      double       volume   = 0; ///< gas volume, m^3 (2D: m^2)
      double       powder   = 0; ///< unfused powder inside, m^3 (2D: m^2)
      double       diameter = 0; ///< equivalent diameter, m
      Point<dim>   centroid;     ///< m
    };

    struct Result
    {
      std::vector<Pore> pores;                ///< in the order of their labels
      double            pore_volume      = 0; ///< all listed pores' gas
      double            built_metal      = 0; ///< M of the built region
      double            built_powder     = 0; ///< P_s of the built region
      double            built_pores      = 0; ///< P_g of the built region
      double            relative_density = 1;
      /// Per cell of the local box: the pore's number (1, 2, ... in the
      /// order of pores) on its open cells, 0 elsewhere (owned values).
      std::vector<double> pore_number;
    };

    /// @p default_bottom: the built region's bottom when the parameter
    /// gives none (the substrate top), m.
    PoreDetector(const Parameters          &prm,
                 const BackgroundGrid<dim> &grid,
                 const double               default_bottom);

    /// Per cell of the local box, the share of the point volume of the
    /// cell that is powder that never melted (state powder), and the share
    /// whose peak temperature lies in [@p T_solidus, @p T_liquidus)
    /// (partially molten: melting began, the liquidus was never reached).
    /// Owned values; 0 in cells without points.
    static std::pair<std::vector<double>, std::vector<double>>
    powder_shares(const BackgroundGrid<dim> &grid,
                  const MaterialPoints<dim> &points,
                  const double               T_solidus,
                  const double               T_liquidus);

    /// The pores of the metal fraction @p alpha and powder share
    /// @p powder (local cell fields, owned values used; null: no powder).
    /// Collective; the result is the same on every rank.
    Result
    find(const std::vector<double> &alpha,
         const std::vector<double> *powder) const;

    /// Rank 0: append the row of @p r to porosity.csv and its pores to
    /// pores.csv in @p directory (created with their headers at the first
    /// call).
    void
    write(const std::string &directory,
          const unsigned int n,
          const double       time,
          const Result      &r);
    /// On resume at @p time: drop the rows after it, append from there.
    void
    resume(const std::string &directory, const double time);

  private:
    const Parameters           prm;
    const BackgroundGrid<dim> &grid;
    const double               bottom;
    std::ofstream              summary_csv, pores_csv;
  };
} // namespace femp

#endif
