#pragma once
//! \file Process-wide allocator tuning for programs that build and factor large sparse systems, and the
//! machine's memory for refusing work that cannot fit.

#include <cstdint>
#include <string>

namespace msd {

//! The machine's physical memory in bytes (sysconf), or 0 when it cannot be told.
std::uint64_t physical_memory();

//! Makes glibc's malloc keep freed memory for reuse instead of returning it to the system: large blocks
//! come from the heap rather than fresh mmap()s, and up to 1 GiB of free heap top stays mapped (beyond
//! that glibc trims it back to 256 MiB). CHOLMOD, OpenBLAS and Eigen allocate and free big temporaries
//! many times during a factorisation; with the default settings every one of them is page-faulted in
//! anew. Measured on the 1M-vertex bi-Laplacian (2 cores): factorisation 9.7 s -> 6.2 s, assembly 2.0 s
//! -> 1.1 s. The price: after a peak the process's resident size stays up to 1 GiB above what it uses.
//! Does nothing under an address-space limit (ulimit -v): growing the heap by 256 MiB steps would fail
//! where the limit leaves less, with mmap() turned off (measured: `msdeform --version` under 300 MB).
//! Call once at program start (the msdeform tool and the benchmarks do); a library never calls it on its
//! own (Python scripts may, with msdeform.retain_freed_memory()).
void retain_freed_memory();

//! Returns the pages of freed heap memory to the system (glibc's malloc_trim; nothing elsewhere), also in
//! the middle of the heap, where retain_freed_memory() keeps them. For the end of a phase whose large
//! temporaries the next phase cannot reuse in place: after the low-pass base (low_pass.cpp), the holes
//! its factor left below B stayed resident while the shell factored beside them (the 6.5M lift's
//! multi-scale prepare peaked at 19.9 GB). Costs a walk of the heap and the page faults of reusing them.
void release_freed_memory();

//! The smallest memory limit of the cgroups this process is in (v2 memory.max, v1
//! memory.limit_in_bytes; a container's limit), in bytes; 0 where there is none or it cannot be read.
std::uint64_t cgroup_memory_limit();

//! The same as release_freed_memory(), only where the freed heap memory exceeds an eighth of the memory
//! the process may use (the physical memory, or a smaller cgroup limit): the pages' new faults cost a 1M
//! shell factorisation about 10 %, so not where memory is plentiful. True if it trimmed.
//! SparseSPDSolver::factor calls it before its peak: the 9.44M lift's multi-scale prepare, whose shell
//! factors B's bi-Laplacian (1.3e9 factor entries) after the low-pass base, held 6.8 GB of the assembly's
//! freed temporaries there and went beyond 24.4 GB; with them returned it peaks at 22.1 GB.
bool release_freed_memory_if_large();

//! An error message `what`; where it says "out of memory" under an address-space limit it does not name,
//! followed by " under the address-space limit (ulimit -v) of N MB: raise the limit" (the likelier cause
//! than the machine's memory).
std::string out_of_memory_message(const std::string& what);

}  // namespace msd
