// Rough conductor: Cook-Torrance microfacet reflection with the conductor
// Fresnel term [Walter et al. 2007] (Mitsuba 3's `roughconductor`). One-sided.
#include "../../core/plugin.h"
#include "../bsdf.h"
#include "../fresnel.h"
#include "../texture.h"
#include "conductor_ior.h"
#include "microfacet_params.h"

#include <tuple>

namespace mvpt {

class RoughConductor final : public Bsdf {
public:
    explicit RoughConductor(const Properties &props) {
        m_ior = read_conductor_ior(props);
        m_distr = read_microfacet_params(props);
        if (props.has_texture("specular_reflectance"))
            m_specular_reflectance = get_texture(props, "specular_reflectance", 1.f);
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
        return lobe<true, false>(at(si), wi, wo).first;
    }

    float pdf(const BsdfContext &, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const override {
        return lobe<false, true>(Local{m_distr.at(si), {}, {}, {}}, wi, wo).second; // no textures but alpha
    }

    std::pair<Spectrum, float> eval_pdf(const BsdfContext &, const SurfaceInteraction &si, Vec3f wi,
                                        Vec3f wo) const override {
        return lobe<true, true>(at(si), wi, wo);
    }

    /// The textures and the distribution once for all the views.
    void eval_pdf_views(const BsdfContext &, const SurfaceInteraction &si, const Vec3f *wi, size_t n, Vec3f wo,
                        Spectrum *f, float *pdf) const override {
        const Local local = at(si);
        for (size_t c = 0; c < n; ++c) std::tie(f[c], pdf[c]) = lobe<true, true>(local, wi[c], wo);
    }

    float roughness(const SurfaceInteraction &si) const override { return m_distr.mean_alpha(si); }

private:
    /// What the lobe needs of the textures at a hit.
    struct Local {
        MicrofacetDistribution distr;
        Spectrum eta, k, specular;
    };
    Local at(const SurfaceInteraction &si) const {
        return {m_distr.at(si), m_ior.eta->eval(si.uv), m_ior.k->eval(si.uv),
                m_specular_reflectance ? m_specular_reflectance->eval(si.uv) : Spectrum(1.f)};
    }

    /// f cos(theta_o) (if `F`) and the density of `sample` (if `P`) at (wi, wo), sharing the half
    /// vector, D and G1(wi).
    template <bool F, bool P> std::pair<Spectrum, float> lobe(const Local &l, Vec3f wi, Vec3f wo) const {
        std::pair<Spectrum, float> out{Spectrum(0.f), 0.f};
        const float cos_theta_i = Frame::cos_theta(wi), cos_theta_o = Frame::cos_theta(wo);
        if (cos_theta_i <= 0.f || cos_theta_o <= 0.f) return out;
        const Vec3f h = normalize(wi + wo);
        const MicrofacetDistribution &distr = l.distr;
        const float D = distr.eval(h);
        const bool visible = distr.sample_visible();
        const float g1_i = F || visible ? distr.smith_g1(wi, h) : 0.f;
        if constexpr (F) {
            if (D != 0.f) {
                // f cos(theta_o) = F D G / (4 cos(theta_i)) [Walter et al. 2007, eq. 20].
                const float value = D * (g1_i * distr.smith_g1(wo, h)) / (4.f * cos_theta_i);
                Spectrum r = fresnel_conductor(dot(wi, h), l.eta, l.k) * value;
                if (m_specular_reflectance) r *= l.specular;
                out.first = r;
            }
        }
        if constexpr (P) {
            if (dot(wi, h) > 0.f && dot(wo, h) > 0.f)
                out.second = visible ? D * g1_i / (4.f * cos_theta_i) : distr.pdf(wi, h) / (4.f * dot(wo, h));
        }
        return out;
    }

    ConductorIor m_ior;
    MicrofacetParams m_distr;
    std::shared_ptr<Texture> m_specular_reflectance;
};

MVPT_REGISTER_PLUGIN("bsdf", "roughconductor", [](const Properties &p, const LoadContext &) {
    return std::make_shared<RoughConductor>(p);
});

} // namespace mvpt
