// NumPy arrays for the bindings: float output arrays owned by a capsule, and
// the (n, 3) float input type the probes take.
#pragma once

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <cstddef>

namespace mvpt_py {

namespace nb = nanobind;

using Vec3Array = nb::ndarray<const float, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>;
using OutArray = nb::ndarray<nb::numpy, float>;

/// A zero-filled float array of shape (n,) when c == 1, else (n, c).
inline OutArray out_array(size_t n, size_t c) {
    float *data = new float[n * c]();
    nb::capsule owner(data, [](void *p) noexcept { delete[] static_cast<float *>(p); });
    size_t shape[2] = {n, c};
    return OutArray(data, c == 1 ? 1 : 2, shape, owner);
}

} // namespace mvpt_py
