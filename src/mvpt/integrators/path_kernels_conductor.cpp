// Vector kernels of the wavefront path tracer for constant rough conductor vertices
// (RoughConductorInfo: roughconductor, or twosided around one): visible-normal sampling and
// next-event evaluation. Each lane performs the scalar operations of RoughConductor,
// MicrofacetDistribution (microfacet.cpp) and TwoSidedBsdf in their order, with selects for
// branches and the shared polynomial exp/log/erf/erfinv (core/poly_math.h), so the results are
// bit-identical to PathIntegrator::li's (tests/cpp/test_path_kernels.cpp).
#include "path_kernels.h"

#include <cmath>

#include "../core/math.h"
#include "../core/multi_isa.h"
#include "../core/poly_math.h"
#include "../core/warp.h"
#include "../render/fresnel.h"
#include "kernel_helpers.h"

namespace mvpt {

using namespace kernel; // the shared lane helpers (kernel_helpers.h)

namespace {

/// MicrofacetDistribution::eval(m) for an isotropic roughness a.
[[gnu::always_inline]] inline float distr_eval(float mx, float my, float mz, float a, bool beckmann) {
    float cos2 = mz * mz;
    float a2 = a * a;
    float e = (mx * mx / a2 + my * my / a2) / cos2;
    float rb = exp_poly(-e) / (Pi * a * a * cos2 * cos2);
    float rg = 1.f / (Pi * a * a * cos2 * cos2 * (1.f + e) * (1.f + e));
    float r = select(beckmann, rb, rg);
    return select(!(cos2 <= 0.f) & (r * mz > 1e-20f), r, 0.f);
}

/// MicrofacetDistribution::smith_g1(v, m) for an isotropic roughness a.
[[gnu::always_inline]] inline float distr_g1(float vx, float vy, float vz, float mx, float my, float mz, float a,
                                             bool beckmann) {
    float xy2 = vx * vx + vy * vy;
    float tan2 = xy2 / (vz * vz);
    float alpha2 = select(xy2 <= 0.f, a * a, (vx * vx * a * a + vy * vy * a * a) / xy2);
    float t = 1.f / std::sqrt(alpha2 * tan2);
    float gb = select(t >= 1.6f, 1.f, (3.535f * t + 2.181f * t * t) / (1.f + 2.276f * t + 2.577f * t * t));
    float gg = 2.f / (1.f + std::sqrt(1.f + alpha2 * tan2));
    float g = select(beckmann, gb, gg);
    g = select(xy2 == 0.f, 1.f, g);
    return select((vx * mx + vy * my + vz * mz) * vz <= 0.f, 0.f, g);
}

/// MicrofacetDistribution::sample_visible_11 (both distributions, one selected).
[[gnu::always_inline]] inline void visible_slopes(float cos_i, float ux, float uy, bool beckmann, bool do_beckmann,
                                                  bool do_ggx, float &sx, float &sy) {
    float gx = 0.f, gy = 0.f, bx = 0.f, by = 0.f;
    if (do_ggx) {
        // Heitz 2018: a concentric disk sample (warp.h) projected onto the visible hemisphere.
        float x = 2.f * ux - 1.f, y = 2.f * uy - 1.f;
        bool centre = (x == 0.f) & (y == 0.f);
        bool x_major = std::abs(x) > std::abs(y);
        float r = select(x_major, x, y);
        float a = (Pi / 4.f) * select(x_major, y / x, -(x / y));
        float z = a * a;
        float sn = ((-1.9515295891e-4f * z + 8.3321608736e-3f) * z - 1.6666654611e-1f) * z * a + a;
        float cs = ((2.443315711809948e-5f * z - 1.388731625493765e-3f) * z + 4.166664568298827e-2f) * z * z -
                   0.5f * z + 1.f;
        float px = select(centre, 0.f, r * select(x_major, cs, -sn));
        float py = select(centre, 0.f, r * select(x_major, sn, cs));
        float s = 0.5f * (1.f + cos_i);
        float root = safe_sqrt(1.f - px * px);
        py = root + s * (py - root);
        float pz = safe_sqrt(1.f - px * px - py * py);
        float sin_i = safe_sqrt(1.f - cos_i * cos_i);
        float inv_norm = 1.f / (sin_i * py + cos_i * pz);
        gx = (cos_i * py - sin_i * pz) * inv_norm;
        gy = px * inv_norm;
    }
    if (do_beckmann) {
        // Jakob 2014: Newton iteration on the visible x-slopes' CDF in the erf domain.
        constexpr float InvSqrtPi = 0.56418958354775628695f;
        float tan_i = safe_sqrt(1.f - cos_i * cos_i) / cos_i;
        float cot_i = 1.f / tan_i;
        float max_val = erf_poly(cot_i);
        float u1 = select(ux < 1e-6f, 1e-6f, select(1.f - 1e-6f < ux, 1.f - 1e-6f, ux));
        float u2 = select(uy < 1e-6f, 1e-6f, select(1.f - 1e-6f < uy, 1.f - 1e-6f, uy));
        float x = max_val - (max_val + 1.f) * erf_poly(std::sqrt(-log_poly(u1)));
        float target = u1 * (1.f + max_val + InvSqrtPi * tan_i * exp_poly(-cot_i * cot_i));
#pragma GCC unroll 3
        for (int it = 0; it < 3; ++it) {
            float slope = erfinv_poly(x);
            float value = 1.f + x + InvSqrtPi * tan_i * exp_poly(-slope * slope) - target;
            float derivative = 1.f - slope * tan_i;
            x -= value / derivative;
        }
        bx = erfinv_poly(x);
        by = erfinv_poly(2.f * u2 - 1.f);
    }
    sx = select(beckmann, bx, gx);
    sy = select(beckmann, by, gy);
}

/// One lane of rough_conductor_sample_kernel; `Mode`: 0 all GGX, 1 all Beckmann, 2 mixed.
template <int Mode> [[gnu::always_inline]] inline void conductor_sample_lane(float *c, size_t s, size_t i) {
    using namespace rs_col;
    const bool beckmann = Mode == 1 || (Mode == 2 && c[Beckmann * s + i] > 0.f);
    const float wx = c[WiX * s + i], wy = c[WiY * s + i], wz0 = c[WiZ * s + i];
    const bool flipped = (wz0 < 0.f) & (c[TwoSided * s + i] > 0.f); // TwoSidedBsdf mirrors the back side
    const float wz = select(flipped, -wz0, wz0);
    const float a = c[Alpha * s + i];
    // MicrofacetDistribution::sample: stretch, sample the alpha = 1 slopes, rotate, unstretch.
    float qx = a * wx, qy = a * wy, qz = wz;
    float inv_len = 1.f / std::sqrt(qx * qx + qy * qy + qz * qz);
    float wpx = qx * inv_len, wpy = qy * inv_len, wpz = qz * inv_len;
    float sin_t = std::sqrt(max_of(0.f, 1.f - wpz * wpz));
    float cos_phi = select(sin_t > 0.f, wpx / sin_t, 1.f), sin_phi = select(sin_t > 0.f, wpy / sin_t, 0.f);
    float s11x, s11y;
    visible_slopes(wpz, c[Ux * s + i], c[Uy * s + i], beckmann, Mode != 0, Mode != 1, s11x, s11y);
    float slx = cos_phi * s11x - sin_phi * s11y, sly = sin_phi * s11x + cos_phi * s11y;
    slx *= a;
    sly *= a;
    float nx = -slx, ny = -sly;
    float inv_m = 1.f / std::sqrt(nx * nx + ny * ny + 1.f * 1.f);
    float mx = nx * inv_m, my = ny * inv_m, mz = 1.f * inv_m;
    bool finite = (std::abs(mx) < Infinity) & (std::abs(my) < Infinity) & (std::abs(mz) < Infinity);
    mx = select(finite, mx, 0.f);
    my = select(finite, my, 0.f);
    mz = select(finite, mz, 1.f);
    // MicrofacetDistribution::pdf(wi, m).
    float d = distr_eval(mx, my, mz, a, beckmann);
    float dot_im = wx * mx + wy * my + wz * mz;
    float pdf_m = distr_g1(wx, wy, wz, mx, my, mz, a, beckmann) * std::abs(dot_im) * d / std::abs(wz);
    pdf_m = select(wz == 0.f, 0.f, pdf_m);
    // RoughConductor::sample: reflect, density, weight G1(wo) F.
    float two_dot = 2.f * dot_im;
    float wox = two_dot * mx - wx, woy = two_dot * my - wy, woz = two_dot * mz - wz;
    float pdf = pdf_m / (4.f * (wox * mx + woy * my + woz * mz));
    float g1 = distr_g1(wox, woy, woz, mx, my, mz, a, beckmann);
    float wr = fresnel_conductor(dot_im, c[EtaR * s + i], c[KR * s + i]) * g1 * c[SpR * s + i];
    float wg = fresnel_conductor(dot_im, c[EtaG * s + i], c[KG * s + i]) * g1 * c[SpG * s + i];
    float wb = fresnel_conductor(dot_im, c[EtaB * s + i], c[KB * s + i]) * g1 * c[SpB * s + i];
    bool sampled = (wz > 0.f) & !(pdf_m == 0.f) & !(woz <= 0.f);
    bool weight_ok = sampled & !((wr == 0.f) & (wg == 0.f) & (wb == 0.f));
    woz = select(flipped, -woz, woz);

    next_ray_and_roulette<Sx, Px, Br, Ox>(c, s, i, wox, woy, woz, pdf, wr, wg, wb, weight_ok);
}

/// One lane of rough_conductor_nee_kernel.
template <int Mode> [[gnu::always_inline]] inline void conductor_nee_lane(float *c, size_t s, size_t i, float light_count) {
    using namespace rn_col;
    const bool beckmann = Mode == 1 || (Mode == 2 && c[Beckmann * s + i] > 0.f);
    const float wx = c[WiX * s + i], wy = c[WiY * s + i], wz0 = c[WiZ * s + i];
    const bool two = c[TwoSided * s + i] > 0.f;
    const bool flipped = (wz0 < 0.f) & two;
    const bool side_ok = (wz0 > 0.f) | flipped; // TwoSidedBsdf: zero at wi.z == 0
    const float wz = select(flipped, -wz0, wz0);
    const float a = c[Alpha * s + i];
    // wo = si.to_local(ls.d), mirrored with wi.
    const float ldx = c[Ldx * s + i], ldy = c[Ldy * s + i], ldz = c[Ldz * s + i];
    float wox = ldx * c[Sx * s + i] + ldy * c[Sy * s + i] + ldz * c[Sz * s + i];
    float woy = ldx * c[Tx * s + i] + ldy * c[Ty * s + i] + ldz * c[Tz * s + i];
    float woz = ldx * c[Nx * s + i] + ldy * c[Ny * s + i] + ldz * c[Nz * s + i];
    woz = select(flipped, -woz, woz);
    // RoughConductor::eval and ::pdf at the half vector.
    bool cos_ok = side_ok & !(wz <= 0.f) & !(woz <= 0.f);
    float hx = wx + wox, hy = wy + woy, hz = wz + woz;
    float inv_h = 1.f / std::sqrt(hx * hx + hy * hy + hz * hz);
    hx *= inv_h, hy *= inv_h, hz *= inv_h;
    float d = distr_eval(hx, hy, hz, a, beckmann);
    float g1_i = distr_g1(wx, wy, wz, hx, hy, hz, a, beckmann);
    float value = d * (g1_i * distr_g1(wox, woy, woz, hx, hy, hz, a, beckmann)) / (4.f * wz);
    float dot_ih = wx * hx + wy * hy + wz * hz;
    float fr = fresnel_conductor(dot_ih, c[EtaR * s + i], c[KR * s + i]) * value * c[SpR * s + i];
    float fg = fresnel_conductor(dot_ih, c[EtaG * s + i], c[KG * s + i]) * value * c[SpG * s + i];
    float fb = fresnel_conductor(dot_ih, c[EtaB * s + i], c[KB * s + i]) * value * c[SpB * s + i];
    bool f_ok = cos_ok & !(d == 0.f) & !((fr == 0.f) & (fg == 0.f) & (fb == 0.f));
    bool pdf_ok = cos_ok & !(dot_ih <= 0.f) & !(wox * hx + woy * hy + woz * hz <= 0.f);
    float pdf = select(pdf_ok, d * g1_i / (4.f * wz), 0.f);
    nee_contribution_and_shadow_ray<Px, Ldx, Wr, Br, Ox>(c, s, i, fr, fg, fb, pdf, f_ok, light_count);
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
template <int Mode>
[[gnu::always_inline]] inline void conductor_sphere_nee_lane(float *c, size_t s, size_t i, const float *q,
                                                             float light_count) {
    bool sampled = sphere_emitter_sample(c, s, i, q);
    conductor_nee_lane<Mode>(c, s, i, light_count);
    c[rn_col::Ok * s + i] = select(sampled, c[rn_col::Ok * s + i], 0.f);
}

/// 0 if every lane is GGX, 1 if every lane is Beckmann, else 2.
int distribution_mode(const float *beckmann, size_t n) {
    size_t count = 0;
    for (size_t i = 0; i < n; ++i) count += beckmann[i] > 0.f;
    return count == 0 ? 0 : count == n ? 1 : 2;
}

} // namespace

MVPT_MULTI_ISA void rough_conductor_sample_ggx(float *c, size_t s, size_t n) {
#pragma GCC ivdep
    for (size_t i = 0; i < n; ++i) conductor_sample_lane<0>(c, s, i);
}
MVPT_MULTI_ISA void rough_conductor_sample_beckmann(float *c, size_t s, size_t n) {
#pragma GCC ivdep
    for (size_t i = 0; i < n; ++i) conductor_sample_lane<1>(c, s, i);
}
MVPT_MULTI_ISA void rough_conductor_sample_mixed(float *c, size_t s, size_t n) {
#pragma GCC ivdep
    for (size_t i = 0; i < n; ++i) conductor_sample_lane<2>(c, s, i);
}

void rough_conductor_sample_kernel(SoaColumns &c, size_t n) {
    switch (distribution_mode(c[rs_col::Beckmann], n)) {
    case 0: rough_conductor_sample_ggx(c.data.data(), c.stride, n); break;
    case 1: rough_conductor_sample_beckmann(c.data.data(), c.stride, n); break;
    default: rough_conductor_sample_mixed(c.data.data(), c.stride, n); break;
    }
}

MVPT_MULTI_ISA void rough_conductor_nee_ggx(float *c, size_t s, size_t n, float light_count) {
#pragma GCC ivdep
    for (size_t i = 0; i < n; ++i) conductor_nee_lane<0>(c, s, i, light_count);
}
MVPT_MULTI_ISA void rough_conductor_nee_beckmann(float *c, size_t s, size_t n, float light_count) {
#pragma GCC ivdep
    for (size_t i = 0; i < n; ++i) conductor_nee_lane<1>(c, s, i, light_count);
}
MVPT_MULTI_ISA void rough_conductor_nee_mixed(float *c, size_t s, size_t n, float light_count) {
#pragma GCC ivdep
    for (size_t i = 0; i < n; ++i) conductor_nee_lane<2>(c, s, i, light_count);
}

void rough_conductor_nee_kernel(SoaColumns &c, size_t n, float light_count) {
    switch (distribution_mode(c[rn_col::Beckmann], n)) {
    case 0: rough_conductor_nee_ggx(c.data.data(), c.stride, n, light_count); break;
    case 1: rough_conductor_nee_beckmann(c.data.data(), c.stride, n, light_count); break;
    default: rough_conductor_nee_mixed(c.data.data(), c.stride, n, light_count); break;
    }
}

MVPT_MULTI_ISA void rough_conductor_sphere_nee_ggx(float *c, size_t s, size_t n, const float *q, float light_count) {
#pragma GCC ivdep
    for (size_t i = 0; i < n; ++i) conductor_sphere_nee_lane<0>(c, s, i, q, light_count);
}
MVPT_MULTI_ISA void rough_conductor_sphere_nee_beckmann(float *c, size_t s, size_t n, const float *q,
                                                        float light_count) {
#pragma GCC ivdep
    for (size_t i = 0; i < n; ++i) conductor_sphere_nee_lane<1>(c, s, i, q, light_count);
}
MVPT_MULTI_ISA void rough_conductor_sphere_nee_mixed(float *c, size_t s, size_t n, const float *q, float light_count) {
#pragma GCC ivdep
    for (size_t i = 0; i < n; ++i) conductor_sphere_nee_lane<2>(c, s, i, q, light_count);
}

void rough_conductor_sphere_nee_kernel(SoaColumns &c, size_t n, const SphereTable &spheres, float light_count) {
    switch (distribution_mode(c[rn_col::Beckmann], n)) {
    case 0: rough_conductor_sphere_nee_ggx(c.data.data(), c.stride, n, spheres.v, light_count); break;
    case 1: rough_conductor_sphere_nee_beckmann(c.data.data(), c.stride, n, spheres.v, light_count); break;
    default: rough_conductor_sphere_nee_mixed(c.data.data(), c.stride, n, spheres.v, light_count); break;
    }
}

} // namespace mvpt
