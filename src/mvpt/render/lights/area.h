// The closed forms that an area emitter of constant radiance amounts to on a parallelogram or a
// sphere, found from its type: vector code samples them (the wavefront path tracer's kernels).
#pragma once

#include "../../core/math.h"

#include <optional>

namespace mvpt {

class Light;

/// A parallelogram emitter of constant radiance whose sample_li picks origin + u.x e1 + u.y e2
/// (uniform by area).
struct QuadEmitter {
    Point3f origin;
    Vec3f e1, e2;
    Normal3f n;
    float inv_area = 0.f;
    Color3f radiance;
};

/// A sphere emitter of constant radiance sampled by Sphere::sample_solid_angle.
struct SphereEmitter {
    Point3f center;
    float radius = 0.f;
    bool flip_normals = false;
    Color3f radiance;
};

/// `light` as a QuadEmitter: an `area` emitter of constant radiance on a parallelogram mesh,
/// whose sample_li is exactly QuadEmitter's sampling (nothing for other lights).
std::optional<QuadEmitter> quad_emitter(const Light &light);
/// `light` as a SphereEmitter: an `area` emitter of constant radiance on a sphere (nothing for other lights).
std::optional<SphereEmitter> sphere_emitter(const Light &light);

} // namespace mvpt
