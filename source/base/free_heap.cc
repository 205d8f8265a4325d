// femp: release_free_heap() (free_heap.h).
#include <femp/base/free_heap.h>

#include <cstdlib> // defines __GLIBC__ with the C library in use

#if defined(__GLIBC__)
#  include <malloc.h>
#endif

namespace femp
{
  void
  release_free_heap()
  {
#if defined(__GLIBC__)
    // Below 64 MiB of free heap the pages are left to be reused: handing
    // them back and faulting them in again would cost more than they hold.
    constexpr std::size_t least = std::size_t(64) << 20;
#  if __GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 33)
    if (mallinfo2().fordblks < least)
      return;
#  endif
    malloc_trim(0);
#endif
  }
} // namespace femp
