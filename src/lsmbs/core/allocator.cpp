#include "lsmbs/core/allocator.hpp"

#if __has_include(<malloc.h>)
#include <malloc.h>
#endif

namespace lsmbs {

void keep_freed_memory() {
#if defined(M_TRIM_THRESHOLD) && defined(M_MMAP_THRESHOLD)
  mallopt(M_TRIM_THRESHOLD, 512 * 1024 * 1024);
  mallopt(M_MMAP_THRESHOLD, 32 * 1024 * 1024);  // glibc's largest on 64-bit systems
#endif
}

}  // namespace lsmbs
