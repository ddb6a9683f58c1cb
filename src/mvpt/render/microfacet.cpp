#include "microfacet.h"

#include "fresnel.h"

#include <cmath>

namespace mvpt {

float erfinv(float x) {
    // Giles, "Approximating the erfinv function", GPU Computing Gems (2010).
    float w = -std::log(std::max((1.f - x) * (1.f + x), 1e-30f)), p;
    if (w < 5.f) {
        w -= 2.5f;
        p = 2.81022636e-08f;
        p = 3.43273939e-07f + p * w;
        p = -3.5233877e-06f + p * w;
        p = -4.39150654e-06f + p * w;
        p = 0.00021858087f + p * w;
        p = -0.00125372503f + p * w;
        p = -0.00417768164f + p * w;
        p = 0.246640727f + p * w;
        p = 1.50140941f + p * w;
    } else {
        w = std::sqrt(w) - 3.f;
        p = -0.000200214257f;
        p = 0.000100950558f + p * w;
        p = 0.00134934322f + p * w;
        p = -0.00367342844f + p * w;
        p = 0.00573950773f + p * w;
        p = -0.0076224613f + p * w;
        p = 0.00943887047f + p * w;
        p = 1.00167406f + p * w;
        p = 2.83297682f + p * w;
    }
    return p * x;
}

float MicrofacetDistribution::eval(Vec3f m) const {
    float cos2 = Frame::cos2_theta(m);
    if (cos2 <= 0.f) return 0.f;
    float ax2 = m_alpha_u * m_alpha_u, ay2 = m_alpha_v * m_alpha_v;
    // tan^2(theta) (cos^2 phi / ax^2 + sin^2 phi / ay^2), written with m.x, m.y.
    float e = (m.x * m.x / ax2 + m.y * m.y / ay2) / cos2;
    float r;
    if (m_type == MicrofacetType::Beckmann)
        r = std::exp(-e) / (Pi * m_alpha_u * m_alpha_v * cos2 * cos2);
    else
        r = 1.f / (Pi * m_alpha_u * m_alpha_v * cos2 * cos2 * (1.f + e) * (1.f + e));
    return (r * cos2 > 1e-20f) ? r : 0.f;
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
        // Slopes of the visible GGX distribution for alpha = 1 [Heitz and d'Eon 2014, appendix].
        if (cos_theta_i > 0.99999f) {
            float r = std::sqrt(u.x / std::max(1.f - u.x, 1e-7f)), phi = 2.f * Pi * u.y;
            return {r * std::cos(phi), r * std::sin(phi)};
        }
        float sin_i = safe_sqrt(1.f - cos_theta_i * cos_theta_i), tan_i = sin_i / cos_theta_i;
        float a = 1.f / tan_i, g1 = 2.f / (1.f + safe_sqrt(1.f + 1.f / (a * a)));
        float A = 2.f * u.x / g1 - 1.f;
        float tmp = 1.f / (A * A - 1.f);
        if (std::abs(A * A - 1.f) < 1e-7f) tmp = 1e7f;
        float B = tan_i, D = safe_sqrt(B * B * tmp * tmp - (A * A - B * B) * tmp);
        float sx1 = B * tmp - D, sx2 = B * tmp + D;
        float sx = (A < 0.f || sx2 > 1.f / tan_i) ? sx1 : sx2;
        float s, uy;
        if (u.y > 0.5f) { s = 1.f; uy = 2.f * (u.y - 0.5f); }
        else { s = -1.f; uy = 2.f * (0.5f - u.y); }
        float z = (uy * (uy * (uy * 0.27385f - 0.73369f) + 0.46341f)) /
                  (uy * (uy * (uy * 0.093073f + 0.309420f) - 1.f) + 0.597999f);
        float sy = s * z * std::sqrt(1.f + sx * sx);
        return {sx, sy};
    }
    // Beckmann: invert the CDF of visible slopes by Newton-bisection [Jakob 2014, Mitsuba].
    float tan_i = safe_sqrt(1.f - cos_theta_i * cos_theta_i) / cos_theta_i, cot_i = 1.f / tan_i;
    constexpr float InvSqrtPi = 0.56418958354775628695f;
    float a = -1.f, c = std::erf(cot_i);
    float ux = std::max(u.x, 1e-6f);
    float theta_i = safe_acos(cos_theta_i);
    float fit = 1.f + theta_i * (-0.876f + theta_i * (0.4265f - 0.0594f * theta_i));
    float b = c - (1.f + c) * std::pow(1.f - ux, fit);
    float norm = 1.f / (1.f + c + InvSqrtPi * tan_i * std::exp(-cot_i * cot_i));
    for (int it = 0; it < 10; ++it) {
        if (!(b >= a && b <= c)) b = 0.5f * (a + c);
        float ie = erfinv(b);
        float value = norm * (1.f + b + InvSqrtPi * tan_i * std::exp(-ie * ie)) - ux;
        float deriv = norm * (1.f - ie * tan_i);
        if (std::abs(value) < 1e-5f) break;
        if (value > 0.f) c = b;
        else a = b;
        b -= value / deriv;
    }
    return {erfinv(b), erfinv(2.f * std::max(u.y, 1e-6f) - 1.f)};
}

Vec3f MicrofacetDistribution::sample(Vec3f wi, Vec2f u, float *pdf_out) const {
    if (!m_sample_visible) {
        // Sample D(m) cos(theta_m) directly.
        float phi, alpha2, tan2;
        if (m_alpha_u == m_alpha_v) {
            phi = 2.f * Pi * u.y;
            alpha2 = m_alpha_u * m_alpha_u;
        } else {
            float r = m_alpha_v / m_alpha_u;
            phi = std::atan(r * std::tan(2.f * Pi * u.y + 0.5f * Pi));
            if (u.y > 0.5f) phi += Pi;
            float c = std::cos(phi), s = std::sin(phi);
            alpha2 = 1.f / (c * c / (m_alpha_u * m_alpha_u) + s * s / (m_alpha_v * m_alpha_v));
        }
        if (m_type == MicrofacetType::Beckmann) tan2 = -alpha2 * std::log(std::max(1.f - u.x, 1e-12f));
        else tan2 = alpha2 * u.x / std::max(1.f - u.x, 1e-12f);
        float cos_t = 1.f / std::sqrt(1.f + tan2), sin_t = safe_sqrt(1.f - cos_t * cos_t);
        Vec3f m(sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t);
        *pdf_out = eval(m) * cos_t;
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
    *pdf_out = pdf(wi, m);
    return m;
}

float fresnel_diffuse_reflectance(float eta) {
    // Integrate 2 cos(theta) F(cos theta) over [0, 1] (midpoint rule, fine grid).
    const int n = 4096;
    double sum = 0;
    for (int i = 0; i < n; ++i) {
        float c = (i + 0.5f) / n;
        sum += 2.0 * c * fresnel_dielectric(c, eta).F;
    }
    return float(sum / n);
}

} // namespace mvpt
