#pragma once
// Double-precision 3-vectors as plain arrays: the exact geometric tests of segment_cull.cpp and
// rig_visibility.cpp.

namespace mvpt {

inline double dot3(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

inline void cross3(const double *a, const double *b, double *out) {
    out[0] = a[1] * b[2] - a[2] * b[1], out[1] = a[2] * b[0] - a[0] * b[2], out[2] = a[0] * b[1] - a[1] * b[0];
}

}  // namespace mvpt
