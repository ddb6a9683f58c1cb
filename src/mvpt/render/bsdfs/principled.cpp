// Mitsuba 3's `principled` BSDF: the Disney principled model with diffuse,
// retro-reflection, fake subsurface (flatness), sheen, GGX specular reflection
// and transmission (spec_trans), metallic and a GTR1 clearcoat lobe
// [Burley 2012; Burley 2015]. Formulas, lobe masks and the lobe-selection
// probabilities follow Mitsuba 3.9 (src/bsdfs/principled.cpp), so that
// eval / pdf agree with it value for value.
#include "../../core/warp.h"
#include "../../core/plugin.h"
#include "../bsdf.h"
#include "../fresnel.h"
#include "../microfacet.h"
#include "joint_lobes.h"
#include "principled_helpers.h"

namespace mvpt {

using namespace principled;

class PrincipledBsdf final : public JointLobesBsdf<PrincipledBsdf> {
public:
    explicit PrincipledBsdf(const Properties &props) {
        m_base_color = get_texture(props, "base_color", 0.5f);
        m_roughness = get_texture(props, "roughness", 0.5f);
        m_anisotropic = LobeParam(props, "anisotropic", 0.f);
        m_spec_trans = LobeParam(props, "spec_trans", 0.f);
        m_sheen = LobeParam(props, "sheen", 0.f);
        m_sheen_tint = LobeParam(props, "sheen_tint", 0.f);
        m_flatness = LobeParam(props, "flatness", 0.f);
        m_spec_tint = LobeParam(props, "spec_tint", 0.f);
        m_metallic = LobeParam(props, "metallic", 0.f);
        m_clearcoat = LobeParam(props, "clearcoat", 0.f);
        m_clearcoat_gloss = get_texture(props, "clearcoat_gloss", 0.f);
        m_spec_srate = props.get_float("main_specular_sampling_rate", 1.f);
        m_clearcoat_srate = props.get_float("clearcoat_sampling_rate", 1.f);
        m_diff_refl_srate = props.get_float("diffuse_reflectance_sampling_rate", 1.f);
        for (const char *rate : {"main_specular_sampling_rate", "clearcoat_sampling_rate",
                                 "diffuse_reflectance_sampling_rate"})
            if (props.get_float(rate, 1.f) < 0.f) props.fail(rate, std::string("'") + rate + "' must be >= 0");

        // `eta` and `specular` describe the same thing; only one may be given.
        if (props.has("eta") && props.has("specular"))
            props.fail("specular", "principled: give either 'eta' or 'specular', not both");
        if (props.has("eta")) {
            m_eta = props.get_float("eta");
            if (!(m_eta > 0.f)) props.fail("eta", "principled: 'eta' must be > 0");
            if (m_spec_trans.enabled && m_eta == 1.f) m_eta = 1.001f; // eta = 1 cannot refract
        } else {
            float specular = props.get_float("specular", 0.5f);
            if (!(specular >= 0.f && 0.08f * specular < 1.f))
                props.fail("specular", "principled: 'specular' must be in [0, 12.5)");
            if (m_spec_trans.enabled && specular == 0.f) specular = 1e-3f;
            // Inverse of specular = 12.5 ((eta - 1) / (eta + 1))^2 [Burley 2015, §5.1].
            m_eta = 2.f / (1.f - std::sqrt(0.08f * specular)) - 1.f;
        }

        m_flags = BsdfDiffuseReflection | BsdfGlossyReflection;
        if (m_spec_trans.enabled) m_flags |= BsdfGlossyTransmission;
    }

    std::pair<BsdfSample, Spectrum> sample(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, float u1,
                                           Vec2f u2) const override {
        BsdfSample bs;
        float cos_theta_i = Frame::cos_theta(wi);
        if (cos_theta_i == 0.f) return {bs, {}};
        const Params q = params(si);
        const Weights &w = q.w;
        bool front_side = cos_theta_i > 0.f;
        // From inside only the specular lobes exist; without transmission nothing.
        if (!front_side && !(w.bsdf > 0.f)) return {bs, {}};

        auto [ax, ay] = dist_params(w.anisotropic, w.roughness, m_anisotropic.enabled);
        Vec3f m_spec = sample_ggx_visible(front_side ? wi : -wi, ax, ay, u2);
        FresnelDielectric fr = fresnel_dielectric(dot(wi, m_spec), m_eta);
        LobeProbs p = lobe_probs(front_side, fr.F, w);

        // Lobe selection in the order diffuse, clearcoat, transmission, reflection.
        if (u1 < p.diffuse) {
            bs.wo = warp::square_to_cosine_hemisphere(u2);
            bs.sampled_type = BsdfDiffuseReflection;
            if (cos_theta_i * Frame::cos_theta(bs.wo) <= 0.f) return {bs, {}};
        } else if (m_clearcoat.enabled && u1 < p.diffuse + p.clearcoat) {
            Gtr1 cc_distr(q.cc_alpha);
            Vec3f m_cc = cc_distr.sample(u2);
            bs.wo = reflect(wi, m_cc);
            bs.sampled_type = BsdfGlossyReflection;
            if (!mac_mic_compatible(m_cc, wi, bs.wo, cos_theta_i, true) ||
                cos_theta_i * Frame::cos_theta(bs.wo) <= 0.f)
                return {bs, {}};
        } else if (m_spec_trans.enabled && u1 < p.diffuse + p.clearcoat + p.spec_trans) {
            bs.wo = refract(wi, m_spec, fr.cos_theta_t, fr.eta_ti);
            bs.sampled_type = BsdfGlossyTransmission;
            bs.eta = fr.eta_it;
            if (!mac_mic_compatible(m_spec, wi, bs.wo, cos_theta_i, false) ||
                cos_theta_i * Frame::cos_theta(bs.wo) >= 0.f)
                return {bs, {}};
        } else {
            bs.wo = reflect(wi, m_spec);
            bs.sampled_type = BsdfGlossyReflection;
            if (!mac_mic_compatible(m_spec, wi, bs.wo, cos_theta_i, true) ||
                cos_theta_i * Frame::cos_theta(bs.wo) <= 0.f)
                return {bs, {}};
        }

        Color3f value;
        lobes(q, ctx, wi, bs.wo, &value, &bs.pdf);
        if (!(bs.pdf > 0.f)) return {bs, {}};
        return {bs, value / bs.pdf};
    }

    /// Selection-probability-weighted mean of the lobes' GGX alphas at normal
    /// incidence (diffuse counts as alpha 1; GTR1's alpha is used as is).
    float roughness(const SurfaceInteraction &si) const override {
        Weights w = weights(si);
        auto [ax, ay] = dist_params(w.anisotropic, w.roughness, m_anisotropic.enabled);
        float F0 = fresnel_dielectric(1.f, m_eta).F;
        LobeProbs p = lobe_probs(true, F0, w);
        float cc_alpha = m_clearcoat.enabled ? clearcoat_alpha(si) : 1.f;
        return p.diffuse + p.clearcoat * cc_alpha + (p.spec_reflect + p.spec_trans) * std::sqrt(ax * ay);
    }

private:
    friend class JointLobesBsdf<PrincipledBsdf>;
    /// Lobe weights needed by sample, eval and pdf.
    struct Weights {
        float anisotropic, roughness, spec_trans, metallic, clearcoat;
        float brdf; ///< weight of the opaque (diffuse) part: (1 - metallic)(1 - spec_trans)
        float bsdf; ///< weight of the transmissive part: (1 - metallic) spec_trans
    };

    /// The textures' values at a hit: what the lobes read.
    struct Params {
        Weights w;
        Color3f base_color;
        float flatness, sheen, sheen_tint, spec_tint, cc_alpha;
    };
    Params params(const SurfaceInteraction &si) const {
        Params q;
        q.w = weights(si);
        q.base_color = m_base_color->eval(si);
        q.flatness = m_flatness.eval_1(si), q.sheen = m_sheen.eval_1(si);
        q.sheen_tint = m_sheen_tint.eval_1(si), q.spec_tint = m_spec_tint.eval_1(si);
        q.cc_alpha = m_clearcoat.enabled ? clearcoat_alpha(si) : 1.f;
        return q;
    }

    /// The value f |cos wo| (into *value) and the density of `sample` (into *pdf) of (wi, wo),
    /// either may be null; they share the half vector, the Fresnel term and the distribution.
    void lobes(const Params &q, const BsdfContext &ctx, Vec3f wi, Vec3f wo, Color3f *value, float *pdf) const {
        if (value) *value = Color3f(0.f);
        if (pdf) *pdf = 0.f;
        float cos_theta_i = Frame::cos_theta(wi);
        if (cos_theta_i == 0.f) return;
        const Weights &w = q.w;
        float cos_theta_o = Frame::cos_theta(wo);
        bool reflect = cos_theta_i * cos_theta_o > 0.f, refract = cos_theta_i * cos_theta_o < 0.f;
        bool front_side = cos_theta_i > 0.f;
        float eta_path = front_side ? m_eta : 1.f / m_eta, inv_eta_path = front_side ? 1.f / m_eta : m_eta;

        auto [ax, ay] = dist_params(w.anisotropic, w.roughness, m_anisotropic.enabled);
        MicrofacetDistribution spec_distr(MicrofacetType::GGX, ax, ay);
        Vec3f wh = half_vector(wi, wo, reflect, eta_path);
        float F = fresnel_dielectric(dot(wi, wh), m_eta).F;
        bool compat_reflect = mac_mic_compatible(wh, wi, wo, cos_theta_i, true);
        bool compat_refract = mac_mic_compatible(wh, wi, wo, cos_theta_i, false);
        if (value) *value = lobe_values(q, ctx, wi, wo, wh, spec_distr, F, compat_reflect, compat_refract, eta_path,
                                         inv_eta_path);
        if (!pdf) return;

        // |d wh / d wo| for reflection [Walter et al. 2007, eq. 14] and refraction (eq. 17).
        LobeProbs p = lobe_probs(front_side, F, w);
        float dot_i = dot(wi, wh), dot_o = dot(wo, wh);
        float dwh_dwo;
        if (m_spec_trans.enabled && !reflect) {
            float denom = dot_i + eta_path * dot_o;
            dwh_dwo = std::abs(eta_path * eta_path * dot_o / (denom * denom));
        } else {
            dwh_dwo = std::abs(1.f / (4.f * dot_o));
        }
        Vec3f wi_up = front_side ? wi : -wi;
        float result = 0.f;
        bool reflect_compat = reflect && compat_reflect;
        if (reflect_compat) result += p.spec_reflect * spec_distr.pdf(wi_up, wh) * dwh_dwo;
        if (reflect) result += p.diffuse * InvPi * cos_theta_o;
        if (m_spec_trans.enabled && refract && compat_refract)
            result += p.spec_trans * spec_distr.pdf(wi_up, wh) * dwh_dwo;
        if (m_clearcoat.enabled && reflect_compat) result += p.clearcoat * Gtr1(q.cc_alpha).pdf(wh) * dwh_dwo;
        *pdf = result;
    }

    /// The lobes' values at (wi, wo) with half vector wh and Fresnel term F.
    Color3f lobe_values(const Params &q, const BsdfContext &ctx, Vec3f wi, Vec3f wo, Vec3f wh,
                        const MicrofacetDistribution &spec_distr, float F, bool compat_reflect, bool compat_refract,
                        float eta_path, float inv_eta_path) const {
        const Weights &w = q.w;
        float cos_theta_i = Frame::cos_theta(wi), cos_theta_o = Frame::cos_theta(wo);
        bool reflect = cos_theta_i * cos_theta_o > 0.f, refract = cos_theta_i * cos_theta_o < 0.f;
        bool front_side = cos_theta_i > 0.f;
        bool spec_reflect_active = reflect && compat_reflect && F > 0.f;
        bool clearcoat_active = m_clearcoat.enabled && w.clearcoat > 0.f && reflect && compat_reflect && front_side;
        bool spec_trans_active = m_spec_trans.enabled && w.bsdf > 0.f && refract && compat_refract && F < 1.f;
        bool diffuse_active = w.brdf > 0.f && reflect && front_side;
        bool sheen_active = m_sheen.enabled && q.sheen > 0.f && reflect && 1.f - w.metallic > 0.f && front_side;

        float D = spec_distr.eval(wh), G = spec_distr.G(wi, wo, wh);
        Color3f value(0.f);

        // Main specular reflection [Walter et al. 2007, eq. 20] with the principled Fresnel blend.
        if (spec_reflect_active) {
            float lum = m_spec_tint.enabled ? luminance(q.base_color) : 1.f;
            Color3f F_p = principled_fresnel(F, w.metallic, q.spec_tint, q.base_color, lum, dot(wi, wh), front_side,
                                             w.bsdf, m_eta, m_metallic.enabled, m_spec_tint.enabled);
            value += F_p * (D * G / (4.f * std::abs(cos_theta_i)));
        }

        // Main specular transmission [Walter et al. 2007, eq. 21], tinted by sqrt(base_color).
        if (spec_trans_active) {
            float scale = ctx.mode == TransportMode::Radiance ? inv_eta_path * inv_eta_path : 1.f;
            float dot_i = dot(wi, wh), dot_o = dot(wo, wh), denom = dot_i + eta_path * dot_o;
            float t = std::abs(scale * (1.f - F) * D * G * eta_path * eta_path * dot_i * dot_o /
                               (cos_theta_i * denom * denom));
            value += csqrt(q.base_color) * (w.bsdf * t);
        }

        if (clearcoat_active) value += clearcoat_value(q, wi, wo, wh);
        if (diffuse_active) add_diffuse(value, q, sheen_active ? q.sheen : 0.f, wi, wo, wh);
        return value;
    }

    /// Clearcoat: GTR1 distribution, Schlick Fresnel with R0 = 0.04, fixed GGX alpha 0.25 masking.
    /// (Mitsuba's form: F D G |cos_o| without the 1 / (4 cos_i cos_o) microfacet factor.)
    Color3f clearcoat_value(const Params &q, Vec3f wi, Vec3f wo, Vec3f wh) const {
        float Fcc = schlick_fresnel(0.04f, dot(wi, wh), m_eta);
        float Dcc = Gtr1(q.cc_alpha).eval(wh);
        float Gcc = smith_ggx1(wi, wh, 0.25f) * smith_ggx1(wo, wh, 0.25f);
        return Color3f(q.w.clearcoat * 0.25f * Fcc * Dcc * Gcc * std::abs(Frame::cos_theta(wo)));
    }

    /// Diffuse with retro-reflection, fake subsurface and sheen [Burley 2015, §5.3], added to
    /// `value` (sheen 0: none).
    void add_diffuse(Color3f &value, const Params &q, float sheen, Vec3f wi, Vec3f wo, Vec3f wh) const {
        const Weights &w = q.w;
        float abs_cos_o = std::abs(Frame::cos_theta(wo)), cos_theta_d = dot(wh, wo);
        float f = disney_diffuse(std::abs(Frame::cos_theta(wi)), abs_cos_o, cos_theta_d, w.roughness, q.flatness,
                                 m_flatness.enabled);
        value += q.base_color * (w.brdf * abs_cos_o * InvPi * f);
        if (sheen > 0.f) {
            Color3f c_sheen = sheen_color(q.base_color, q.sheen_tint, m_sheen_tint.enabled);
            value += c_sheen * (sheen * (1.f - w.metallic) * schlick_weight(std::abs(cos_theta_d)) * abs_cos_o);
        }
    }

    Weights weights(const SurfaceInteraction &si) const {
        Weights w;
        w.anisotropic = m_anisotropic.eval_1(si);
        w.roughness = m_roughness->eval_1(si);
        w.spec_trans = m_spec_trans.eval_1(si);
        w.metallic = m_metallic.eval_1(si);
        w.clearcoat = m_clearcoat.eval_1(si);
        w.brdf = (1.f - w.metallic) * (1.f - w.spec_trans);
        w.bsdf = (1.f - w.metallic) * w.spec_trans;
        return w;
    }

    /// Normalised lobe-selection probabilities; from inside only the two specular
    /// lobes, in the ratio F : 1 - F. Clearcoat gets 1/4 of its weight, matching
    /// its 0.25 energy scale (Mitsuba's strategy).
    struct LobeProbs {
        float diffuse = 0, clearcoat = 0, spec_trans = 0, spec_reflect = 0;
    };
    LobeProbs lobe_probs(bool front_side, float F, const Weights &w) const {
        LobeProbs p;
        if (front_side) {
            p.spec_reflect = m_spec_srate * (1.f - w.bsdf * (1.f - F));
            p.spec_trans = m_spec_trans.enabled ? m_spec_srate * w.bsdf * (1.f - F) : 0.f;
            p.clearcoat = m_clearcoat.enabled ? 0.25f * w.clearcoat * m_clearcoat_srate : 0.f;
            p.diffuse = w.brdf * m_diff_refl_srate;
        } else {
            p.spec_reflect = F;
            p.spec_trans = m_spec_trans.enabled ? 1.f - F : 0.f;
        }
        float total = p.spec_reflect + p.spec_trans + p.clearcoat + p.diffuse;
        if (!(total > 0.f)) return LobeProbs{}; // every sampling rate zeroed: nothing to sample
        float rcp_total = 1.f / total;
        p.spec_reflect *= rcp_total;
        p.spec_trans *= rcp_total;
        p.clearcoat *= rcp_total;
        p.diffuse *= rcp_total;
        return p;
    }

    /// Clearcoat GTR1 alpha, mapped from clearcoat_gloss to [0.1, 0.001].
    float clearcoat_alpha(const SurfaceInteraction &si) const { return lerp(m_clearcoat_gloss->eval_1(si), 0.1f, 0.001f); }

    /// Generalised half vector (reflection or refraction), oriented to +z.
    static Vec3f half_vector(Vec3f wi, Vec3f wo, bool reflect, float eta_path) {
        Vec3f wh = normalize(wi + wo * (reflect ? 1.f : eta_path));
        return std::signbit(wh.z) ? -wh : wh;
    }

    std::shared_ptr<Texture> m_base_color, m_roughness, m_clearcoat_gloss;
    LobeParam m_anisotropic, m_spec_trans, m_sheen, m_sheen_tint, m_flatness, m_spec_tint, m_metallic, m_clearcoat;
    float m_eta;
    float m_spec_srate, m_clearcoat_srate, m_diff_refl_srate;
};

MVPT_REGISTER_PLUGIN("bsdf", "principled", [](const Properties &p, const LoadContext &) {
    return std::make_shared<PrincipledBsdf>(p);
});

} // namespace mvpt
