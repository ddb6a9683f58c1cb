// Fresnel equations for dielectrics and conductors (unpolarised light).
#pragma once

#include "../core/math.h"

namespace mvpt {

/// Result of the dielectric Fresnel equations at one interface.
struct FresnelDielectric {
    float F = 1.f;         ///< reflectance
    float cos_theta_t = 0; ///< signed cosine of the refracted direction (opposite sign to cos_theta_i)
    float eta_it = 1.f;    ///< relative IOR along the refracted direction
    float eta_ti = 1.f;    ///< its inverse
};

/// Dielectric reflectance for incident cosine `cos_theta_i` (negative: from
/// inside) and relative IOR `eta` = n_inside / n_outside [Walter et al. 2007]. Branch-free
/// (total internal reflection and eta = 1 are selected), so loops over views vectorise.
[[gnu::always_inline]] inline FresnelDielectric fresnel_dielectric(float cos_theta_i, float eta) {
    FresnelDielectric r;
    const bool outside = cos_theta_i >= 0.f, index_matched = eta == 1.f;
    const float rcp_eta = 1.f / eta;
    r.eta_it = select(outside, eta, rcp_eta);
    r.eta_ti = select(outside, rcp_eta, eta);
    const float cos_t_sqr = 1.f - r.eta_ti * r.eta_ti * (1.f - cos_theta_i * cos_theta_i);
    const float cos_i = std::abs(cos_theta_i);
    const bool total_internal = cos_t_sqr <= 0.f;
    const float cos_t = std::sqrt(select(total_internal, 0.f, cos_t_sqr));
    const float a_s = (r.eta_ti * cos_i - cos_t) / (r.eta_ti * cos_i + cos_t);
    const float a_p = (cos_i - r.eta_ti * cos_t) / (cos_i + r.eta_ti * cos_t);
    r.F = select(index_matched, 0.f, select(total_internal, 1.f, 0.5f * (a_s * a_s + a_p * a_p)));
    r.cos_theta_t = select(index_matched, -cos_theta_i, select(total_internal, 0.f, select(outside, -cos_t, cos_t)));
    return r;
}

/// Conductor reflectance for complex IOR eta + i k, per channel (also in the vector kernels).
[[gnu::always_inline]] inline float fresnel_conductor(float cos_theta_i, float eta, float k) {
    float c2 = cos_theta_i * cos_theta_i, s2 = 1.f - c2, s4 = s2 * s2;
    float t1 = eta * eta - k * k - s2;
    float a2pb2 = safe_sqrt(t1 * t1 + 4.f * k * k * eta * eta);
    float a = safe_sqrt(0.5f * (a2pb2 + t1));
    float term1 = a2pb2 + c2, term2 = 2.f * cos_theta_i * a;
    float r_s = (term1 - term2) / (term1 + term2);
    float term3 = a2pb2 * c2 + s4, term4 = term2 * s2;
    float r_p = r_s * (term3 - term4) / (term3 + term4);
    return 0.5f * (r_s + r_p);
}

inline Color3f fresnel_conductor(float cos_theta_i, Color3f eta, Color3f k) {
    return {fresnel_conductor(cos_theta_i, eta.r, k.r), fresnel_conductor(cos_theta_i, eta.g, k.g),
            fresnel_conductor(cos_theta_i, eta.b, k.b)};
}

/// Refract `wi` (pointing away) about normal `m` with the cosine from fresnel_dielectric.
inline Vec3f refract(Vec3f wi, Vec3f m, float cos_theta_t, float eta_ti) {
    return m * (dot(wi, m) * eta_ti + cos_theta_t) - wi * eta_ti;
}
/// Refraction about the local +z axis.
inline Vec3f refract(Vec3f wi, float cos_theta_t, float eta_ti) { return {-eta_ti * wi.x, -eta_ti * wi.y, cos_theta_t}; }

/// Diffuse Fresnel reflectance F_dr(eta): the cosine-weighted hemispherical
/// average of F, by the same fits Mitsuba 3 uses: Egan and Hilgeman (1973) for
/// eta < 1, d'Eon and Irving (2011) otherwise (max. rel. error ~0.1-0.6%).
inline float fresnel_diffuse_reflectance(float eta) {
    float inv_eta = 1.f / eta;
    if (eta < 1.f) return 0.0636f * inv_eta + eta * (eta * -1.4399f + 0.7099f) + 0.6681f;
    float x = inv_eta; // polynomial in 1/eta, Horner form
    return 0.919317f + x * (-3.4793f + x * (6.75335f + x * (-7.80989f + x * (4.98554f + x * -1.36881f))));
}

} // namespace mvpt
