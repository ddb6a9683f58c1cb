// Rough dielectric interface: microfacet reflection and refraction
// [Walter et al. 2007, "Microfacet Models for Refraction through Rough
// Surfaces"] (Mitsuba 3's `roughdielectric`). Two-sided.
#include "../../core/plugin.h"
#include "../bsdf.h"
#include "../fresnel.h"
#include "../ior.h"
#include "../texture.h"
#include "joint_lobes.h"
#include "microfacet_params.h"

namespace mvpt {

class RoughDielectric final : public JointLobesBsdf<RoughDielectric> {
public:
    explicit RoughDielectric(const Properties &props) {
        if (props.has_texture("specular_reflectance"))
            m_specular_reflectance = get_texture(props, "specular_reflectance", 1.f);
        if (props.has_texture("specular_transmittance"))
            m_specular_transmittance = get_texture(props, "specular_transmittance", 1.f);
        float int_ior = read_ior(props, "int_ior", "bk7"), ext_ior = read_ior(props, "ext_ior", "air");
        if (int_ior == ext_ior) props.fail("int_ior", "the interior and exterior indices of refraction must differ");
        m_eta = int_ior / ext_ior;
        m_inv_eta = ext_ior / int_ior;
        m_distr = read_microfacet_params(props);
        m_flags = BsdfGlossyReflection | BsdfGlossyTransmission;
    }

    std::pair<BsdfSample, Spectrum> sample(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, float u1,
                                           Vec2f u2) const override {
        BsdfSample bs;
        float cos_theta_i = Frame::cos_theta(wi);
        if (cos_theta_i == 0.f) return {bs, {}};
        MicrofacetDistribution distr = m_distr.at(si);
        MicrofacetDistribution sample_distr = sampling_distribution(distr, cos_theta_i);
        float pdf_m = 0.f;
        Vec3f m = sample_distr.sample(std::copysign(1.f, cos_theta_i) * wi, u2, &pdf_m);
        if (pdf_m == 0.f) return {bs, {}};

        FresnelDielectric fr = fresnel_dielectric(dot(wi, m), m_eta);
        bool reflect_sel = u1 <= fr.F;
        Spectrum weight(1.f);
        float dwh_dwo;
        if (reflect_sel) {
            bs.wo = reflect(wi, m);
            bs.pdf = pdf_m * fr.F;
            bs.sampled_type = BsdfGlossyReflection;
            if (m_specular_reflectance) weight *= m_specular_reflectance->eval(si);
            dwh_dwo = 1.f / (4.f * dot(bs.wo, m)); // [Walter et al. 2007, eq. 14]
        } else {
            bs.wo = refract(wi, m, fr.cos_theta_t, fr.eta_ti);
            bs.pdf = pdf_m * (1.f - fr.F);
            bs.eta = fr.eta_it;
            bs.sampled_type = BsdfGlossyTransmission;
            if (ctx.mode == TransportMode::Radiance) weight *= fr.eta_ti * fr.eta_ti;
            if (m_specular_transmittance) weight *= m_specular_transmittance->eval(si);
            // [Walter et al. 2007, eq. 17]
            dwh_dwo = bs.eta * bs.eta * dot(bs.wo, m) / sqr(dot(wi, m) + bs.eta * dot(bs.wo, m));
        }
        bs.pdf *= std::abs(dwh_dwo);
        if (distr.sample_visible()) {
            weight *= distr.smith_g1(bs.wo, m);
        } else {
            // Sampled from the widened distribution: the weight is f cos / pdf in full
            // (Mitsuba's G-based shortcut would assume the unwidened one). Shadowed samples,
            // and those that left on the wrong side for their lobe, have no weight.
            if (distr.G(wi, bs.wo, m) == 0.f) return {bs, {}};
            Spectrum value;
            float p;
            lobes(params(si), ctx, wi, bs.wo, &value, &p);
            if (!(p > 0.f)) return {bs, {}};
            return {bs, value / p};
        }
        return {bs, weight};
    }

    float roughness(const SurfaceInteraction &si) const override { return m_distr.mean_alpha(si); }

private:
    friend class JointLobesBsdf<RoughDielectric>;
    /// The textures' values at a hit.
    struct Params {
        MicrofacetDistribution distr;
        Spectrum reflectance{1.f}, transmittance{1.f};
    };
    Params params(const SurfaceInteraction &si) const {
        Params q{m_distr.at(si)};
        if (m_specular_reflectance) q.reflectance = m_specular_reflectance->eval(si);
        if (m_specular_transmittance) q.transmittance = m_specular_transmittance->eval(si);
        return q;
    }

    /// f |cos wo| (into *value) and the density of `sample` (into *pdf) of (wi, wo), either may
    /// be null; they share the generalised half vector m [Walter et al. 2007, eq. 16] and F.
    void lobes(const Params &q, const BsdfContext &ctx, Vec3f wi, Vec3f wo, Spectrum *value, float *pdf) const {
        if (value) *value = Spectrum();
        if (pdf) *pdf = 0.f;
        float cos_theta_i = Frame::cos_theta(wi), cos_theta_o = Frame::cos_theta(wo);
        if (cos_theta_i == 0.f) return;
        bool is_reflection = cos_theta_i * cos_theta_o > 0.f;
        float eta = cos_theta_i > 0.f ? m_eta : m_inv_eta, inv_eta = cos_theta_i > 0.f ? m_inv_eta : m_eta;
        // Generalised half-vector, oriented towards the macro-surface normal.
        Vec3f m = normalize(wi + wo * (is_reflection ? 1.f : eta));
        m = m * std::copysign(1.f, Frame::cos_theta(m));
        float F = fresnel_dielectric(dot(wi, m), m_eta).F;
        if (value) {
            float D = q.distr.eval(m), G = q.distr.G(wi, wo, m);
            if (is_reflection) {
                *value = Spectrum(F * D * G / (4.f * std::abs(cos_theta_i)));
                if (m_specular_reflectance) *value *= q.reflectance;
            } else {
                // [Walter et al. 2007, eq. 21], with the radiance scale 1/eta^2.
                float scale = ctx.mode == TransportMode::Radiance ? inv_eta * inv_eta : 1.f;
                float dot_i = dot(wi, m), dot_o = dot(wo, m);
                *value = Spectrum(std::abs(scale * (1.f - F) * D * G * eta * eta * dot_i * dot_o /
                                           (cos_theta_i * sqr(dot_i + eta * dot_o))));
                if (m_specular_transmittance) *value *= q.transmittance;
            }
        }
        // Micro- and macro-surface must agree on the sides (as smith_g1 enforces in the value).
        if (!pdf || !(dot(wi, m) * cos_theta_i > 0.f && dot(wo, m) * cos_theta_o > 0.f)) return;
        float dwh_dwo = is_reflection ? 1.f / (4.f * dot(wo, m))
                                      : eta * eta * dot(wo, m) / sqr(dot(wi, m) + eta * dot(wo, m));
        MicrofacetDistribution sample_distr = sampling_distribution(q.distr, cos_theta_i);
        float prob = sample_distr.pdf(std::copysign(1.f, cos_theta_i) * wi, m);
        prob *= is_reflection ? F : 1.f - F;
        *pdf = prob * std::abs(dwh_dwo);
    }

    /// Without visible-normal sampling, sample a slightly wider lobe [Walter et al. 2007, §5.3].
    static MicrofacetDistribution sampling_distribution(MicrofacetDistribution d, float cos_theta_i) {
        if (!d.sample_visible()) d.scale_alpha(1.2f - 0.2f * std::sqrt(std::abs(cos_theta_i)));
        return d;
    }

    float m_eta, m_inv_eta;
    MicrofacetParams m_distr;
    std::shared_ptr<Texture> m_specular_reflectance, m_specular_transmittance;
};

MVPT_REGISTER_PLUGIN("bsdf", "roughdielectric", [](const Properties &p, const LoadContext &) {
    return std::make_shared<RoughDielectric>(p);
});

} // namespace mvpt
