// femp: hands the memory that the heap holds free back to the operating
// system, after the phases that allocate large temporary buffers (the setup,
// a checkpoint's write and its restore). No equation of the paper.
//
// Why it is needed: SuperLU_DIST, which deal.II links through PETSc, turns
// off two things of glibc's malloc when it is loaded (mallopt M_MMAP_MAX = 0
// and M_TRIM_THRESHOLD = -1): large blocks no longer get their own memory
// maps, which free() would return, and the heap is never trimmed. Every
// buffer that femp frees then stays resident: without the release below,
// writing a checkpoint of 3 GB leaves about 4.6 GB more resident. femp
// leaves the library's settings as they are (memory maps for large blocks
// would change the cost of the steps' temporary buffers) and returns the
// free memory after the phases that free much (malloc_trim).
#ifndef femp_free_heap_h
#define femp_free_heap_h

namespace femp
{
  /// Returns the heap's free pages to the operating system when the heap
  /// holds at least 64 MiB free (glibc's malloc_trim; nothing with another
  /// C library). Local to the calling process; its cost is that of the
  /// page faults when the memory is used again (about 0.1 s per GB).
  void
  release_free_heap();
} // namespace femp

#endif
