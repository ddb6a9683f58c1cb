// Rough conductor: Cook-Torrance microfacet reflection with the conductor
// Fresnel term [Walter et al. 2007] (Mitsuba 3's `roughconductor`). One-sided.
#include "../../scene/plugin.h"
#include "../bsdf.h"
#include "../fresnel.h"
#include "../texture.h"
#include "conductor_ior.h"
#include "microfacet_params.h"

namespace mvpt {

class RoughConductor final : public Bsdf {
public:
    explicit RoughConductor(const Properties &props) {
        m_ior = read_conductor_ior(props);
        m_distr = read_microfacet_params(props);
        if (props.has_texture("specular_reflectance"))
            m_specular_reflectance = props.get_texture("specular_reflectance", 1.f);
        m_flags = BsdfGlossyReflection;
        // Constant and isotropic with visible-normal sampling: the wavefront's vector kernels.
        auto constant = [](const std::shared_ptr<Texture> &t) { return !t || t->is_constant(); };
        if (constant(m_ior.eta) && constant(m_ior.k) && constant(m_specular_reflectance) && constant(m_distr.alpha_u) &&
            !m_distr.anisotropic() && m_distr.sample_visible) {
            const Vec2f uv(0.f, 0.f);
            RoughConductorInfo &info = m_rough_conductor;
            info = RoughConductorInfo{};
            info.beckmann = m_distr.type == MicrofacetType::Beckmann;
            info.alpha = MicrofacetDistribution(m_distr.type, m_distr.alpha_u->eval_1(uv), m_distr.alpha_v->eval_1(uv))
                             .alpha_u();
            info.eta = m_ior.eta->eval(uv);
            info.k = m_ior.k->eval(uv);
            if (m_specular_reflectance) info.specular = m_specular_reflectance->eval(uv);
            m_is_rough_conductor = true;
        }
    }

    std::pair<BsdfSample, Spectrum> sample(const BsdfContext &, const SurfaceInteraction &si, Vec3f wi, float,
                                           Vec2f u2) const override {
        // Filled in place (one named result): returning a copied pair is slower.
        std::pair<BsdfSample, Spectrum> result;
        BsdfSample &bs = result.first;
        float cos_theta_i = Frame::cos_theta(wi);
        if (cos_theta_i <= 0.f) return result;
        MicrofacetDistribution distr = m_distr.at(si);
        float pdf_m = 0.f;
        Vec3f m = distr.sample(wi, u2, &pdf_m);
        bs.wo = reflect(wi, m);
        bs.sampled_type = BsdfGlossyReflection;
        if (pdf_m == 0.f || Frame::cos_theta(bs.wo) <= 0.f) return result;
        // Jacobian of the half-vector mapping dm/dwo = 1 / (4 |wo.m|) [Walter et al. 2007, eq. 14].
        bs.pdf = pdf_m / (4.f * dot(bs.wo, m));
        float weight;
        if (distr.sample_visible()) weight = distr.smith_g1(bs.wo, m);
        else weight = distr.G(wi, bs.wo, m) * dot(wi, m) / (cos_theta_i * Frame::cos_theta(m));
        Spectrum F = fresnel_conductor(dot(wi, m), m_ior.eta->eval(si.uv), m_ior.k->eval(si.uv));
        Spectrum &w = result.second;
        w = F * weight;
        if (m_specular_reflectance) w *= m_specular_reflectance->eval(si.uv);
        return result;
    }

    Spectrum eval(const BsdfContext &, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const override {
        float cos_theta_i = Frame::cos_theta(wi), cos_theta_o = Frame::cos_theta(wo);
        if (cos_theta_i <= 0.f || cos_theta_o <= 0.f) return {};
        Vec3f h = normalize(wi + wo);
        MicrofacetDistribution distr = m_distr.at(si);
        float D = distr.eval(h);
        if (D == 0.f) return {};
        // f cos(theta_o) = F D G / (4 cos(theta_i)) [Walter et al. 2007, eq. 20].
        float value = D * distr.G(wi, wo, h) / (4.f * cos_theta_i);
        Spectrum F = fresnel_conductor(dot(wi, h), m_ior.eta->eval(si.uv), m_ior.k->eval(si.uv));
        Spectrum r = F * value;
        if (m_specular_reflectance) r *= m_specular_reflectance->eval(si.uv);
        return r;
    }

    float pdf(const BsdfContext &, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const override {
        float cos_theta_i = Frame::cos_theta(wi), cos_theta_o = Frame::cos_theta(wo);
        Vec3f m = normalize(wi + wo);
        if (cos_theta_i <= 0.f || cos_theta_o <= 0.f || dot(wi, m) <= 0.f || dot(wo, m) <= 0.f) return 0.f;
        MicrofacetDistribution distr = m_distr.at(si);
        if (distr.sample_visible()) return distr.eval(m) * distr.smith_g1(wi, m) / (4.f * cos_theta_i);
        return distr.pdf(wi, m) / (4.f * dot(wo, m));
    }

    float roughness(const SurfaceInteraction &si) const override { return m_distr.mean_alpha(si); }

private:
    ConductorIor m_ior;
    MicrofacetParams m_distr;
    std::shared_ptr<Texture> m_specular_reflectance;
};

MVPT_REGISTER_PLUGIN("bsdf", "roughconductor", [](const Properties &p, const LoadContext &) {
    return std::make_shared<RoughConductor>(p);
});

} // namespace mvpt
