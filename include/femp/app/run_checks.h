// femp: checks of a scene that span several modules or the machine, run by
// the driver before any work: the scene file itself (readable, not empty,
// no parameter set twice), names of output files, a memory estimate against
// the machine's memory, and the output directory (parameters.prm written
// into it). Also the run limits that keep a scene from running on without
// feedback (doc/input_errors.md).
#ifndef femp_run_checks_h
#define femp_run_checks_h

#include <deal.II/base/mpi.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/timer.h>

#include <femp/base/parameter_table.h>

#include <map>
#include <string>
#include <utility>

namespace femp
{
  /// At most the first ~80 characters of @p value, for messages.
  std::string
  short_value(const std::string &value);

  /// The scene file must be a readable regular file with at least one 'set'
  /// or 'include' statement, and must not set one parameter twice (an
  /// 'include' followed by a 'set' of an included parameter is allowed).
  void
  check_scene_file(const std::string &file_name);

  /// Subsection 'Run limits': memory limit and flow sub-step bound.
  void
  declare_run_limits(dealii::ParameterHandler &prm);

  /// Limits read by check_memory(); defaults if it was not called.
  struct RunLimits
  {
    double       memory_limit       = 0;      ///< bytes, 0: no check
    unsigned int max_flow_substeps  = 100000; ///< per temperature step
    unsigned int max_solid_substeps = 100000; ///< per temperature step

    /// The entries of subsection 'Run limits', each listed once (the
    /// members' values are the defaults).
    struct Parameters
    {
      double       memory_limit           = 0; ///< GiB; 0: this machine's
      double       disk_limit             = 0; ///< GiB; 0: the free space
      unsigned int max_flow_substeps      = 100000;
      unsigned int max_solid_substeps     = 100000;
      double       progress_wall_interval = 30; ///< s

      void
      add_parameters(ParameterTable &table);
      /// Read from a handler that is not changed.
      static Parameters
      of(const dealii::ParameterHandler &prm);
    };
  };
  const RunLimits &
  run_limits();

  /// Names of files inside the output directory must stay inside it (no
  /// '..' component, no absolute path, probe line names without '/').
  void
  check_output_file_names(const dealii::ParameterHandler &prm);

  /// Values no module refuses by itself: a plain-number initial
  /// temperature in (0, 1e5] K, a packing fraction in (0, 0.64], a line
  /// scan of non-zero length, a scan-path file in the format of the
  /// dimension.
  void
  check_values(const dealii::ParameterHandler &prm);

  /// Refuse a scene whose rough memory estimate (cells, points, probe
  /// samples) exceeds 'Run limits/Memory limit' (default: the machine's
  /// memory from /proc/meminfo); also reads run_limits().
  void
  check_memory(dealii::ParameterHandler &prm, const unsigned int n_ranks);

  /// Refuse a scene whose rough output estimate (field outputs of the
  /// cells, material-point outputs, format) exceeds 'Run limits/Disk limit'
  /// (default: the free space where 'Output/Directory' lies).
  void
  check_disk(dealii::ParameterHandler &prm);

  /// Collective: create the output directory, apply 'Output/Existing
  /// directory' (refuse, or clear earlier numbered files) and write the
  /// parameters used to parameters.prm (rank 0). Throws on every rank.
  void
  prepare_output_directory(const dealii::ParameterHandler &prm,
                           const MPI_Comm                  comm);

  /// The part of the step a timer section belongs to: 'flow: ...' and
  /// 'setup: ...' sections are summed as 'melt flow' and 'setup' (the
  /// cost report, layer_cost.csv).
  std::string
  part_of(const std::string &section);

  /// Wall time (s) and calls per timer section of this rank: the parts of
  /// a run before its rebalances (doc/builds.md, "Rebalancing at a layer
  /// start").
  using TimerSums = std::map<std::string, std::pair<double, unsigned int>>;

  /// @p sums with the sections of @p timer added.
  void
  add_timer_sums(const dealii::TimerOutput &timer, TimerSums &sums);

  /// The end-of-run cost (collective): on the screen (rank 0) the wall
  /// time since femp started and, per part of the step (the sections of
  /// @p timer, those named 'flow: ...' or 'setup: ...' summed as one
  /// part), the slowest rank's wall time and its share; in
  /// @p directory/timing.txt every section with its calls and its
  /// minimum, average and maximum wall time over the ranks; @p earlier: the
  /// sections of the parts of the run before its last rebalance, added to @p
  /// timer's.
  void
  print_cost_report(const dealii::TimerOutput &timer,
                    const std::string         &directory,
                    const MPI_Comm             comm,
                    const TimerSums           &earlier = {});
} // namespace femp

#endif
