// Microfacet distributions (GGX / Beckmann, anisotropic) with Smith masking
// and visible-normal sampling [Heitz and d'Eon 2014; Heitz 2018 for GGX;
// Jakob 2014 for Beckmann], following Mitsuba 3's MicrofacetDistribution.
#pragma once

#include "../core/math.h"

#include <cctype>
#include <string>

namespace mvpt {

enum class MicrofacetType { Beckmann, GGX };

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
    float eval(Vec3f m) const;
    /// Density of `sample` producing m (given wi when sampling visible normals).
    float pdf(Vec3f wi, Vec3f m) const;
    /// Sample a microfacet normal; returns m and writes its density (unless `pdf` is null).
    Vec3f sample(Vec3f wi, Vec2f u, float *pdf) const;
    /// Smith's separable shadowing-masking G1(v, m).
    float smith_g1(Vec3f v, Vec3f m) const;
    /// G(wi, wo, m) = G1(wi, m) G1(wo, m).
    float G(Vec3f wi, Vec3f wo, Vec3f m) const { return smith_g1(wi, m) * smith_g1(wo, m); }

private:
    Vec2f sample_visible_11(float cos_theta_i, Vec2f u) const;
    float project_roughness_sqr(Vec3f v) const;

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
