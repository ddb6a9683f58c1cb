#include "microfacet.h"

#include "../core/poly_math.h"
#include "../core/warp.h"

#include <cmath>

namespace mvpt {

float erfinv(float x) { return erfinv_poly(x); }

float MicrofacetDistribution::eval(Vec3f m) const {
    float cos2 = Frame::cos2_theta(m);
    if (cos2 <= 0.f) return 0.f;
    float ax2 = m_alpha_u * m_alpha_u, ay2 = m_alpha_v * m_alpha_v;
    // tan^2(theta) (cos^2 phi / ax^2 + sin^2 phi / ay^2), written with m.x, m.y.
    float e = (m.x * m.x / ax2 + m.y * m.y / ay2) / cos2;
    float r;
    if (m_type == MicrofacetType::Beckmann)
        r = exp_poly(-e) / (Pi * m_alpha_u * m_alpha_v * cos2 * cos2);
    else
        r = 1.f / (Pi * m_alpha_u * m_alpha_v * cos2 * cos2 * (1.f + e) * (1.f + e));
    // As Mitsuba: drop negligible values to avoid numerical trouble downstream.
    return (r * m.z > 1e-20f) ? r : 0.f;
}

float MicrofacetDistribution::project_roughness_sqr(Vec3f v) const {
    float xy2 = v.x * v.x + v.y * v.y;
    if (xy2 <= 0.f) return m_alpha_u * m_alpha_u;
    return (v.x * v.x * m_alpha_u * m_alpha_u + v.y * v.y * m_alpha_v * m_alpha_v) / xy2;
}

float MicrofacetDistribution::smith_g1(Vec3f v, Vec3f m) const {
    if (dot(v, m) * Frame::cos_theta(v) <= 0.f) return 0.f;
    float xy2 = v.x * v.x + v.y * v.y;
    if (xy2 == 0.f) return 1.f;
    float tan2 = xy2 / (v.z * v.z);
    float alpha2 = project_roughness_sqr(v);
    if (m_type == MicrofacetType::Beckmann) {
        float a = 1.f / std::sqrt(alpha2 * tan2);
        if (a >= 1.6f) return 1.f;
        return (3.535f * a + 2.181f * a * a) / (1.f + 2.276f * a + 2.577f * a * a);
    }
    return 2.f / (1.f + std::sqrt(1.f + alpha2 * tan2));
}

float MicrofacetDistribution::pdf(Vec3f wi, Vec3f m) const {
    float d = eval(m);
    if (!m_sample_visible) return d * Frame::cos_theta(m);
    float cos_i = Frame::cos_theta(wi);
    if (cos_i == 0.f) return 0.f;
    return smith_g1(wi, m) * absdot(wi, m) * d / std::abs(cos_i);
}

Vec2f MicrofacetDistribution::sample_visible_11(float cos_theta_i, Vec2f u) const {
    if (m_type == MicrofacetType::GGX) {
        // Exact visible-normal sampling of the alpha = 1 GGX distribution by projecting a
        // disk sample onto the visible hemisphere [Heitz 2018, "A Simpler and Exact Sampling
        // Routine for the GGX Distribution of Visible Normals"], written in slope space.
        Vec2f p = warp::square_to_uniform_disk_concentric(u);
        float s = 0.5f * (1.f + cos_theta_i);
        p.y = lerp(s, safe_sqrt(1.f - p.x * p.x), p.y);
        float z = safe_sqrt(1.f - p.x * p.x - p.y * p.y);
        float sin_theta_i = safe_sqrt(1.f - cos_theta_i * cos_theta_i);
        float inv_norm = 1.f / (sin_theta_i * p.y + cos_theta_i * z);
        return {(cos_theta_i * p.y - sin_theta_i * z) * inv_norm, p.x * inv_norm};
    }
    // Beckmann: numerical inversion of the CDF of visible x-slopes in the erf() domain,
    // started from the analytic solution for grazing incidence and refined by three
    // Newton steps [Jakob 2014, "An Improved Visible Normal Sampling Routine for the
    // Beckmann Distribution"]; the y-slope is an independent Gaussian.
    constexpr float InvSqrtPi = 0.56418958354775628695f;
    float tan_theta_i = safe_sqrt(1.f - cos_theta_i * cos_theta_i) / cos_theta_i;
    float cot_theta_i = 1.f / tan_theta_i;
    float max_val = erf_poly(cot_theta_i);
    u.x = std::clamp(u.x, 1e-6f, 1.f - 1e-6f);
    u.y = std::clamp(u.y, 1e-6f, 1.f - 1e-6f);
    float x = max_val - (max_val + 1.f) * erf_poly(std::sqrt(-log_poly(u.x)));
    float target = u.x * (1.f + max_val + InvSqrtPi * tan_theta_i * exp_poly(-cot_theta_i * cot_theta_i));
    for (int it = 0; it < 3; ++it) {
        float slope = erfinv(x);
        float value = 1.f + x + InvSqrtPi * tan_theta_i * exp_poly(-slope * slope) - target;
        float derivative = 1.f - slope * tan_theta_i;
        x -= value / derivative;
    }
    return {erfinv(x), erfinv(2.f * u.y - 1.f)};
}

Vec3f MicrofacetDistribution::sample(Vec3f wi, Vec2f u, float *pdf_out) const {
    if (!m_sample_visible) {
        // Sample D(m) cos(theta_m) directly.
        float sin_phi, cos_phi, alpha2, tan2;
        if (m_alpha_u == m_alpha_v) {
            float phi = 2.f * Pi * u.y;
            cos_phi = std::cos(phi);
            sin_phi = std::sin(phi);
            alpha2 = m_alpha_u * m_alpha_u;
        } else {
            // Anisotropic azimuth: tan(phi) = (alpha_v / alpha_u) tan(2 pi u) [Walter et al. 2007].
            float t = (m_alpha_v / m_alpha_u) * std::tan(2.f * Pi * u.y);
            cos_phi = std::copysign(1.f / std::sqrt(t * t + 1.f), std::abs(u.y - 0.5f) - 0.25f);
            sin_phi = cos_phi * t;
            alpha2 = 1.f / (sqr(cos_phi / m_alpha_u) + sqr(sin_phi / m_alpha_v));
        }
        if (m_type == MicrofacetType::Beckmann) tan2 = -alpha2 * log_poly(std::max(1.f - u.x, 1e-12f));
        else tan2 = alpha2 * u.x / std::max(1.f - u.x, 1e-12f);
        float cos_t = 1.f / std::sqrt(1.f + tan2), sin_t = safe_sqrt(1.f - cos_t * cos_t);
        Vec3f m(sin_t * cos_phi, sin_t * sin_phi, cos_t);
        if (pdf_out) *pdf_out = eval(m) * cos_t;
        return m;
    }
    // Stretch wi to the alpha = 1 configuration, sample slopes, unstretch [Heitz and d'Eon 2014].
    Vec3f wi_p = normalize(Vec3f(m_alpha_u * wi.x, m_alpha_v * wi.y, wi.z));
    float sin_t = Frame::sin_theta(wi_p);
    float cos_phi = sin_t > 0.f ? wi_p.x / sin_t : 1.f, sin_phi = sin_t > 0.f ? wi_p.y / sin_t : 0.f;
    Vec2f slope = sample_visible_11(wi_p.z, u);
    slope = {cos_phi * slope.x - sin_phi * slope.y, sin_phi * slope.x + cos_phi * slope.y};
    slope.x *= m_alpha_u;
    slope.y *= m_alpha_v;
    Vec3f m = normalize(Vec3f(-slope.x, -slope.y, 1.f));
    if (!all_finite(m)) m = Vec3f(0.f, 0.f, 1.f);
    if (pdf_out) *pdf_out = pdf(wi, m);
    return m;
}

} // namespace mvpt
