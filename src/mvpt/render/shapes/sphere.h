// What a `sphere` shape is, for code that treats spheres apart (emitter sampling in vector
// kernels, the occluders of multi-view path tracing's segment culling).
#pragma once

#include "../../core/math.h"

#include <optional>

namespace mvpt {

class Shape;

/// A sphere in world space, its normals pointing inwards when `flip_normals`.
struct SphereGeometry {
    Point3f center;
    double radius = 0.0;
    bool flip_normals = false;
};

/// `shape`'s sphere when it is a `sphere` (nothing for other shapes).
std::optional<SphereGeometry> sphere_geometry(const Shape &shape);

} // namespace mvpt
