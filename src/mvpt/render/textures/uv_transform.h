// The `to_uv` parameter of textures: a 2D affine map taken from a 4x4 transform
// (rows/columns x, y and the translation column), as Mitsuba applies it.
#pragma once

#include "../../core/transform.h"

namespace mvpt {

struct UvTransform {
    float a = 1, b = 0, c = 0, d = 0, e = 1, f = 0;
    UvTransform() = default;
    explicit UvTransform(const Transform &t) {
        const Matrix4 &m = t.matrix();
        a = float(m.m[0][0]); b = float(m.m[0][1]); c = float(m.m[0][3]);
        d = float(m.m[1][0]); e = float(m.m[1][1]); f = float(m.m[1][3]);
    }
    Vec2f operator()(Vec2f uv) const { return {a * uv.x + b * uv.y + c, d * uv.x + e * uv.y + f}; }
};

} // namespace mvpt
