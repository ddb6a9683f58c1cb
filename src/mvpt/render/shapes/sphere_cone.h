// Sampling the cone a sphere subtends from a point outside it, uniformly in solid angle
// [Akalin, "Sampling the visible sphere"]: one lane, branch-free. The sphere's light sampling
// (Sphere::sample_solid_angle) and the wavefront's sphere-emitter kernels call it.
#pragma once

#include "../../core/math.h"
#include "../../core/warp.h"
#include "../interaction.h"

namespace mvpt {

/// The radius below which a point's distance from the centre counts as inside the sphere,
/// where it samples by area, not by cone: the radius moved by RayEpsilon away from the side
/// the normals face (outwards with flip_normals), so that points on the surface count inside.
[[gnu::always_inline]] inline float cone_test_radius(float radius, bool flip_normals) {
    return radius * (flip_normals ? (1.f + RayEpsilon) : (1.f - RayEpsilon));
}

struct SphereConeSample {
    Vec3f dir;     ///< from the centre to the sampled point (its outward normal)
    float cos_max; ///< the cone's half-angle cosine
    float pdf;     ///< the solid-angle density, uniform in the cone
};

/// A point on the sphere (center, radius) seen from `ref` outside it, from the numbers u.
[[gnu::always_inline]] inline SphereConeSample sample_sphere_cone(Vec3f center, float radius, Vec3f ref, Vec2f u) {
    const Vec3f dc = center - ref;
    const float inv_dc = 1.f / std::sqrt(squared_norm(dc)), sin_max = radius * inv_dc, sin_max2 = sin_max * sin_max,
                inv_sin_max = 1.f / sin_max, cos_max = safe_sqrt(1.f - sin_max2);
    // Taylor expansion below ~1.5 degrees, where 1 - cos^2 cancels badly.
    const float sin2 = select(sin_max2 > 0.00068523f, 1.f - sqr((cos_max - 1.f) * u.x + 1.f), sin_max2 * u.x);
    const float cos_t = safe_sqrt(1.f - sin2);
    // The angle alpha at the centre between -dc and the sampled point.
    const float cos_alpha = sin2 * inv_sin_max + cos_t * safe_sqrt(1.f - sin2 * inv_sin_max * inv_sin_max);
    const float sin_alpha = safe_sqrt(1.f - cos_alpha * cos_alpha);
    const Vec2f sc_phi = warp::sincos_turn(u.y); // no libm: the same bits in vector loops
    const Vec3f dir = Frame(dc * -inv_dc).to_world({sc_phi.y * sin_alpha, sc_phi.x * sin_alpha, cos_alpha});
    return {dir, cos_max, warp::square_to_uniform_cone_pdf(cos_max)};
}

} // namespace mvpt
