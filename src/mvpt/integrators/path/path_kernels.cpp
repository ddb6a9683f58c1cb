#include "path_kernels.h"

#include <cmath>

#include "../../core/math.h"
#include "../../core/simd.h"
#include "../../core/warp.h"
#include "../../render/interaction.h"
#include "kernel_helpers.h"

namespace mvpt {

using namespace kernel; // the shared lane helpers (kernel_helpers.h)

MVPT_MULTI_ISA void lambert_sample_kernel_impl(float *c, size_t s, size_t n) {
    using namespace ls_col;
#pragma GCC ivdep
    for (size_t i = 0; i < n; ++i) {
        const float wiz = c[WiZ * s + i];
        const bool front = wiz > 0.f, back = (wiz < 0.f) & (c[TwoSided * s + i] > 0.f);
        // DiffuseBsdf::sample (warp.h's branch-free cosine-weighted hemisphere).
        const Vec3f wo = warp::square_to_cosine_hemisphere(Vec2f(c[Ux * s + i], c[Uy * s + i]));
        const float wox = wo.x, woy = wo.y;
        float woz = wo.z;
        const float pdf = warp::square_to_cosine_hemisphere_pdf(wo);
        woz = select(back, -woz, woz); // twosided mirrors the back side's sample
        const float rr = c[Rr * s + i], rg = c[Rg * s + i], rb = c[Rb * s + i];
        bool weight_ok = (front | back) & !(pdf <= 0.f) & !((rr == 0.f) & (rg == 0.f) & (rb == 0.f));

        next_ray_and_roulette<Sx, Px, Br, Ox>(c, s, i, wox, woy, woz, pdf, rr, rg, rb, weight_ok);
    }
}

void lambert_sample_kernel(SoaColumns &c, size_t n) { lambert_sample_kernel_impl(c.data.data(), c.stride, n); }

MVPT_MULTI_ISA void lambert_nee_kernel_impl(float *c, size_t s, size_t n, float light_count) {
    using namespace ln_col;
#pragma GCC ivdep
    for (size_t i = 0; i < n; ++i) {
        const float wiz = c[WiZ * s + i];
        const bool front = wiz > 0.f, back = (wiz < 0.f) & (c[TwoSided * s + i] > 0.f);
        const float ldx = c[Ldx * s + i], ldy = c[Ldy * s + i], ldz = c[Ldz * s + i];
        // cos(wo) in the local frame (twosided mirrors the back side).
        float woz = ldx * c[Nx * s + i] + ldy * c[Ny * s + i] + ldz * c[Nz * s + i];
        float cos_o = select(back, -woz, woz);
        bool f_ok = (front | back) & !(cos_o <= 0.f);
        float scale = InvPi * cos_o;
        float fr = c[Rr * s + i] * scale, fg = c[Rg * s + i] * scale, fb = c[Rb * s + i] * scale;
        bool ok = f_ok & !((fr == 0.f) & (fg == 0.f) & (fb == 0.f));
        float pdf = warp::cosine_hemisphere_pdf(cos_o);
        nee_contribution_and_shadow_ray<Px, Ldx, Wr, Br, Ox>(c, s, i, fr, fg, fb, pdf, ok, light_count);
    }
}

void lambert_nee_kernel(SoaColumns &c, size_t n, float light_count) {
    lambert_nee_kernel_impl(c.data.data(), c.stride, n, light_count);
}

namespace {

/// The part of next-event estimation after sample_li, for lane i of lq_col columns: BSDF value
/// and density, MIS, contribution (as lambert_nee_kernel) and the shadow ray spawn_ray_to(lp).
/// v = lp - p; ld and lpdf: the emitter sample's direction and density; w: its weight L/pdf.
[[gnu::always_inline]] inline void lambert_nee_tail(float *c, size_t s, size_t i, float px, float py, float pz,
                                                    float lpx, float lpy, float lpz, float vx, float vy, float vz,
                                                    float ldx, float ldy, float ldz, float lpdf, float wr, float wg,
                                                    float wb, bool sampled, float light_count) {
    using namespace lq_col;
    const float wiz = c[WiZ * s + i];
    const bool front = wiz > 0.f, back = (wiz < 0.f) & (c[TwoSided * s + i] > 0.f);
    float woz = ldx * c[Nx * s + i] + ldy * c[Ny * s + i] + ldz * c[Nz * s + i];
    float cos_o = select(back, -woz, woz);
    bool f_ok = (front | back) & !(cos_o <= 0.f);
    float scale = InvPi * cos_o;
    float fr = c[Rr * s + i] * scale, fg = c[Rg * s + i] * scale, fb = c[Rb * s + i] * scale;
    bool ok = sampled & f_ok & !((fr == 0.f) & (fg == 0.f) & (fb == 0.f));
    float pdf = warp::cosine_hemisphere_pdf(cos_o);
    float w = mis_power(lpdf / light_count, pdf);
    c[Cr * s + i] = ((c[Br * s + i] * fr) * (wr * light_count)) * w;
    c[Cg * s + i] = ((c[Bg * s + i] * fg) * (wg * light_count)) * w;
    c[Cb * s + i] = ((c[Bb * s + i] * fb) * (wb * light_count)) * w;
    c[Ok * s + i] = select(ok, 1.f, 0.f);

    const float gx = c[Gx * s + i], gy = c[Gy * s + i], gz = c[Gz * s + i];
    float off = offset_along(px, py, pz, gx, gy, gz, vx, vy, vz);
    float ox = px + gx * off, oy = py + gy * off, oz = pz + gz * off;
    float tx = lpx - ox, ty = lpy - oy, tz = lpz - oz;
    float tdist = std::sqrt(tx * tx + ty * ty + tz * tz);
    float inv = 1.f / tdist;
    c[Ox * s + i] = ox;
    c[Oy * s + i] = oy;
    c[Oz * s + i] = oz;
    c[Dx * s + i] = tx * inv;
    c[Dy * s + i] = ty * inv;
    c[Dz * s + i] = tz * inv;
    c[TMax * s + i] = tdist * (1.f - ShadowEpsilon);
}

} // namespace

/// One lane of lambert_quad_nee_kernel: quad `k` of table `q`.
__attribute__((always_inline)) inline void lambert_quad_nee_lane(float *c, size_t s, size_t i, const float *q, int k,
                                                                 float light_count) {
    using namespace lq_col;
    constexpr size_t M = QuadTable::Max;
    const float px = c[Px * s + i], py = c[Py * s + i], pz = c[Pz * s + i];
    // TriangleMesh::sample_point (parallelogram), area_to_solid_angle, AreaLight::sample_li.
    const float ux = c[Ux * s + i], uy = c[Uy * s + i];
    float lpx = (q[QuadTable::Ox * M + k] + q[QuadTable::E1x * M + k] * ux) + q[QuadTable::E2x * M + k] * uy;
    float lpy = (q[QuadTable::Oy * M + k] + q[QuadTable::E1y * M + k] * ux) + q[QuadTable::E2y * M + k] * uy;
    float lpz = (q[QuadTable::Oz * M + k] + q[QuadTable::E1z * M + k] * ux) + q[QuadTable::E2z * M + k] * uy;
    const float qnx = q[QuadTable::Nx * M + k], qny = q[QuadTable::Ny * M + k], qnz = q[QuadTable::Nz * M + k];
    float vx = lpx - px, vy = lpy - py, vz = lpz - pz;
    float dist2 = vx * vx + vy * vy + vz * vz;
    float dist = std::sqrt(dist2);
    float cos_t = std::abs(qnx * vx + qny * vy + qnz * vz) / dist;
    float lpdf = select(cos_t > 0.f, q[QuadTable::InvArea * M + k] * dist2 / cos_t, 0.f);
    float inv_dist = 1.f / dist;
    const float ldx = vx * inv_dist, ldy = vy * inv_dist, ldz = vz * inv_dist;
    bool front_side = !(qnx * ldx + qny * ldy + qnz * ldz >= 0.f); // one-sided emitter
    float inv_pdf = 1.f / lpdf;
    float wr = q[QuadTable::Lr * M + k] * inv_pdf, wg = q[QuadTable::Lg * M + k] * inv_pdf,
          wb = q[QuadTable::Lb * M + k] * inv_pdf;
    bool sampled = (lpdf > 0.f) & (dist > 0.f) & front_side & !((wr == 0.f) & (wg == 0.f) & (wb == 0.f));
    lambert_nee_tail(c, s, i, px, py, pz, lpx, lpy, lpz, vx, vy, vz, ldx, ldy, ldz, lpdf, wr, wg, wb, sampled,
                     light_count);
}

MVPT_MULTI_ISA void lambert_quad_nee_kernel_impl(float *c, size_t s, size_t n, const float *q, float light_count) {
#pragma GCC ivdep
    for (size_t i = 0; i < n; ++i) lambert_quad_nee_lane(c, s, i, q, int(c[lq_col::Quad * s + i]), light_count);
}

/// All lanes on the quad that `q` points at (its row offset applied): the table's entries are
/// loop invariants, broadcast once, instead of being gathered lane by lane.
MVPT_MULTI_ISA void lambert_one_quad_nee_kernel_impl(float *c, size_t s, size_t n, const float *q, float light_count) {
#pragma GCC ivdep
    for (size_t i = 0; i < n; ++i) lambert_quad_nee_lane(c, s, i, q, 0, light_count);
}

void lambert_quad_nee_kernel(SoaColumns &c, size_t n, const QuadTable &quads, float light_count, int one_quad) {
    if (one_quad >= 0)
        lambert_one_quad_nee_kernel_impl(c.data.data(), c.stride, n, quads.v + one_quad, light_count);
    else
        lambert_quad_nee_kernel_impl(c.data.data(), c.stride, n, quads.v, light_count);
}

MVPT_MULTI_ISA void lambert_sphere_nee_kernel_impl(float *c, size_t s, size_t n, const float *q, float light_count) {
    using namespace lq_col;
#pragma GCC ivdep
    for (size_t i = 0; i < n; ++i) {
        const int k = int(c[Quad * s + i]);
        const float px = c[Px * s + i], py = c[Py * s + i], pz = c[Pz * s + i];
        const float ux = c[Ux * s + i], uy = c[Uy * s + i];
        // Sphere::sample_solid_angle from outside: a uniform direction in the subtended cone.
        const SphereEmitterSample e = sample_sphere_emitter(px, py, pz, ux, uy, q, k);
        lambert_nee_tail(c, s, i, px, py, pz, e.lpx, e.lpy, e.lpz, e.vx, e.vy, e.vz, e.ldx, e.ldy, e.ldz, e.pdf, e.wr,
                         e.wg, e.wb, e.sampled, light_count);
    }
}

void lambert_sphere_nee_kernel(SoaColumns &c, size_t n, const SphereTable &spheres, float light_count) {
    lambert_sphere_nee_kernel_impl(c.data.data(), c.stride, n, spheres.v, light_count);
}

} // namespace mvpt
