// Regression of the bead measurement (TrackShape, doc/cases.md "Bead
// shape") on a tiny heat + melt-flow track (tests/track_bead_scene.prm):
// 100 W over 40 um of powder on 316L, 60 us, the laser off after 20 us.
// Reads track_bead.csv and the last track_shape_<n>.csv of the run and
// checks what must hold for any correct run:
//   - nothing is re-solidified before the laser has passed the section and
//     the melt there has cooled below the solidus (the first rows are 0);
//   - at the end the section holds a bead: width at least one cell and at
//     most the pool's width bound (the box, 64 um), height above 0 and
//     below the powder layer plus two cells (the melt cannot rise higher
//     than the powder it came from, 40 um, by more than the interpolation);
//   - every bead column in the section's file lies inside the reported
//     width, and the reported height is the largest height of those columns.
// Prints the width (cells) and height (um) rounded.
// One argument: the scene.
#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

namespace
{
  std::vector<std::vector<std::string>>
  read_rows(const std::string &file)
  {
    std::ifstream in(file);
    AssertThrow(in, ExcMessage("cannot read " + file));
    std::vector<std::vector<std::string>> rows;
    std::string                           row;
    while (std::getline(in, row))
      if (!row.empty() && row[0] != '#')
        rows.push_back(Utilities::split_string_list(row, ','));
    return rows;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  try
    {
      run_scene<3>(argv[1], comm, {{"Output", "Directory", "out"}});
      MPI_Barrier(comm);
      const auto   series = read_rows("out/track_bead.csv");
      const double h = 8e-6, layer = 40e-6;
      AssertThrow(series.size() == 8, ExcMessage("7 outputs expected"));
      const auto   last   = series.back();
      const double width  = Utilities::string_to_double(last[3]);
      const double height = Utilities::string_to_double(last[4]);
      checks.at_most("bead width in the section at 10 us (while molten), m",
                     Utilities::string_to_double(series[2][3]),
                     0.);
      checks.print("bead width at 60 us (cells)", std::round(width / h), 2);
      checks.print("bead height at 60 us (um)", std::round(height * 1e6), 2);
      checks.in_range("bead width at 60 us / h", width / h, 1, 8);
      checks.in_range("bead height at 60 us / (layer + 2h)",
                      height / (layer + 2 * h),
                      1e-3,
                      1);
      // The section's columns in the last track_shape file.
      const auto shape = read_rows("out/track_shape_00006.csv");
      double     y_lo = 1, y_hi = -1, h_max = 0;
      for (std::size_t r = 1; r < shape.size(); ++r)
        if (shape[r][0] == "cross_1" && shape[r][5] == "1")
          {
            const double y = Utilities::string_to_double(shape[r][2]);
            y_lo           = std::min(y_lo, y);
            y_hi           = std::max(y_hi, y);
            h_max = std::max(h_max, Utilities::string_to_double(shape[r][4]));
          }
      checks.at_most("|width - extent of the bead columns| / h",
                     std::abs(width - (y_hi - y_lo + h)) / h,
                     1e-6);
      checks.at_most("|height - largest bead column height| / h",
                     std::abs(height - h_max) / h,
                     1e-6);
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
