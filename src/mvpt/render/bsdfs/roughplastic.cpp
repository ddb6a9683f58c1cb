// Rough plastic: a diffuse base under a rough dielectric coating (Mitsuba 3's
// `roughplastic`): microfacet reflection plus a diffuse term attenuated by the
// coating's precomputed rough transmittance and internal reflectance
// [Weidlich and Wilkie 2007; Mitsuba's tabulation]. One-sided, isotropic.
#include "../../core/quadrature.h"
#include "../../core/warp.h"
#include "../../scene/plugin.h"
#include "../bsdf.h"
#include "../fresnel.h"
#include "../ior.h"
#include "../microfacet.h"
#include "../texture.h"

#include <array>

namespace mvpt {

namespace {

/// Resolution of the tabulated external transmittance over cos(theta) (Mitsuba's value).
constexpr int TransmittanceRes = 64;

/// Albedo of microfacet reflection (`transmission` false) or transmission
/// through a dielectric with relative IOR `eta`, seen from `wi`: the visible-normal
/// estimator G1(wo, m) F (or 1 - F) integrated over the unit square with a
/// tensor Gauss-Legendre rule (32^2 nodes for eta > 1, 128^2 otherwise), as Mitsuba.
float microfacet_albedo(const MicrofacetDistribution &distr, Vec3f wi, float eta, bool transmission) {
    std::vector<float> nodes, weights;
    gauss_legendre(eta > 1.f ? 32 : 128, nodes, weights);
    double sum = 0.0;
    for (size_t j = 0; j < nodes.size(); ++j)
        for (size_t i = 0; i < nodes.size(); ++i) {
            Vec2f u(0.5f * nodes[i] + 0.5f, 0.5f * nodes[j] + 0.5f);
            float pdf_m;
            Vec3f m = distr.sample(wi, u, &pdf_m);
            FresnelDielectric fr = fresnel_dielectric(dot(wi, m), eta);
            float value;
            if (transmission) {
                Vec3f wo = refract(wi, m, fr.cos_theta_t, fr.eta_ti);
                value = wo.z * wi.z >= 0.f ? 0.f : distr.smith_g1(wo, m) * (1.f - fr.F);
            } else {
                Vec3f wo = reflect(wi, m);
                value = (wo.z <= 0.f || wi.z <= 0.f) ? 0.f : distr.smith_g1(wo, m) * fr.F;
            }
            sum += double(value) * weights[i] * weights[j] * 0.25;
        }
    return float(sum);
}

} // namespace

class RoughPlastic final : public Bsdf {
public:
    explicit RoughPlastic(const Properties &props) {
        float int_ior = read_ior(props, "int_ior", "polypropylene"), ext_ior = read_ior(props, "ext_ior", "air");
        if (int_ior == ext_ior) props.fail("int_ior", "the interior and exterior indices of refraction must differ");
        m_eta = int_ior / ext_ior;
        m_diffuse_reflectance = props.get_texture("diffuse_reflectance", 0.5f);
        if (props.has_texture("specular_reflectance"))
            m_specular_reflectance = props.get_texture("specular_reflectance", 1.f);
        m_nonlinear = props.get_bool("nonlinear", false);
        read_roughness(props);
        m_flags = BsdfGlossyReflection | BsdfDiffuseReflection;

        m_inv_eta_2 = 1.f / (m_eta * m_eta);
        float d_mean = m_diffuse_reflectance->mean().mean();
        float s_mean = m_specular_reflectance ? m_specular_reflectance->mean().mean() : 1.f;
        m_specular_sampling_weight = s_mean / (d_mean + s_mean);

        // Tabulate the coating's transmittance t(mu) and its internal diffuse reflectance,
        // always with visible-normal sampling as in Mitsuba.
        MicrofacetDistribution distr(m_type, m_alpha, m_alpha, true);
        double internal = 0.0;
        for (int i = 0; i < TransmittanceRes; ++i) {
            float mu = std::max(1e-6f, float(i) / float(TransmittanceRes - 1));
            Vec3f wi(std::sqrt(1.f - mu * mu), 0.f, mu);
            m_external_transmittance[i] = microfacet_albedo(distr, wi, m_eta, true);
            internal += double(microfacet_albedo(distr, wi, 1.f / m_eta, false)) * mu;
        }
        m_internal_reflectance = float(internal / TransmittanceRes) * 2.f;
    }

    std::pair<BsdfSample, Spectrum> sample(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, float u1,
                                           Vec2f u2) const override {
        BsdfSample bs;
        float cos_theta_i = Frame::cos_theta(wi);
        if (cos_theta_i <= 0.f) return {bs, {}};
        if (u1 < specular_probability(cos_theta_i)) {
            float pdf_m;
            Vec3f m = distribution().sample(wi, u2, &pdf_m);
            bs.wo = reflect(wi, m);
            bs.sampled_type = BsdfGlossyReflection;
        } else {
            bs.wo = warp::square_to_cosine_hemisphere(u2);
            bs.sampled_type = BsdfDiffuseReflection;
        }
        bs.pdf = pdf(ctx, si, wi, bs.wo);
        if (!(bs.pdf > 0.f)) return {bs, {}};
        return {bs, eval(ctx, si, wi, bs.wo) / bs.pdf};
    }

    Spectrum eval(const BsdfContext &, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const override {
        float cos_theta_i = Frame::cos_theta(wi), cos_theta_o = Frame::cos_theta(wo);
        if (cos_theta_i <= 0.f || cos_theta_o <= 0.f) return {};
        MicrofacetDistribution distr = distribution();
        Vec3f h = normalize(wo + wi);
        float F = fresnel_dielectric(dot(wi, h), m_eta).F;
        Spectrum value(F * distr.eval(h) * distr.G(wi, wo, h) / (4.f * cos_theta_i));
        if (m_specular_reflectance) value *= m_specular_reflectance->eval(si.uv);

        float t_i = transmittance(cos_theta_i), t_o = transmittance(cos_theta_o);
        Spectrum diff = m_diffuse_reflectance->eval(si.uv);
        Spectrum denom = m_nonlinear ? Spectrum(1.f) - diff * m_internal_reflectance
                                     : Spectrum(1.f - m_internal_reflectance);
        return value + diff / denom * (InvPi * m_inv_eta_2 * cos_theta_o * t_i * t_o);
    }

    float pdf(const BsdfContext &, const SurfaceInteraction &, Vec3f wi, Vec3f wo) const override {
        float cos_theta_i = Frame::cos_theta(wi), cos_theta_o = Frame::cos_theta(wo);
        if (cos_theta_i <= 0.f || cos_theta_o <= 0.f) return 0.f;
        float prob_specular = specular_probability(cos_theta_i);
        MicrofacetDistribution distr = distribution();
        Vec3f h = normalize(wo + wi);
        float p_spec = distr.sample_visible() ? distr.eval(h) * distr.smith_g1(wi, h) / (4.f * cos_theta_i)
                                              : distr.pdf(wi, h) / (4.f * dot(wo, h));
        return prob_specular * p_spec + (1.f - prob_specular) * warp::square_to_cosine_hemisphere_pdf(wo);
    }

    float roughness(const SurfaceInteraction &) const override { return m_alpha; }

private:
    /// `alpha` (float, default 0.1), or equal `alpha_u`/`alpha_v`; anisotropy is rejected as by Mitsuba.
    void read_roughness(const Properties &props) {
        m_type = MicrofacetType::Beckmann;
        if (props.has("distribution")) {
            std::string d = props.get_string("distribution");
            if (!parse_microfacet_type(d, m_type))
                props.fail("distribution", "invalid distribution \"" + d + "\", must be \"beckmann\" or \"ggx\"");
        }
        m_sample_visible = props.get_bool("sample_visible", true);
        if (props.has("alpha_u") || props.has("alpha_v")) {
            if (!props.has("alpha_u") || !props.has("alpha_v"))
                props.fail(props.has("alpha_u") ? "alpha_u" : "alpha_v",
                           "both 'alpha_u' and 'alpha_v' must be specified");
            if (props.has("alpha")) props.fail("alpha", "specify either 'alpha' or 'alpha_u'/'alpha_v', not both");
            m_alpha = props.get_float("alpha_u");
            if (props.get_float("alpha_v") != m_alpha)
                props.fail("alpha_v", "roughplastic does not support anisotropic roughness");
        } else {
            m_alpha = props.get_float("alpha", 0.1f);
        }
    }
    MicrofacetDistribution distribution() const {
        return MicrofacetDistribution(m_type, m_alpha, m_alpha, m_sample_visible);
    }
    float specular_probability(float cos_theta_i) const {
        float t_i = transmittance(cos_theta_i);
        float ps = (1.f - t_i) * m_specular_sampling_weight, pd = t_i * (1.f - m_specular_sampling_weight);
        return ps / (ps + pd);
    }
    /// Linear interpolation in the transmittance table.
    float transmittance(float cos_theta) const {
        float x = cos_theta * float(TransmittanceRes - 1);
        int idx = std::min(int(x), TransmittanceRes - 2);
        return lerp(x - float(idx), m_external_transmittance[idx], m_external_transmittance[idx + 1]);
    }

    MicrofacetType m_type;
    float m_alpha, m_eta, m_inv_eta_2, m_specular_sampling_weight, m_internal_reflectance;
    bool m_sample_visible, m_nonlinear;
    std::array<float, TransmittanceRes> m_external_transmittance;
    std::shared_ptr<Texture> m_diffuse_reflectance, m_specular_reflectance;
};

MVPT_REGISTER_PLUGIN("bsdf", "roughplastic", [](const Properties &p, const LoadContext &) {
    return std::make_shared<RoughPlastic>(p);
});

} // namespace mvpt
