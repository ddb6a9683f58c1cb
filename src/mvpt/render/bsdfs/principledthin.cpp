// Mitsuba 3's `principledthin` BSDF: the principled model for thin,
// two-sided sheets (leaves, paper, cloth) [Burley 2015, §4]. A GGX reflection
// lobe, a GGX "transmission" lobe that reflects and then mirrors the direction
// through the sheet (no bending; roughness scaled by eta, Burley 2015, fig. 15),
// diffuse reflection with retro-reflection, fake subsurface and sheen, and
// Lambertian diffuse transmission. Symmetric: a back-side query is answered by
// mirroring both directions to the front. Formulas, masks and lobe-selection
// probabilities follow Mitsuba 3.9 (src/bsdfs/principledthin.cpp).
#include "../../core/warp.h"
#include "../../core/plugin.h"
#include "../bsdf.h"
#include "../fresnel.h"
#include "../microfacet.h"
#include "principled_helpers.h"

namespace mvpt {

using namespace principled;

class PrincipledThinBsdf final : public Bsdf {
public:
    explicit PrincipledThinBsdf(const Properties &props) {
        m_base_color = get_texture(props, "base_color", 0.5f);
        m_roughness = get_texture(props, "roughness", 0.5f);
        m_anisotropic = LobeParam(props, "anisotropic", 0.f);
        m_spec_trans = LobeParam(props, "spec_trans", 0.f);
        m_sheen = LobeParam(props, "sheen", 0.f);
        m_sheen_tint = LobeParam(props, "sheen_tint", 0.f);
        m_flatness = LobeParam(props, "flatness", 0.f);
        m_spec_tint = LobeParam(props, "spec_tint", 0.f);
        m_eta = get_texture(props, "eta", 1.5f, SpectrumUse::Unbounded);
        m_diff_trans = LobeParam(props, "diff_trans", 0.f);
        auto rate = [&](const char *name) {
            float r = props.get_float(name, 1.f);
            if (r < 0.f) props.fail(name, std::string("'") + name + "' must be >= 0");
            return r;
        };
        m_spec_refl_srate = rate("specular_reflectance_sampling_rate");
        m_spec_trans_srate = rate("specular_transmittance_sampling_rate");
        m_diff_trans_srate = rate("diffuse_transmittance_sampling_rate");
        m_diff_refl_srate = rate("diffuse_reflectance_sampling_rate");

        m_flags = BsdfDiffuseReflection | BsdfDiffuseTransmission | BsdfGlossyReflection;
        if (m_spec_trans.enabled) m_flags |= BsdfGlossyTransmission;
    }

    std::pair<BsdfSample, Spectrum> sample(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi_in,
                                           float u1, Vec2f u2) const override {
        BsdfSample bs;
        float cos_theta_i = Frame::cos_theta(wi_in);
        if (cos_theta_i == 0.f) return {bs, {}};
        Weights w = weights(si);
        // Work on the front side; the result is mirrored back at the end.
        Vec3f wi = cos_theta_i > 0.f ? wi_in : -wi_in;
        LobeProbs p = lobe_probs(w);

        Vec3f wo;
        if (m_spec_trans.enabled && u1 < p.spec_reflect) {
            auto [ax, ay] = dist_params(w.anisotropic, w.roughness, m_anisotropic.enabled);
            Vec3f m = sample_ggx_visible(wi, ax, ay, u2);
            wo = reflect(wi, m);
            bs.sampled_type = BsdfGlossyReflection;
            if (!(Frame::cos_theta(wo) > 0.f) || !mac_mic_compatible(m, wi, wo, wi.z, true)) return {bs, {}};
        } else if (m_spec_trans.enabled && u1 < p.spec_reflect + p.spec_trans) {
            auto [ax, ay] = dist_params(w.anisotropic, scaled_roughness(w), m_anisotropic.enabled);
            Vec3f m = sample_ggx_visible(wi, ax, ay, u2);
            // Reflect on the microfacet, then pass straight through the sheet.
            wo = reflect(wi, m);
            wo.z = -wo.z;
            bs.sampled_type = BsdfGlossyTransmission;
            if (!(Frame::cos_theta(wo) < 0.f) || !mac_mic_compatible(m, wi, wo, wi.z, false)) return {bs, {}};
        } else if (!m_diff_trans.enabled || u1 < p.spec_reflect + p.spec_trans + p.diffuse_reflect) {
            wo = warp::square_to_cosine_hemisphere(u2);
            bs.sampled_type = BsdfDiffuseReflection;
        } else {
            wo = -warp::square_to_cosine_hemisphere(u2);
            bs.sampled_type = BsdfDiffuseTransmission;
        }
        bs.wo = cos_theta_i > 0.f ? wo : -wo;
        bs.eta = 1.f;

        bs.pdf = pdf(ctx, si, wi_in, bs.wo);
        if (!(bs.pdf > 0.f)) return {bs, {}};
        return {bs, eval(ctx, si, wi_in, bs.wo) / bs.pdf};
    }

    Spectrum eval(const BsdfContext &, const SurfaceInteraction &si, Vec3f wi_in, Vec3f wo_in) const override {
        float cos_theta_i = Frame::cos_theta(wi_in);
        if (cos_theta_i == 0.f) return {};
        Weights w = weights(si);
        float flatness = m_flatness.eval_1(si);
        Color3f base_color = m_base_color->eval(si);

        // Mirror to the front side (the sheet is symmetric).
        Vec3f wi = cos_theta_i > 0.f ? wi_in : -wi_in, wo = cos_theta_i > 0.f ? wo_in : -wo_in;
        cos_theta_i = std::abs(cos_theta_i);
        float cos_theta_o = Frame::cos_theta(wo);
        bool reflect = cos_theta_o > 0.f, refract = cos_theta_o < 0.f;
        // Half vector of wi and wo mirrored to the upper side.
        Vec3f wh = normalize(wi + Vec3f(wo.x, wo.y, std::abs(wo.z)));

        bool spec_reflect_active = w.spec_trans > 0.f && reflect && mac_mic_compatible(wh, wi, wo, wi.z, true);
        bool spec_trans_active = refract && w.spec_trans > 0.f && mac_mic_compatible(wh, wi, wo, wi.z, false);
        bool diffuse_reflect_active = reflect && w.spec_trans < 1.f && w.diff_trans < 1.f;
        bool diffuse_trans_active = refract && w.spec_trans < 1.f && w.diff_trans > 0.f;

        Color3f value(0.f);
        if (m_spec_trans.enabled) {
            float F = fresnel_dielectric(dot(wi, wh), w.eta).F;
            if (spec_reflect_active) {
                auto [ax, ay] = dist_params(w.anisotropic, w.roughness, m_anisotropic.enabled);
                MicrofacetDistribution distr(MicrofacetType::GGX, ax, ay);
                float lum = m_spec_tint.enabled ? luminance(base_color) : 1.f;
                Color3f F_thin = thin_fresnel(F, m_spec_tint.eval_1(si), base_color, lum, dot(wi, wh), w.eta,
                                              m_spec_tint.enabled);
                value += F_thin * (w.spec_trans * distr.eval(wh) * distr.G(wi, wo, wh) / (4.f * cos_theta_i));
            }
            if (spec_trans_active) {
                auto [ax, ay] = dist_params(w.anisotropic, scaled_roughness(w), m_anisotropic.enabled);
                MicrofacetDistribution distr(MicrofacetType::GGX, ax, ay);
                value += base_color *
                         (w.spec_trans * (1.f - F) * distr.eval(wh) * distr.G(wi, wo, wh) / (4.f * cos_theta_i));
            }
        }

        if (diffuse_reflect_active) {
            float cos_theta_d = dot(wh, wo);
            float f = disney_diffuse(cos_theta_i, std::abs(cos_theta_o), cos_theta_d, w.roughness, flatness,
                                     m_flatness.enabled);
            float weight = (1.f - w.spec_trans) * (1.f - w.diff_trans);
            value += base_color * (weight * cos_theta_o * InvPi * f);
            float sheen = m_sheen.eval_1(si);
            if (m_sheen.enabled && sheen > 0.f) {
                Color3f c_sheen = sheen_color(base_color, m_sheen_tint.eval_1(si), m_sheen_tint.enabled);
                value += c_sheen * (sheen * weight * schlick_weight(std::abs(cos_theta_d)) * std::abs(cos_theta_o));
            }
        }
        // Lambertian diffuse transmission.
        if (m_diff_trans.enabled && diffuse_trans_active)
            value += base_color * ((1.f - w.spec_trans) * w.diff_trans * InvPi * std::abs(cos_theta_o));
        return value;
    }

    float pdf(const BsdfContext &, const SurfaceInteraction &si, Vec3f wi_in, Vec3f wo_in) const override {
        float cos_theta_i = Frame::cos_theta(wi_in);
        if (cos_theta_i == 0.f) return 0.f;
        Weights w = weights(si);
        Vec3f wi = cos_theta_i > 0.f ? wi_in : -wi_in, wo = cos_theta_i > 0.f ? wo_in : -wo_in;
        float cos_theta_o = Frame::cos_theta(wo);
        bool reflect = cos_theta_o > 0.f, refract = cos_theta_o < 0.f;
        LobeProbs p = lobe_probs(w);

        float result = 0.f;
        if (m_spec_trans.enabled) {
            Vec3f wo_r(wo.x, wo.y, std::abs(wo.z));
            Vec3f wh = normalize(wi + wo_r);
            // |d wh / d wo| of a reflection, with the mirrored wo [Walter et al. 2007, eq. 14].
            float dwh_dwo = std::abs(1.f / (4.f * dot(wo_r, wh)));
            if (reflect && mac_mic_compatible(wh, wi, wo, wi.z, true)) {
                auto [ax, ay] = dist_params(w.anisotropic, w.roughness, m_anisotropic.enabled);
                result += p.spec_reflect * MicrofacetDistribution(MicrofacetType::GGX, ax, ay).pdf(wi, wh) * dwh_dwo;
            }
            if (refract && mac_mic_compatible(wh, wi, wo, wi.z, false)) {
                auto [ax, ay] = dist_params(w.anisotropic, scaled_roughness(w), m_anisotropic.enabled);
                result += p.spec_trans * MicrofacetDistribution(MicrofacetType::GGX, ax, ay).pdf(wi, wh) * dwh_dwo;
            }
        }
        if (reflect) result += p.diffuse_reflect * InvPi * cos_theta_o;
        if (m_diff_trans.enabled && refract) result += p.diffuse_trans * InvPi * -cos_theta_o;
        return result;
    }

    /// Selection-probability-weighted mean of the lobes' GGX alphas (diffuse: 1).
    float roughness(const SurfaceInteraction &si) const override {
        Weights w = weights(si);
        LobeProbs p = lobe_probs(w);
        auto [ax, ay] = dist_params(w.anisotropic, w.roughness, m_anisotropic.enabled);
        auto [sx, sy] = dist_params(w.anisotropic, scaled_roughness(w), m_anisotropic.enabled);
        return p.diffuse_reflect + p.diffuse_trans + p.spec_reflect * std::sqrt(ax * ay) +
               p.spec_trans * std::sqrt(sx * sy);
    }

private:
    struct Weights {
        float anisotropic, roughness, spec_trans, eta;
        float diff_trans; ///< the diff_trans parameter halved: its range is [0, 2]
    };
    Weights weights(const SurfaceInteraction &si) const {
        Weights w;
        w.anisotropic = m_anisotropic.eval_1(si);
        w.roughness = m_roughness->eval_1(si);
        w.spec_trans = m_spec_trans.eval_1(si);
        w.eta = m_eta->eval_1(si);
        w.diff_trans = m_diff_trans.eval_1(si) / 2.f;
        return w;
    }

    /// Roughness of the transmission lobe, scaled by IOR [Burley 2015, fig. 15].
    static float scaled_roughness(const Weights &w) { return (0.65f * w.eta - 0.35f) * w.roughness; }

    /// Normalised lobe-selection probabilities (Mitsuba's strategy): the specular
    /// lobes share spec_trans equally, the diffuse lobes share the rest by diff_trans.
    struct LobeProbs {
        float spec_reflect = 0, spec_trans = 0, diffuse_reflect = 0, diffuse_trans = 0;
    };
    LobeProbs lobe_probs(const Weights &w) const {
        LobeProbs p;
        if (m_spec_trans.enabled) {
            p.spec_reflect = w.spec_trans * m_spec_refl_srate / 2.f;
            p.spec_trans = w.spec_trans * m_spec_trans_srate / 2.f;
        }
        p.diffuse_reflect = m_diff_refl_srate * (1.f - w.spec_trans) * (1.f - w.diff_trans);
        if (m_diff_trans.enabled) p.diffuse_trans = m_diff_trans_srate * (1.f - w.spec_trans) * w.diff_trans;
        float total = p.spec_reflect + p.spec_trans + p.diffuse_reflect + p.diffuse_trans;
        if (!(total > 0.f)) return LobeProbs{}; // every sampling rate zeroed: nothing to sample
        float rcp_total = 1.f / total;
        p.spec_reflect *= rcp_total;
        p.spec_trans *= rcp_total;
        p.diffuse_reflect *= rcp_total;
        p.diffuse_trans *= rcp_total;
        return p;
    }

    std::shared_ptr<Texture> m_base_color, m_roughness, m_eta;
    LobeParam m_anisotropic, m_spec_trans, m_sheen, m_sheen_tint, m_flatness, m_spec_tint, m_diff_trans;
    float m_spec_refl_srate, m_spec_trans_srate, m_diff_trans_srate, m_diff_refl_srate;
};

MVPT_REGISTER_PLUGIN("bsdf", "principledthin", [](const Properties &p, const LoadContext &) {
    return std::make_shared<PrincipledThinBsdf>(p);
});

} // namespace mvpt
