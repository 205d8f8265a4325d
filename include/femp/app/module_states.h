// femp: the modules that carry state from one step to the next, each under
// a named checkpoint section (doc/checkpoint.md). A module registers once
// (add(): its save_state() and load_state() are found by name); writing a
// checkpoint and restoring from one are loops over the registered modules,
// in the order of registration.
#ifndef femp_module_states_h
#define femp_module_states_h

#include <deal.II/base/conditional_ostream.h>

#include <femp/io/checkpoint.h>

#include <functional>
#include <string>
#include <vector>

namespace femp
{
  template <int dim>
  class ModuleStates
  {
  public:
    using Save = std::function<void(StateWriter &)>;
    using Load = std::function<void(std::vector<StateReader> &)>;

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
    /// State kept by other means than a module's two functions.
    void
    add(const std::string &name,
        const Save        &save,
        const Load        &load,
        const std::string &missing = std::string())
    {
      entries.push_back({name, save, load, missing});
    }

    /// Write every registered module's section into a checkpoint at
    /// @p step, @p time (collective), say so on @p out; returns its
    /// directory.
    std::string
    write(Checkpoint<dim>    &checkpoint,
          const unsigned int  step,
          const double        time,
          ConditionalOStream &out) const;
    /// Restore every registered module from the checkpoint read, say so
    /// on @p out.
    void
    restore(const Checkpoint<dim> &checkpoint, ConditionalOStream &out) const;

  private:
    struct Entry
    {
      std::string name;
      Save        save;
      Load        load;
      std::string missing;
    };
    std::vector<Entry> entries;
  };
} // namespace femp

#endif
