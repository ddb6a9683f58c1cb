// Lane helpers shared by the wavefront's vector kernels (path_kernels*.cpp): the ends of their
// BSDF-sampling and next-event steps and sphere emitter sampling, written with the scalar
// code's own branch-free steps (ray_offset, rr_survival, mis_power), bit-identical to it.
#pragma once

#include <cmath>

#include "../../core/math.h"
#include "../../core/warp.h"
#include "../../render/interaction.h"
#include "../../render/shapes/sphere_cone.h"
#include "path_kernels.h"
#include "path_steps.h"

namespace mvpt::kernel {

/// SurfaceInteraction::offset_p's offset of lane values (ray_offset).
[[gnu::always_inline]] inline float offset_along(float px, float py, float pz, float gx, float gy, float gz, float dx,
                                                float dy, float dz) {
    return ray_offset(Point3f(px, py, pz), Normal3f(gx, gy, gz), Vec3f(dx, dy, dz));
}

/// The end of a BSDF-sampling kernel, li's steps after Bsdf::sample: the next ray
/// (Frame::to_world of the local direction wo, SurfaceInteraction::spawn_ray), the throughput
/// times the sample's weight (wr, wg, wb), then Russian roulette in li's order (max_value, then
/// q = min(t eta^2, 0.95)). Column blocks of lane i: the shading frame s, t, n from S0, the
/// position and geometric normal from P0, throughput, eta, u_rr and whether roulette applies
/// from B0; outputs ray origin, direction, density and whether the path continues from O0.
template <size_t S0, size_t P0, size_t B0, size_t O0>
[[gnu::always_inline]] inline void next_ray_and_roulette(float *c, size_t s, size_t i, float wox, float woy, float woz,
                                                         float pdf, float wr, float wg, float wb, bool weight_ok) {
    auto col = [c, s, i](size_t k) -> float & { return c[k * s + i]; };
    float dx = (col(S0 + 0) * wox + col(S0 + 3) * woy) + col(S0 + 6) * woz;
    float dy = (col(S0 + 1) * wox + col(S0 + 4) * woy) + col(S0 + 7) * woz;
    float dz = (col(S0 + 2) * wox + col(S0 + 5) * woy) + col(S0 + 8) * woz;
    const float px = col(P0), py = col(P0 + 1), pz = col(P0 + 2);
    const float gx = col(P0 + 3), gy = col(P0 + 4), gz = col(P0 + 5);
    float off = offset_along(px, py, pz, gx, gy, gz, dx, dy, dz);
    col(O0) = px + gx * off;
    col(O0 + 1) = py + gy * off;
    col(O0 + 2) = pz + gz * off;
    col(O0 + 3) = dx;
    col(O0 + 4) = dy;
    col(O0 + 5) = dz;
    col(O0 + 6) = pdf;
    float br = col(B0) * wr, bg = col(B0 + 1) * wg, bb = col(B0 + 2) * wb;
    float t_max = max_of(br, max_of(bg, bb));
    const float eta = col(B0 + 3);
    float q = rr_survival(t_max, eta);
    bool rr_on = col(B0 + 5) > 0.f;
    float inv_q = 1.f / q;
    col(B0) = select(rr_on, br * inv_q, br);
    col(B0 + 1) = select(rr_on, bg * inv_q, bg);
    col(B0 + 2) = select(rr_on, bb * inv_q, bb);
    bool alive = weight_ok & (t_max > 0.f) & !(rr_on & (col(B0 + 4) >= q));
    col(O0 + 7) = select(alive, 1.f, 0.f);
}

/// The end of a next-event kernel, li's steps after the BSDF value f and density `pdf` at the
/// emitter sample: the power-heuristic MIS weight, the contribution throughput f (L/pdf)
/// (light count) w, and the shadow ray (spawn_ray(d) towards an infinitely distant emitter,
/// else spawn_ray_to(p)). Column blocks of lane i: position and geometric normal from P0; the
/// emitter sample (direction, point, distance, density, delta) from L0; its weight from W0;
/// the throughput from B0; outputs shadow ray (origin, direction, t_max), contribution and
/// whether it counts from O0.
template <size_t P0, size_t L0, size_t W0, size_t B0, size_t O0>
[[gnu::always_inline]] inline void nee_contribution_and_shadow_ray(float *c, size_t s, size_t i, float fr, float fg,
                                                                   float fb, float pdf, bool ok, float light_count) {
    auto col = [c, s, i](size_t k) -> float & { return c[k * s + i]; };
    float w = select(col(L0 + 8) > 0.f, 1.f, mis_power(col(L0 + 7) / light_count, pdf));
    col(O0 + 7) = ((col(B0) * fr) * (col(W0) * light_count)) * w;
    col(O0 + 8) = ((col(B0 + 1) * fg) * (col(W0 + 1) * light_count)) * w;
    col(O0 + 9) = ((col(B0 + 2) * fb) * (col(W0 + 2) * light_count)) * w;
    col(O0 + 10) = select(ok, 1.f, 0.f);

    const float px = col(P0), py = col(P0 + 1), pz = col(P0 + 2);
    const float ldx = col(L0), ldy = col(L0 + 1), ldz = col(L0 + 2);
    const float lpx = col(L0 + 3), lpy = col(L0 + 4), lpz = col(L0 + 5);
    bool inf = std::abs(col(L0 + 6)) == Infinity; // std::isinf
    float ex = select(inf, ldx, lpx - px), ey = select(inf, ldy, lpy - py), ez = select(inf, ldz, lpz - pz);
    const float gx = col(P0 + 3), gy = col(P0 + 4), gz = col(P0 + 5);
    float off = offset_along(px, py, pz, gx, gy, gz, ex, ey, ez);
    float ox = px + gx * off, oy = py + gy * off, oz = pz + gz * off;
    float tx = lpx - ox, ty = lpy - oy, tz = lpz - oz;
    float dist = std::sqrt(tx * tx + ty * ty + tz * tz);
    float inv = 1.f / dist;
    col(O0) = ox;
    col(O0 + 1) = oy;
    col(O0 + 2) = oz;
    col(O0 + 3) = select(inf, ldx, tx * inv);
    col(O0 + 4) = select(inf, ldy, ty * inv);
    col(O0 + 5) = select(inf, ldz, tz * inv);
    col(O0 + 6) = select(inf, Infinity, dist * (1.f - ShadowEpsilon));
}

/// A point on a sphere emitter seen from p (outside), sampled uniformly in the subtended cone
/// (sample_sphere_cone, as Sphere::sample_solid_angle) with AreaLight::sample_li's direction,
/// distance, density and weight L/pdf, operation for operation as the scalar code.
struct SphereEmitterSample {
    float lpx, lpy, lpz;  ///< the point on the sphere
    float vx, vy, vz;     ///< from p to it
    float ldx, ldy, ldz;  ///< unit direction
    float dist, pdf;      ///< distance, solid-angle density
    float wr, wg, wb;     ///< radiance / pdf
    bool sampled;         ///< false where li would skip the sample
};
/// `u` = (ux, uy) the two numbers of the emitter sample, `q` the SphereTable's rows and `k`
/// the sphere's entry (centre, radius, orientation: `flip` when normals point inwards,
/// radiance).
[[gnu::always_inline]] inline SphereEmitterSample sample_sphere_emitter(float px, float py, float pz, float ux, float uy,
                                                                       const float *q, int k) {
    constexpr size_t M = SphereTable::Max;
    const float cx = q[SphereTable::Cx * M + k], cy = q[SphereTable::Cy * M + k], cz = q[SphereTable::Cz * M + k];
    const float radius = q[SphereTable::Radius * M + k];
    const bool flip = q[SphereTable::Flip * M + k] > 0.f;
    const float lr = q[SphereTable::Lr * M + k], lg = q[SphereTable::Lg * M + k], lb = q[SphereTable::Lb * M + k];
    SphereEmitterSample r;
    const SphereConeSample cone = sample_sphere_cone(Vec3f(cx, cy, cz), radius, Vec3f(px, py, pz), Vec2f(ux, uy));
    const float dirx = cone.dir.x, diry = cone.dir.y, dirz = cone.dir.z;
    r.lpx = cx + dirx * radius, r.lpy = cy + diry * radius, r.lpz = cz + dirz * radius;
    float snx = select(flip, -dirx, dirx), sny = select(flip, -diry, diry), snz = select(flip, -dirz, dirz);
    r.vx = r.lpx - px, r.vy = r.lpy - py, r.vz = r.lpz - pz;
    float dist2 = r.vx * r.vx + r.vy * r.vy + r.vz * r.vz;
    r.pdf = select(dist2 == 0.f, 0.f, cone.pdf);
    // AreaLight::sample_li.
    r.dist = std::sqrt(dist2);
    float inv_dist = 1.f / r.dist;
    r.ldx = r.vx * inv_dist, r.ldy = r.vy * inv_dist, r.ldz = r.vz * inv_dist;
    bool front_side = !(snx * r.ldx + sny * r.ldy + snz * r.ldz >= 0.f);
    float inv_pdf = 1.f / r.pdf;
    r.wr = lr * inv_pdf, r.wg = lg * inv_pdf, r.wb = lb * inv_pdf;
    r.sampled = (r.pdf > 0.f) & (r.dist > 0.f) & front_side & !((r.wr == 0.f) & (r.wg == 0.f) & (r.wb == 0.f));
    return r;
}

} // namespace mvpt::kernel
