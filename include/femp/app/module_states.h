// femp: the modules that carry state from one step to the next, each under
// a named checkpoint section (doc/checkpoint.md), and the checkpoint they
// are written to and restored from. A module registers once (add(): its
// save_state() and load_state() are found by name); writing a checkpoint
// and restoring from one are loops over the registered modules, in the
// order of registration, then over what follows a restore (after_restore()).
#ifndef femp_module_states_h
#define femp_module_states_h

#include <deal.II/base/conditional_ostream.h>
#include <deal.II/base/timer.h>

#include <femp/base/input_checks.h>
#include <femp/io/checkpoint.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace femp
{
  using namespace dealii;

  template <int dim>
  class ModuleStates
  {
  public:
    using Save = std::function<void(StateWriter &)>;
    using Load = std::function<void(std::vector<StateReader> &)>;

    /// The checkpoint of @p prm (a relative directory lies in
    /// @p output_directory); when resuming, it is read here, so that a
    /// corrupt or mismatched one is refused before any work.
    ModuleStates(const typename Checkpoint<dim>::Parameters &prm,
                 const std::string                          &output_directory,
                 const typename Checkpoint<dim>::Scene      &scene,
                 MPI_Comm                                    comm);

    /// Whether the run resumes from a checkpoint.
    bool
    resuming() const
    {
      return checkpoint->resuming();
    }
    /// The checkpoint itself (its triggers carry state too).
    Checkpoint<dim> &
    checkpoint_file()
    {
      return *checkpoint;
    }

    /// A module with save_state(StateWriter &) and
    /// load_state(std::vector<StateReader> &) under section @p name.
    /// @p missing: what to say when a checkpoint lacks the section (empty:
    /// the checkpoint's own error).
    template <class Module>
    void
    add(const std::string &name,
        Module            &module,
        const std::string &missing = std::string())
    {
      add(
        name,
        [&module](StateWriter &out) { module.save_state(out); },
        [&module](std::vector<StateReader> &in) { module.load_state(in); },
        missing);
    }
    /// State kept by other means than a module's two functions. An empty
    /// @p load: the section is read before the restore, by the module that
    /// needs it at its setup (checkpoint_file().section()); restore()
    /// passes it by.
    void
    add(const std::string &name,
        const Save        &save,
        const Load        &load,
        const std::string &missing = std::string())
    {
      // A checkpoint without a section that @p missing explains is refused
      // here, at the setup, before any work.
      if (load && !missing.empty() && resuming())
        require(checkpoint->has_section(name),
                "Checkpoint/Resume from",
                checkpoint->path_read(),
                missing);
      entries.push_back({name, save, load, missing});
    }
    /// What follows a restore once every section is loaded, in the order
    /// of registration.
    void
    after_restore(const std::function<void()> &then)
    {
      restored.push_back(then);
    }

    /// Whether a checkpoint is due after step @p step at @p time
    /// (collective when the wall-clock trigger is on).
    bool
    due(const unsigned int step, const double time)
    {
      return checkpoint->enabled() && checkpoint->due(step, time);
    }
    /// Write every registered module's section into a checkpoint of
    /// @p kind at @p step, @p time (collective, timed on @p timer), say so
    /// on @p out; returns its directory.
    std::string
    write(const unsigned int   step,
          const double         time,
          ConditionalOStream  &out,
          TimerOutput         &timer,
          const CheckpointKind kind = CheckpointKind::user);
    /// Restore every registered module from the checkpoint read (timed on
    /// @p timer), run what follows a restore, say so on @p out, and let
    /// the checkpoint's bytes go.
    void
    restore(ConditionalOStream &out, TimerOutput &timer);

  private:
    struct Entry
    {
      std::string name;
      Save        save;
      Load        load;
      std::string missing;
    };
    std::unique_ptr<Checkpoint<dim>>   checkpoint;
    std::vector<Entry>                 entries;
    std::vector<std::function<void()>> restored;
  };
} // namespace femp

#endif
