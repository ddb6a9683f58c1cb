// What the operating system says about memory: this process's resident size and how much
// more it can have (Linux /proc; 0 where unknown).
#pragma once

namespace mvpt {

/// Bytes this process holds in physical memory now.
double resident_bytes();
/// Bytes of memory available for new allocations without swapping (MemAvailable).
double available_bytes();

} // namespace mvpt
