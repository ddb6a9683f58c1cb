#include "microfacet.h"

#include <cmath>

namespace mvpt {

float erfinv(float x) { return erfinv_poly(x); }

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
    const Vec3f m = beckmann() ? microfacet_sample_visible<MicrofacetLanes::Beckmann>(wi, u, m_alpha_u, m_alpha_v, true)
                               : microfacet_sample_visible<MicrofacetLanes::GGX>(wi, u, m_alpha_u, m_alpha_v, false);
    if (pdf_out) *pdf_out = pdf(wi, m);
    return m;
}

} // namespace mvpt
