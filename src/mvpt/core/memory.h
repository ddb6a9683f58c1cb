// What the operating system says about memory: this process's resident size and how much
// more it can have (Linux /proc, getrlimit and the cgroup's files; 0 where unknown).
#pragma once

namespace mvpt {

/// The least memory a rendered view-pixel takes, whatever the method: its developed image,
/// variance and sample count (and the count's float copy for Python).
constexpr double MinBytesPerRenderedPixel = 6 * sizeof(float) + sizeof(unsigned) + sizeof(float);

/// Bytes this process holds in physical memory now.
double resident_bytes();

/// How much more memory this process can have, and what sets that bound.
struct MemoryRoom {
    double bytes = 0.0;  ///< 0: unknown
    const char *limit = "the machine";  ///< "the machine", "the address-space limit (ulimit -v)", ...
};

/// The least of: the machine's memory available without swapping (MemAvailable), what the
/// address-space limit (RLIMIT_AS, `ulimit -v`) leaves and what the cgroup's limit
/// (memory.max, a container's) leaves.
MemoryRoom available_memory();

} // namespace mvpt
