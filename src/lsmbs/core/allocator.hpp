#pragma once
// Heap settings for long runs (glibc). By default glibc returns the top of the heap to the system
// once more than 128 kB are free, and serves blocks above a dynamic threshold by mmap; a run that
// allocates and frees a large temporary at every residual evaluation (the IDAS sensitivity
// residual assembles the GGL Jacobian) then takes page faults for fresh zeroed pages at every
// call. Keeping freed memory in the process removes that (docs/performance.md, "Allocator").
namespace lsmbs {

/// Raises glibc's trim threshold to 512 MB and its mmap threshold to 32 MB (its largest); a
/// no-op elsewhere. Called by the command line and the Python module at start.
void keep_freed_memory();

}  // namespace lsmbs
