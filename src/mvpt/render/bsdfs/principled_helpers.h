// Pieces shared by the `principled` and `principledthin` BSDFs: the GTR1
// clearcoat distribution, Schlick Fresnel terms, the principled Fresnel blend
// and the roughness mapping [Burley 2012, "Physically Based Shading at
// Disney"; Burley 2015, "Extending the Disney BRDF to a BSDF with Integrated
// Subsurface Scattering"], following Mitsuba 3's conventions.
#pragma once

#include "../../core/math.h"
#include "../../core/warp.h"
#include "../../core/properties.h"
#include "../texture.h"

#include <string>
#include <utility>

namespace mvpt::principled {

/// Whether a lobe parameter switches its lobe on (Mitsuba's `get_flag`): it is
/// given, and not as a float equal to zero. (Deviation: an `<rgb>` of zeros also
/// counts as off here; its lobe then evaluates to zero either way.)
inline bool lobe_enabled(const Properties &props, const std::string &name) {
    if (!props.has_texture(name)) return false;
    if (!props.has(name)) return true; // a texture object
    Color3f c = props.get_color(name, Color3f(0.f));
    return !(c.r == 0.f && c.g == 0.f && c.b == 0.f);
}

/// Texture parameter that is only evaluated when its lobe is enabled (else 0).
struct LobeParam {
    std::shared_ptr<Texture> tex;
    bool enabled = false;

    LobeParam() = default;
    LobeParam(const Properties &props, const std::string &name, float def)
        : enabled(lobe_enabled(props, name)) {
        tex = get_texture(props, name, def);
    }
    float eval_1(const SurfaceInteraction &si) const { return enabled ? tex->eval_1(si) : 0.f; }
};

/// Rec. 709 luminance of a linear RGB colour.
inline float luminance(Color3f c) { return 0.212671f * c.r + 0.715160f * c.g + 0.072169f * c.b; }

/// Schlick's weight (1 - cos)^5, with the argument clamped to [0, 1].
inline float schlick_weight(float cos_i) {
    float m = std::clamp(1.f - cos_i, 0.f, 1.f);
    float m2 = m * m;
    return m2 * m2 * m;
}

/// Schlick Fresnel R0 + (1 - R0) (1 - cos)^5; inside a denser medium the cosine
/// of the refracted direction is used [Burley 2015, §5.1; Mitsuba `calc_schlick`].
template <typename T> inline T schlick_fresnel(T r0, float cos_theta_i, float eta) {
    bool outside = cos_theta_i >= 0.f;
    float eta_it = outside ? eta : 1.f / eta, eta_ti = outside ? 1.f / eta : eta;
    float cos_t = safe_sqrt(1.f - (1.f - cos_theta_i * cos_theta_i) * eta_ti * eta_ti);
    float w = eta_it > 1.f ? schlick_weight(std::abs(cos_theta_i)) : schlick_weight(cos_t);
    return r0 + (T(1.f) - r0) * w;
}

/// Normal-incidence reflectance of relative IOR `eta`.
inline float schlick_r0(float eta) {
    float r = (eta - 1.f) / (eta + 1.f);
    return r * r;
}

/// Both `wi` and `wo` on the side of microfacet `m` that the macro surface
/// allows: same side for reflection, opposite sides for transmission.
inline bool mac_mic_compatible(Vec3f m, Vec3f wi, Vec3f wo, float cos_theta_i, bool reflection) {
    Vec3f ms = cos_theta_i < 0.f ? -m : m;
    if (dot(wi, ms) <= 0.f) return false;
    return reflection ? dot(wo, ms) > 0.f : dot(wo, ms) < 0.f;
}

/// GGX alphas from roughness and anisotropy [Burley 2012, addenda B.2].
inline std::pair<float, float> dist_params(float anisotropic, float roughness, bool has_anisotropic) {
    float r2 = roughness * roughness;
    if (!has_anisotropic) {
        float a = std::max(0.001f, r2);
        return {a, a};
    }
    float aspect = std::sqrt(1.f - 0.9f * anisotropic);
    return {std::max(0.001f, r2 / aspect), std::max(0.001f, r2 * aspect)};
}

/// Principled Fresnel: the dielectric term blended with Schlick terms for the
/// metallic and spec_tint parts on the front side; plain dielectric (scaled by
/// the transmission weight `bsdf`) from inside [Mitsuba `principled_fresnel`].
inline Color3f principled_fresnel(float F_dielectric, float metallic, float spec_tint, Color3f base_color, float lum,
                                  float cos_theta_i, bool front_side, float bsdf, float eta, bool has_metallic,
                                  bool has_spec_tint) {
    if (!front_side) return Color3f(bsdf * F_dielectric);
    float eta_it = cos_theta_i >= 0.f ? eta : 1.f / eta;
    Color3f F_schlick(0.f);
    if (has_metallic) F_schlick += schlick_fresnel(base_color, cos_theta_i, eta) * metallic;
    if (has_spec_tint) {
        Color3f c_tint = lum > 0.f ? base_color / lum : Color3f(1.f);
        F_schlick += schlick_fresnel(c_tint * schlick_r0(eta_it), cos_theta_i, eta) * ((1.f - metallic) * spec_tint);
    }
    return Color3f((1.f - metallic) * (1.f - spec_tint) * F_dielectric) + F_schlick;
}

/// Thin-sheet Fresnel: the dielectric term blended with a tinted Schlick term.
inline Color3f thin_fresnel(float F_dielectric, float spec_tint, Color3f base_color, float lum, float cos_theta_i,
                            float eta_t, bool has_spec_tint) {
    Color3f F_schlick(0.f);
    if (has_spec_tint) {
        Color3f c_tint = lum > 0.f ? base_color / lum : Color3f(1.f);
        F_schlick = schlick_fresnel(c_tint * schlick_r0(eta_t), cos_theta_i, eta_t);
    }
    return Color3f(F_dielectric) * (1.f - spec_tint) + F_schlick * spec_tint;
}

/// Diffuse factor (without base_color / pi): Burley's Fresnel-shaped diffuse plus
/// retro-reflection, blended towards the Hanrahan-Krueger-like fake subsurface
/// term by `flatness` [Burley 2012, §5.3; Burley 2015, §5.3]. `cos_theta_d` is
/// the cosine between the half vector and wo.
inline float disney_diffuse(float abs_cos_i, float abs_cos_o, float cos_theta_d, float roughness, float flatness,
                            bool has_flatness) {
    float Fo = schlick_weight(abs_cos_o), Fi = schlick_weight(abs_cos_i);
    float f_diff = (1.f - 0.5f * Fi) * (1.f - 0.5f * Fo);
    float Rr = 2.f * roughness * cos_theta_d * cos_theta_d;
    float f_retro = Rr * (Fo + Fi + Fo * Fi * (Rr - 1.f));
    if (!has_flatness) return f_diff + f_retro;
    float Fss90 = Rr / 2.f;
    float Fss = lerp(Fo, 1.f, Fss90) * lerp(Fi, 1.f, Fss90);
    float f_ss = 1.25f * (Fss * (1.f / (abs_cos_o + abs_cos_i) - 0.5f) + 0.5f);
    return lerp(flatness, f_diff + f_retro, f_ss);
}

/// Sheen colour: white, tinted towards the luminance-normalised base colour.
inline Color3f sheen_color(Color3f base_color, float sheen_tint, bool has_sheen_tint) {
    if (!has_sheen_tint) return Color3f(1.f);
    float lum = luminance(base_color);
    Color3f c_tint = lum > 0.f ? base_color / lum : Color3f(1.f);
    return lerp(sheen_tint, Color3f(1.f), c_tint);
}

/// Sample a GGX normal from the distribution of normals visible from `wi` (upper
/// hemisphere) exactly, by projecting a disk sample onto the hemisphere of the
/// stretched configuration [Heitz 2018, "Sampling the GGX Distribution of Visible
/// Normals", JCGT 7(4)]; the slope form of Mitsuba 3. (MicrofacetDistribution::sample
/// uses the approximate slope fit of Heitz and d'Eon 2014, which a 10^6-sample
/// χ² test detects.) Its density is MicrofacetDistribution::pdf(wi, m).
inline Vec3f sample_ggx_visible(Vec3f wi, float ax, float ay, Vec2f u) {
    // Stretch wi to the alpha = 1 configuration.
    Vec3f wi_p = normalize(Vec3f(ax * wi.x, ay * wi.y, wi.z));
    float cos_i = wi_p.z, sin_i = safe_sqrt(1.f - cos_i * cos_i);
    float cos_phi = sin_i > 0.f ? std::clamp(wi_p.x / sin_i, -1.f, 1.f) : 1.f;
    float sin_phi = sin_i > 0.f ? std::clamp(wi_p.y / sin_i, -1.f, 1.f) : 0.f;
    // Disk sample, squeezed onto the visible part of the projected hemisphere.
    Vec2f p = warp::square_to_uniform_disk_concentric(u);
    float s = 0.5f * (1.f + cos_i);
    p.y = lerp(s, safe_sqrt(1.f - p.x * p.x), p.y);
    float z = safe_sqrt(1.f - p.x * p.x - p.y * p.y);
    // Lift to the hemisphere around wi_p and convert to slopes.
    float inv = 1.f / (sin_i * p.y + cos_i * z);
    Vec2f slope((cos_i * p.y - sin_i * z) * inv, p.x * inv);
    // Rotate back and unstretch.
    slope = {(cos_phi * slope.x - sin_phi * slope.y) * ax, (sin_phi * slope.x + cos_phi * slope.y) * ay};
    Vec3f m = normalize(Vec3f(-slope.x, -slope.y, 1.f));
    return all_finite(m) ? m : Vec3f(0.f, 0.f, 1.f);
}

/// Isotropic GTR1 ("Berry") normal distribution of the clearcoat lobe, sampled
/// proportionally to D(m) cos(theta_m) [Burley 2012, addenda B.1 and B.2].
class Gtr1 {
public:
    explicit Gtr1(float alpha) : m_alpha(alpha) {}

    /// D(m) = (a^2 - 1) / (pi log(a^2) (1 + (a^2 - 1) cos^2 theta)).
    float eval(Vec3f m) const {
        float a2 = m_alpha * m_alpha, c = Frame::cos_theta(m);
        float d = (a2 - 1.f) / (Pi * std::log(a2) * (1.f + (a2 - 1.f) * c * c));
        return d * c > 1e-20f ? d : 0.f;
    }
    /// Density of `sample`: D(m) cos(theta_m) on the upper hemisphere.
    float pdf(Vec3f m) const { return m.z < 0.f ? 0.f : Frame::cos_theta(m) * eval(m); }
    /// Sample m; `u.x` drives the azimuth, `u.y` the elevation.
    Vec3f sample(Vec2f u) const {
        float phi = 2.f * Pi * u.x, a2 = m_alpha * m_alpha;
        float cos2 = (1.f - std::pow(a2, 1.f - u.y)) / (1.f - a2);
        float sin_t = std::sqrt(std::max(0.f, 1.f - cos2)), cos_t = std::sqrt(std::max(0.f, cos2));
        return {std::cos(phi) * sin_t, std::sin(phi) * sin_t, cos_t};
    }

private:
    float m_alpha;
};

/// Smith G1 of an isotropic GGX with roughness `alpha` (the clearcoat lobe's
/// fixed alpha = 0.25 masking) [Walter et al. 2007, eq. 34].
inline float smith_ggx1(Vec3f v, Vec3f wh, float alpha) {
    if (dot(v, wh) * Frame::cos_theta(v) <= 0.f) return 0.f;
    if (v.z == 1.f) return 1.f;
    float c2 = v.z * v.z, tan2 = (1.f - c2) / c2;
    return 2.f / (1.f + std::sqrt(1.f + alpha * alpha * tan2));
}

} // namespace mvpt::principled
