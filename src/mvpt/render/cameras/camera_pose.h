// A camera's rigid frame at one instant, in float for per-ray use.
#pragma once

#include "../../core/transform.h"

namespace mvpt {

/// Camera-to-world frame at one time: the origin (lens centre), the world images of the
/// camera axes (+x left, +y up, +z forward, Mitsuba's look_at) and the inverse linear part.
struct CameraPose {
    Point3f origin{0.f};
    Vec3f axis[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};     ///< columns of the linear part
    Vec3f inv_row[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};  ///< rows of its inverse

    CameraPose() = default;
    /// From an affine camera-to-world transform (its exact inverse comes with it).
    explicit CameraPose(const Transform &t) {
        const Matrix4 &m = t.matrix(), &inv = t.inverse_matrix();
        origin = {float(m.m[0][3]), float(m.m[1][3]), float(m.m[2][3])};
        for (int j = 0; j < 3; ++j) {
            axis[j] = {float(m.m[0][j]), float(m.m[1][j]), float(m.m[2][j])};
            inv_row[j] = {float(inv.m[j][0]), float(inv.m[j][1]), float(inv.m[j][2])};
        }
    }

    /// Camera-space point to world space.
    Point3f to_world(Point3f p) const { return origin + axis[0] * p.x + axis[1] * p.y + axis[2] * p.z; }
    /// Camera-space vector to world space.
    Vec3f vector_to_world(Vec3f v) const { return axis[0] * v.x + axis[1] * v.y + axis[2] * v.z; }
    /// World-space point to camera space.
    Point3f to_camera(Point3f p) const {
        Vec3f d = p - origin;
        return {dot(inv_row[0], d), dot(inv_row[1], d), dot(inv_row[2], d)};
    }
};

} // namespace mvpt
