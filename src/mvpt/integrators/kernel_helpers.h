// Lane helpers shared by the wavefront's vector kernels (path_kernels*.cpp): branch-free
// forms of std::max / std::min and SurfaceInteraction::offset_p, bit-identical to the scalar code.
#pragma once

#include <cmath>

#include "../core/math.h"
#include "../render/interaction.h"

namespace mvpt::kernel {

/// std::max(a, b) and std::min(a, b) as selects (same result for every input, NaN included).
[[gnu::always_inline]] inline float max_of(float a, float b) { return select(a < b, b, a); }
[[gnu::always_inline]] inline float min_of(float a, float b) { return select(b < a, b, a); }

/// SurfaceInteraction::offset_p's offset along the geometric normal g, on the side of d.
[[gnu::always_inline]] inline float offset_along(float px, float py, float pz, float gx, float gy, float gz, float dx,
                                                float dy, float dz) {
    // std::max({|x|, |y|, |z|}) keeps the first of equal values; all are non-negative here.
    float m = max_of(max_of(std::abs(px), std::abs(py)), std::abs(pz));
    float mag = (1.f + m) * RayEpsilon;
    return std::copysign(mag, gx * dx + gy * dy + gz * dz);
}

} // namespace mvpt::kernel
