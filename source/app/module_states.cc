// femp: checkpoint write and restore as loops over the modules with state
// (module_states.h).
#include <femp/app/module_states.h>
#include <femp/base/free_heap.h>
#include <femp/base/input_checks.h>

namespace femp
{
  template <int dim>
  ModuleStates<dim>::ModuleStates(
    const typename Checkpoint<dim>::Parameters &prm,
    const std::string                          &output_directory,
    const typename Checkpoint<dim>::Scene      &scene,
    MPI_Comm                                    comm)
      : checkpoint(
          std::make_unique<Checkpoint<dim>>(prm, output_directory, scene, comm))
  {
    if (checkpoint->resuming())
      checkpoint->read(); // refuses a corrupt or mismatched one here
  }

  template <int dim>
  std::string
  ModuleStates<dim>::write(const unsigned int   step,
                           const double         time,
                           ConditionalOStream  &out,
                           TimerOutput         &timer,
                           const CheckpointKind kind)
  {
    TimerOutput::Scope       t(timer, "checkpoint");
    std::vector<StateWriter> bytes(entries.size());
    std::vector<std::pair<std::string, const StateWriter *>> sections;
    for (std::size_t i = 0; i < entries.size(); ++i)
      {
        entries[i].save(bytes[i]);
        sections.emplace_back(entries[i].name, &bytes[i]);
      }
    const std::string dir = checkpoint->write(step, time, sections, kind);
    // The modules' bytes are freed on return; their memory goes back.
    bytes.clear();
    bytes.shrink_to_fit();
    release_free_heap();
    out << "Checkpoint: step " << step << ", time " << time << " s -> " << dir
        << " (" << checkpoint->bytes_written() << " bytes)" << std::endl;
    return dir;
  }

  template <int dim>
  void
  ModuleStates<dim>::restore(ConditionalOStream &out, TimerOutput &timer)
  {
    TimerOutput::Scope t(timer, "checkpoint");
    for (const auto &e : entries)
      {
        if (!e.load)
          continue;
        if (!e.missing.empty())
          require(checkpoint->has_section(e.name),
                  "Checkpoint/Resume from",
                  checkpoint->path_read(),
                  e.missing);
        auto parts = checkpoint->section(e.name);
        e.load(parts);
      }
    out << "Resumed from " << checkpoint->path_read() << " (written by "
        << checkpoint->saved_ranks() << " rank(s)) at step "
        << checkpoint->saved_step() << ", time " << checkpoint->saved_time()
        << " s" << std::endl;
    for (const auto &then : restored)
      then();
    checkpoint->release();
    release_free_heap(); // the file's image and the readers' copies
  }

  template class ModuleStates<2>;
  template class ModuleStates<3>;
} // namespace femp
