// femp: checkpoint write and restore as loops over the modules with state
// (module_states.h).
#include <femp/app/module_states.h>
#include <femp/base/input_checks.h>

namespace femp
{
  template <int dim>
  std::string
  ModuleStates<dim>::write(Checkpoint<dim>   &checkpoint,
                           const unsigned int step,
                           const double       time) const
  {
    std::vector<StateWriter> bytes(entries.size());
    std::vector<std::pair<std::string, const StateWriter *>> sections;
    for (std::size_t i = 0; i < entries.size(); ++i)
      {
        entries[i].save(bytes[i]);
        sections.emplace_back(entries[i].name, &bytes[i]);
      }
    return checkpoint.write(step, time, sections);
  }

  template <int dim>
  void
  ModuleStates<dim>::restore(const Checkpoint<dim> &checkpoint) const
  {
    for (const auto &e : entries)
      {
        if (!e.missing.empty())
          require(checkpoint.has_section(e.name),
                  "Checkpoint/Resume from",
                  checkpoint.path_read(),
                  e.missing);
        auto parts = checkpoint.section(e.name);
        e.load(parts);
      }
  }

  template class ModuleStates<2>;
  template class ModuleStates<3>;
} // namespace femp
