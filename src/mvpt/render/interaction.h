// A ray's hit on a surface: position, normals, shading frame, uv.
#pragma once

#include "../core/math.h"

namespace mvpt {

class Shape;
class Instance;

/// Relative offset for leaving a surface (Mitsuba's RayEpsilon scale).
inline constexpr float RayEpsilon = 89.f * 0x1p-24f;
inline constexpr float ShadowEpsilon = 10.f * RayEpsilon;

/// How far along the geometric normal n a ray from p leaves the surface, signed to the side
/// of d: (1 + max |p_i|) RayEpsilon, Mitsuba's offset (one lane; the kernels run it on many).
[[gnu::always_inline]] inline float ray_offset(Point3f p, Normal3f n, Vec3f d) {
    // max_of keeps the first of equal values, as std::max({...}); all are non-negative here.
    const float m = max_of(max_of(std::abs(p.x), std::abs(p.y)), std::abs(p.z));
    return std::copysign((1.f + m) * RayEpsilon, n.x * d.x + n.y * d.y + n.z * d.z);
}

struct SurfaceInteraction {
    Point3f p;
    float t = Infinity;
    /// Geometric normal, oriented by the shape (not flipped towards the ray).
    Normal3f n;
    /// Shading frame (its n is the interpolated shading normal).
    Frame sh_frame;
    Vec2f uv;
    /// Direction towards the previous vertex, in the shading frame.
    Vec3f wi;
    float time = 0.f;
    const Shape *shape = nullptr;
    /// The instance whose shape was hit (nullptr: none), whose transform takes `shape`'s space
    /// to the world (surface_uv_partials).
    const Instance *instance = nullptr;
    /// Primitive index inside the shape (triangle index for meshes).
    uint32_t prim = 0;
    /// The hit's coordinates on its primitive as the ray tracer reports them (a triangle's
    /// barycentrics b1, b2), for what is interpolated over it (mesh attributes).
    Vec2f prim_uv;

    bool is_valid() const { return shape != nullptr; }
    Vec3f to_local(Vec3f v) const { return sh_frame.to_local(v); }
    Vec3f to_world(Vec3f v) const { return sh_frame.to_world(v); }

    /// Origin moved off the surface along the geometric normal, on the side of `d`.
    Point3f offset_p(Vec3f d) const { return p + n * ray_offset(p, n, d); }
    Ray spawn_ray(Vec3f d) const { return Ray{offset_p(d), d, 0.f, Infinity, time}; }
    /// Shadow ray towards `target` that stops just short of it.
    Ray spawn_ray_to(Point3f target) const {
        Point3f o = offset_p(target - p);
        Vec3f d = target - o;
        float dist = norm(d);
        return Ray{o, d / dist, 0.f, dist * (1.f - ShadowEpsilon), time};
    }
};

} // namespace mvpt
