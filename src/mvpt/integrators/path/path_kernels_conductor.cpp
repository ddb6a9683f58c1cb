// Vector kernels of the wavefront path tracer for constant rough conductor vertices
// (RoughConductorInfo: roughconductor, or twosided around one): visible-normal sampling and
// next-event evaluation. Each lane calls the distribution's and the conductor's own lane
// functions (render/microfacet.h, render/bsdfs/roughconductor.h) and mirrors TwoSidedBsdf with
// selects, so the results are bit-identical to PathIntegrator::li's
// (tests/cpp/test_path_kernels.cpp).
#include "path_kernels.h"

#include <cmath>

#include "../../core/math.h"
#include "../../core/simd.h"
#include "../../core/poly_math.h"
#include "../../core/warp.h"
#include "../../render/bsdfs/roughconductor.h"
#include "kernel_helpers.h"

namespace mvpt {

using namespace kernel; // the shared lane helpers (kernel_helpers.h)

namespace {

/// The conductor of lane i (RoughConductorInfo's columns).
[[gnu::always_inline]] inline RoughConductorLocal conductor_at(const float *c, size_t s, size_t i) {
    using namespace cond_col;
    RoughConductorLocal l;
    l.alpha_u = l.alpha_v = c[Alpha * s + i];
    l.eta = Color3f(c[EtaR * s + i], c[EtaG * s + i], c[EtaB * s + i]);
    l.k = Color3f(c[KR * s + i], c[KG * s + i], c[KB * s + i]);
    l.specular = Color3f(c[SpR * s + i], c[SpG * s + i], c[SpB * s + i]);
    return l;
}

/// Whether lane i's distribution is Beckmann's, given which distributions the lanes hold.
template <MicrofacetLanes Lanes>
[[gnu::always_inline]] inline bool lane_is_beckmann(const float *c, size_t s, size_t i) {
    return Lanes == MicrofacetLanes::Beckmann ||
           (Lanes == MicrofacetLanes::Mixed && c[cond_col::Beckmann * s + i] > 0.f);
}

/// One lane of rough_conductor_sample_kernel.
template <MicrofacetLanes Lanes>
[[gnu::always_inline]] inline void conductor_sample_lane(float *c, size_t s, size_t i) {
    using namespace rs_col;
    const bool beckmann = lane_is_beckmann<Lanes>(c, s, i);
    const float wx = c[WiX * s + i], wy = c[WiY * s + i], wz0 = c[WiZ * s + i];
    const bool flipped = (wz0 < 0.f) & (c[TwoSided * s + i] > 0.f); // TwoSidedBsdf mirrors the back side
    const float wz = select(flipped, -wz0, wz0);
    const float a = c[Alpha * s + i];
    // RoughConductor::sample: MicrofacetDistribution::sample and ::pdf (visible normals), then the reflection.
    const Vec3f wi(wx, wy, wz);
    const Vec3f m = microfacet_sample_visible<Lanes>(wi, Vec2f(c[Ux * s + i], c[Uy * s + i]), a, a, beckmann);
    const float pdf_m = microfacet_pdf_visible(wi, m, a, a, beckmann);
    const RoughConductorSample r = rough_conductor_reflect(conductor_at(c, s, i), beckmann, wi, m, pdf_m);
    const float woz = select(flipped, -r.wo.z, r.wo.z);

    next_ray_and_roulette<Sx, Px, Br, Ox>(c, s, i, r.wo.x, r.wo.y, woz, r.pdf, r.weight.r, r.weight.g, r.weight.b,
                                          r.ok);
}

/// One lane of rough_conductor_nee_kernel.
template <MicrofacetLanes Lanes>
[[gnu::always_inline]] inline void conductor_nee_lane(float *c, size_t s, size_t i, float light_count) {
    using namespace rn_col;
    const bool beckmann = lane_is_beckmann<Lanes>(c, s, i);
    const float wx = c[WiX * s + i], wy = c[WiY * s + i], wz0 = c[WiZ * s + i];
    const bool two = c[TwoSided * s + i] > 0.f;
    const bool flipped = (wz0 < 0.f) & two;
    const bool side_ok = (wz0 > 0.f) | flipped; // TwoSidedBsdf: zero at wi.z == 0
    const float wz = select(flipped, -wz0, wz0);
    // wo = si.to_local(ls.d), mirrored with wi.
    const float ldx = c[Ldx * s + i], ldy = c[Ldy * s + i], ldz = c[Ldz * s + i];
    float wox = ldx * c[Sx * s + i] + ldy * c[Sy * s + i] + ldz * c[Sz * s + i];
    float woy = ldx * c[Tx * s + i] + ldy * c[Ty * s + i] + ldz * c[Tz * s + i];
    float woz = ldx * c[Nx * s + i] + ldy * c[Ny * s + i] + ldz * c[Nz * s + i];
    woz = select(flipped, -woz, woz);
    // RoughConductor::eval and ::pdf.
    Color3f f;
    float pdf;
    rough_conductor_lobe<true, true>(conductor_at(c, s, i), beckmann, Vec3f(wx, wy, wz), Vec3f(wox, woy, woz), f, pdf);
    const bool f_ok = side_ok & !((f.r == 0.f) & (f.g == 0.f) & (f.b == 0.f));
    nee_contribution_and_shadow_ray<Px, Ldx, Wr, Br, Ox>(c, s, i, f.r, f.g, f.b, select(side_ok, pdf, 0.f), f_ok,
                                                         light_count);
}

/// Sphere::sample_solid_angle from outside (a uniform direction in the subtended cone), then
/// AreaLight::sample_li, for lane i of rsn_col columns: writes the emitter sample (direction,
/// point, distance, density, delta) and its weight L/pdf; false if li would skip the sample.
[[gnu::always_inline]] inline bool sphere_emitter_sample(float *c, size_t s, size_t i, const float *q) {
    using namespace rsn_col;
    using namespace rn_col;
    const int k = int(c[Sphere * s + i]);
    const float px = c[Px * s + i], py = c[Py * s + i], pz = c[Pz * s + i];
    const float ux = c[Ux * s + i], uy = c[Uy * s + i];
    const SphereEmitterSample e = sample_sphere_emitter(px, py, pz, ux, uy, q, k);
    c[Ldx * s + i] = e.ldx, c[Ldy * s + i] = e.ldy, c[Ldz * s + i] = e.ldz;
    c[Lpx * s + i] = e.lpx, c[Lpy * s + i] = e.lpy, c[Lpz * s + i] = e.lpz;
    c[LDist * s + i] = e.dist, c[LPdf * s + i] = e.pdf, c[LDelta * s + i] = 0.f;
    c[Wr * s + i] = e.wr, c[Wg * s + i] = e.wg, c[Wb * s + i] = e.wb;
    return e.sampled;
}

/// One lane of rough_conductor_sphere_nee_kernel.
template <MicrofacetLanes Lanes>
[[gnu::always_inline]] inline void conductor_sphere_nee_lane(float *c, size_t s, size_t i, const float *q,
                                                             float light_count) {
    bool sampled = sphere_emitter_sample(c, s, i, q);
    conductor_nee_lane<Lanes>(c, s, i, light_count);
    c[rn_col::Ok * s + i] = select(sampled, c[rn_col::Ok * s + i], 0.f);
}

/// Which distributions the lanes hold.
MicrofacetLanes lanes_of(const float *beckmann, size_t n) {
    size_t count = 0;
    for (size_t i = 0; i < n; ++i) count += beckmann[i] > 0.f;
    return count == 0 ? MicrofacetLanes::GGX : count == n ? MicrofacetLanes::Beckmann : MicrofacetLanes::Mixed;
}

} // namespace

MVPT_MULTI_ISA void rough_conductor_sample_ggx(float *c, size_t s, size_t n) {
#pragma GCC ivdep
    for (size_t i = 0; i < n; ++i) conductor_sample_lane<MicrofacetLanes::GGX>(c, s, i);
}
MVPT_MULTI_ISA void rough_conductor_sample_beckmann(float *c, size_t s, size_t n) {
#pragma GCC ivdep
    for (size_t i = 0; i < n; ++i) conductor_sample_lane<MicrofacetLanes::Beckmann>(c, s, i);
}
MVPT_MULTI_ISA void rough_conductor_sample_mixed(float *c, size_t s, size_t n) {
#pragma GCC ivdep
    for (size_t i = 0; i < n; ++i) conductor_sample_lane<MicrofacetLanes::Mixed>(c, s, i);
}

void rough_conductor_sample_kernel(SoaColumns &c, size_t n) {
    switch (lanes_of(c[rs_col::Beckmann], n)) {
    case MicrofacetLanes::GGX: rough_conductor_sample_ggx(c.data.data(), c.stride, n); break;
    case MicrofacetLanes::Beckmann: rough_conductor_sample_beckmann(c.data.data(), c.stride, n); break;
    default: rough_conductor_sample_mixed(c.data.data(), c.stride, n); break;
    }
}

MVPT_MULTI_ISA void rough_conductor_nee_ggx(float *c, size_t s, size_t n, float light_count) {
#pragma GCC ivdep
    for (size_t i = 0; i < n; ++i) conductor_nee_lane<MicrofacetLanes::GGX>(c, s, i, light_count);
}
MVPT_MULTI_ISA void rough_conductor_nee_beckmann(float *c, size_t s, size_t n, float light_count) {
#pragma GCC ivdep
    for (size_t i = 0; i < n; ++i) conductor_nee_lane<MicrofacetLanes::Beckmann>(c, s, i, light_count);
}
MVPT_MULTI_ISA void rough_conductor_nee_mixed(float *c, size_t s, size_t n, float light_count) {
#pragma GCC ivdep
    for (size_t i = 0; i < n; ++i) conductor_nee_lane<MicrofacetLanes::Mixed>(c, s, i, light_count);
}

void rough_conductor_nee_kernel(SoaColumns &c, size_t n, float light_count) {
    switch (lanes_of(c[rn_col::Beckmann], n)) {
    case MicrofacetLanes::GGX: rough_conductor_nee_ggx(c.data.data(), c.stride, n, light_count); break;
    case MicrofacetLanes::Beckmann: rough_conductor_nee_beckmann(c.data.data(), c.stride, n, light_count); break;
    default: rough_conductor_nee_mixed(c.data.data(), c.stride, n, light_count); break;
    }
}

MVPT_MULTI_ISA void rough_conductor_sphere_nee_ggx(float *c, size_t s, size_t n, const float *q, float light_count) {
#pragma GCC ivdep
    for (size_t i = 0; i < n; ++i) conductor_sphere_nee_lane<MicrofacetLanes::GGX>(c, s, i, q, light_count);
}
MVPT_MULTI_ISA void rough_conductor_sphere_nee_beckmann(float *c, size_t s, size_t n, const float *q,
                                                        float light_count) {
#pragma GCC ivdep
    for (size_t i = 0; i < n; ++i) conductor_sphere_nee_lane<MicrofacetLanes::Beckmann>(c, s, i, q, light_count);
}
MVPT_MULTI_ISA void rough_conductor_sphere_nee_mixed(float *c, size_t s, size_t n, const float *q, float light_count) {
#pragma GCC ivdep
    for (size_t i = 0; i < n; ++i) conductor_sphere_nee_lane<MicrofacetLanes::Mixed>(c, s, i, q, light_count);
}

void rough_conductor_sphere_nee_kernel(SoaColumns &c, size_t n, const SphereTable &spheres, float light_count) {
    switch (lanes_of(c[rn_col::Beckmann], n)) {
    case MicrofacetLanes::GGX:
        rough_conductor_sphere_nee_ggx(c.data.data(), c.stride, n, spheres.v, light_count);
        break;
    case MicrofacetLanes::Beckmann:
        rough_conductor_sphere_nee_beckmann(c.data.data(), c.stride, n, spheres.v, light_count);
        break;
    default: rough_conductor_sphere_nee_mixed(c.data.data(), c.stride, n, spheres.v, light_count); break;
    }
}

} // namespace mvpt
