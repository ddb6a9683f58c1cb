// Microfacet distributions (GGX / Beckmann, anisotropic) with Smith masking
// and visible-normal sampling [Heitz and d'Eon 2014; Heitz 2018 for GGX;
// Jakob 2014 for Beckmann], following Mitsuba 3's MicrofacetDistribution.
#pragma once

#include "../core/math.h"
#include "../core/poly_math.h"
#include "../core/warp.h"

#include <cctype>
#include <string>
#include <type_traits>

namespace mvpt {

enum class MicrofacetType { Beckmann, GGX };

// One lane of the distribution, written without branches (selects instead) so that loops
// over paths or over views vectorise. These are the definitions: MicrofacetDistribution, the
// BSDFs' loops over views and the wavefront's kernels all call them.

/// D(m) for roughness (ax, ay): GGX [Walter et al. 2007, eq. 33] or Beckmann, anisotropic;
/// values below 1e-20 (times cos theta_m) are dropped as by Mitsuba.
[[gnu::always_inline]] inline float microfacet_d(Vec3f m, float ax, float ay, bool beckmann) {
    const float cos2 = m.z * m.z;
    // tan^2(theta) (cos^2 phi / ax^2 + sin^2 phi / ay^2), written with m.x, m.y.
    const float e = (m.x * m.x / (ax * ax) + m.y * m.y / (ay * ay)) / cos2;
    const float rb = exp_poly(-e) / (Pi * ax * ay * cos2 * cos2);
    const float rg = 1.f / (Pi * ax * ay * cos2 * cos2 * (1.f + e) * (1.f + e));
    const float r = select(beckmann, rb, rg);
    return select(!(cos2 <= 0.f) & (r * m.z > 1e-20f), r, 0.f);
}

/// Smith's G1(v, m): exact for GGX, Walter et al.'s rational fit for Beckmann; zero where v
/// sees the back of m.
[[gnu::always_inline]] inline float microfacet_g1(Vec3f v, Vec3f m, float ax, float ay, bool beckmann) {
    const float xy2 = v.x * v.x + v.y * v.y;
    const float tan2 = xy2 / (v.z * v.z);
    // The roughness projected on v's azimuth, squared.
    const float alpha2 = select(xy2 <= 0.f, ax * ax, (v.x * v.x * ax * ax + v.y * v.y * ay * ay) / xy2);
    const float a = 1.f / std::sqrt(alpha2 * tan2);
    const float gb = select(a >= 1.6f, 1.f, (3.535f * a + 2.181f * a * a) / (1.f + 2.276f * a + 2.577f * a * a));
    const float gg = 2.f / (1.f + std::sqrt(1.f + alpha2 * tan2));
    const float g = select(xy2 == 0.f, 1.f, select(beckmann, gb, gg));
    return select(dot(v, m) * v.z <= 0.f, 0.f, g);
}

/// Density of visible-normal sampling producing m: G1(wi, m) |wi.m| D(m) / |cos theta_i|.
[[gnu::always_inline]] inline float microfacet_pdf_visible(Vec3f wi, Vec3f m, float ax, float ay, bool beckmann) {
    const float p = microfacet_g1(wi, m, ax, ay, beckmann) * std::abs(dot(wi, m)) * microfacet_d(m, ax, ay, beckmann) /
                    std::abs(wi.z);
    return select(wi.z == 0.f, 0.f, p);
}

/// Visible slopes of the alpha = 1 GGX distribution seen at incident cosine cos_i: a disk
/// sample projected onto the visible hemisphere [Heitz 2018, "A Simpler and Exact Sampling
/// Routine for the GGX Distribution of Visible Normals"], in slope space.
[[gnu::always_inline]] inline Vec2f ggx_visible_slopes(float cos_i, Vec2f u) {
    Vec2f p = warp::square_to_uniform_disk_concentric(u);
    const float s = 0.5f * (1.f + cos_i);
    p.y = lerp(s, safe_sqrt(1.f - p.x * p.x), p.y);
    const float z = safe_sqrt(1.f - p.x * p.x - p.y * p.y);
    const float sin_i = safe_sqrt(1.f - cos_i * cos_i);
    const float inv_norm = 1.f / (sin_i * p.y + cos_i * z);
    return {(cos_i * p.y - sin_i * z) * inv_norm, p.x * inv_norm};
}

/// Visible slopes of the alpha = 1 Beckmann distribution: the CDF of visible x-slopes inverted
/// in the erf() domain from the analytic grazing solution by three Newton steps [Jakob 2014,
/// "An Improved Visible Normal Sampling Routine for the Beckmann Distribution"]; the y-slope
/// is an independent Gaussian.
[[gnu::always_inline]] inline Vec2f beckmann_visible_slopes(float cos_i, Vec2f u) {
    constexpr float InvSqrtPi = 0.56418958354775628695f;
    const float tan_i = safe_sqrt(1.f - cos_i * cos_i) / cos_i;
    const float cot_i = 1.f / tan_i;
    const float max_val = erf_poly(cot_i);
    const float u1 = select(u.x < 1e-6f, 1e-6f, select(1.f - 1e-6f < u.x, 1.f - 1e-6f, u.x));
    const float u2 = select(u.y < 1e-6f, 1e-6f, select(1.f - 1e-6f < u.y, 1.f - 1e-6f, u.y));
    float x = max_val - (max_val + 1.f) * erf_poly(std::sqrt(-log_poly(u1)));
    const float target = u1 * (1.f + max_val + InvSqrtPi * tan_i * exp_poly(-cot_i * cot_i));
#pragma GCC unroll 3
    for (int it = 0; it < 3; ++it) {
        const float slope = erfinv_poly(x);
        const float value = 1.f + x + InvSqrtPi * tan_i * exp_poly(-slope * slope) - target;
        const float derivative = 1.f - slope * tan_i;
        x -= value / derivative;
    }
    return {erfinv_poly(x), erfinv_poly(2.f * u2 - 1.f)};
}

/// Calls `lobe(beckmann)` with the distribution as a compile-time constant (std::true_type or
/// std::false_type), so that code written for per-lane distributions computes only one of them.
template <typename Lobe> [[gnu::always_inline]] inline void with_distribution(bool beckmann, Lobe &&lobe) {
    if (beckmann) lobe(std::true_type{});
    else lobe(std::false_type{});
}

/// Which distributions a loop's lanes hold: the slopes of the others are not computed.
enum class MicrofacetLanes { GGX, Beckmann, Mixed };

/// A visible normal for wi (upper hemisphere): stretch wi to the alpha = 1 configuration,
/// sample its slopes, rotate and unstretch them [Heitz and d'Eon 2014]; +z if that fails.
template <MicrofacetLanes Lanes>
[[gnu::always_inline]] inline Vec3f microfacet_sample_visible(Vec3f wi, Vec2f u, float ax, float ay, bool beckmann) {
    const Vec3f wi_p = normalize(Vec3f(ax * wi.x, ay * wi.y, wi.z));
    const float sin2 = 1.f - wi_p.z * wi_p.z, sin_t = std::sqrt(select(0.f < sin2, sin2, 0.f));
    const float cos_phi = select(sin_t > 0.f, wi_p.x / sin_t, 1.f), sin_phi = select(sin_t > 0.f, wi_p.y / sin_t, 0.f);
    Vec2f sg, sb;
    if constexpr (Lanes != MicrofacetLanes::Beckmann) sg = ggx_visible_slopes(wi_p.z, u);
    if constexpr (Lanes != MicrofacetLanes::GGX) sb = beckmann_visible_slopes(wi_p.z, u);
    const Vec2f s11(select(beckmann, sb.x, sg.x), select(beckmann, sb.y, sg.y));
    const float sx = (cos_phi * s11.x - sin_phi * s11.y) * ax, sy = (sin_phi * s11.x + cos_phi * s11.y) * ay;
    const Vec3f m = normalize(Vec3f(-sx, -sy, 1.f));
    const bool finite = (std::abs(m.x) < Infinity) & (std::abs(m.y) < Infinity) & (std::abs(m.z) < Infinity);
    return {select(finite, m.x, 0.f), select(finite, m.y, 0.f), select(finite, m.z, 1.f)};
}

/// Inverse error function (Giles 2010 single-precision approximation).
float erfinv(float x);

class MicrofacetDistribution {
public:
    MicrofacetDistribution(MicrofacetType type, float alpha_u, float alpha_v, bool sample_visible = true)
        : m_type(type), m_alpha_u(std::max(alpha_u, 1e-4f)), m_alpha_v(std::max(alpha_v, 1e-4f)),
          m_sample_visible(sample_visible) {}

    MicrofacetType type() const { return m_type; }
    float alpha_u() const { return m_alpha_u; }
    float alpha_v() const { return m_alpha_v; }
    bool sample_visible() const { return m_sample_visible; }
    /// Multiply both roughnesses by `s` (Walter et al.'s sampling-roughness widening).
    void scale_alpha(float s) { m_alpha_u *= s; m_alpha_v *= s; }

    /// Normal distribution D(m).
    float eval(Vec3f m) const {
        return beckmann() ? microfacet_d(m, m_alpha_u, m_alpha_v, true) : microfacet_d(m, m_alpha_u, m_alpha_v, false);
    }
    /// Density of `sample` producing m (given wi when sampling visible normals).
    float pdf(Vec3f wi, Vec3f m) const {
        if (!m_sample_visible) return eval(m) * Frame::cos_theta(m);
        return beckmann() ? microfacet_pdf_visible(wi, m, m_alpha_u, m_alpha_v, true)
                          : microfacet_pdf_visible(wi, m, m_alpha_u, m_alpha_v, false);
    }
    /// Sample a microfacet normal; returns m and writes its density (unless `pdf` is null).
    Vec3f sample(Vec3f wi, Vec2f u, float *pdf) const;
    /// Smith's separable shadowing-masking G1(v, m).
    float smith_g1(Vec3f v, Vec3f m) const {
        return beckmann() ? microfacet_g1(v, m, m_alpha_u, m_alpha_v, true)
                          : microfacet_g1(v, m, m_alpha_u, m_alpha_v, false);
    }
    /// G(wi, wo, m) = G1(wi, m) G1(wo, m).
    float G(Vec3f wi, Vec3f wo, Vec3f m) const { return smith_g1(wi, m) * smith_g1(wo, m); }

private:
    bool beckmann() const { return m_type == MicrofacetType::Beckmann; }

    MicrofacetType m_type;
    float m_alpha_u, m_alpha_v;
    bool m_sample_visible;
};

/// Parse "ggx" / "beckmann" (case-insensitive, as Mitsuba); false if unknown.
inline bool parse_microfacet_type(std::string s, MicrofacetType &t) {
    for (auto &c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (s == "ggx") { t = MicrofacetType::GGX; return true; }
    if (s == "beckmann") { t = MicrofacetType::Beckmann; return true; }
    return false;
}

} // namespace mvpt
