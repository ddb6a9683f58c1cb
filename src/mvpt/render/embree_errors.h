#pragma once
// Embree's failures as exceptions. Under a memory limit (ulimit -v, a cgroup) Embree returns
// null from its allocating calls and leaves an error on the device; code that went on would
// crash. Each step that allocates checks, and the render ends with one message instead.

#include <embree3/rtcore.h>

namespace mvpt {

/// Throws std::runtime_error naming `what` (the step) when `device` holds an error, or when
/// `result` is null (Embree returned nothing).
void embree_check(RTCDevice device, const char *what, const void *result = reinterpret_cast<const void *>(1));

/// `p`, checked by embree_check.
template <typename T> T *embree_checked(T *p, RTCDevice device, const char *what) {
    embree_check(device, what, p);
    return p;
}

} // namespace mvpt
