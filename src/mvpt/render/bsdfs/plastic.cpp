// Smooth plastic: a diffuse base under a smooth dielectric coating, with the
// internal reflections between coating and base summed in closed form
// [Weidlich and Wilkie 2007] (Mitsuba 3's `plastic`). One-sided.
#include "../../core/warp.h"
#include "../../core/plugin.h"
#include "../bsdf.h"
#include "../fresnel.h"
#include "../ior.h"
#include "../texture.h"

#include <algorithm>

namespace mvpt {

class SmoothPlastic final : public Bsdf {
public:
    explicit SmoothPlastic(const Properties &props) {
        float int_ior = read_ior(props, "int_ior", "polypropylene"), ext_ior = read_ior(props, "ext_ior", "air");
        m_eta = int_ior / ext_ior;
        m_diffuse_reflectance = get_texture(props, "diffuse_reflectance", 0.5f);
        if (props.has_texture("specular_reflectance"))
            m_specular_reflectance = get_texture(props, "specular_reflectance", 1.f);
        m_nonlinear = props.get_bool("nonlinear", false);
        m_flags = BsdfDeltaReflection | BsdfDiffuseReflection;

        m_inv_eta_2 = 1.f / (m_eta * m_eta);
        m_fdr_int = fresnel_diffuse_reflectance(1.f / m_eta);
        // Lobe selection weight from the mean reflectances, as Mitsuba.
        float d_mean = m_diffuse_reflectance->mean().mean();
        float s_mean = m_specular_reflectance ? m_specular_reflectance->mean().mean() : 1.f;
        m_specular_sampling_weight = s_mean / (d_mean + s_mean);
    }

    std::pair<BsdfSample, Spectrum> sample(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, float u1,
                                           Vec2f u2) const override {
        BsdfSample bs;
        float cos_theta_i = Frame::cos_theta(wi);
        if (cos_theta_i <= 0.f) return {bs, {}};
        float f_i = fresnel_dielectric(cos_theta_i, m_eta).F;
        float prob_specular = specular_probability(f_i);
        if (!(ctx.type_mask & BsdfDeltaReflection)) prob_specular = 0.f;
        else if (!(ctx.type_mask & BsdfDiffuseReflection)) prob_specular = 1.f;
        if (u1 < prob_specular) {
            bs.wo = Vec3f(-wi.x, -wi.y, wi.z);
            bs.pdf = prob_specular;
            bs.sampled_type = BsdfDeltaReflection;
            Spectrum value(f_i / bs.pdf);
            if (m_specular_reflectance) value *= m_specular_reflectance->eval(si);
            return {bs, value};
        }
        float prob_diffuse = 1.f - prob_specular;
        bs.wo = warp::square_to_cosine_hemisphere(u2);
        bs.pdf = prob_diffuse * warp::square_to_cosine_hemisphere_pdf(bs.wo);
        bs.sampled_type = BsdfDiffuseReflection;
        float f_o = fresnel_dielectric(Frame::cos_theta(bs.wo), m_eta).F;
        return {bs, diffuse_albedo(si) * (m_inv_eta_2 * (1.f - f_i) * (1.f - f_o) / prob_diffuse)};
    }

    Spectrum eval(const BsdfContext &, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const override {
        float cos_theta_i = Frame::cos_theta(wi), cos_theta_o = Frame::cos_theta(wo);
        if (cos_theta_i <= 0.f || cos_theta_o <= 0.f) return {};
        float f_i = fresnel_dielectric(cos_theta_i, m_eta).F, f_o = fresnel_dielectric(cos_theta_o, m_eta).F;
        return diffuse_albedo(si) *
               (warp::square_to_cosine_hemisphere_pdf(wo) * m_inv_eta_2 * (1.f - f_i) * (1.f - f_o));
    }

    float pdf(const BsdfContext &, const SurfaceInteraction &, Vec3f wi, Vec3f wo) const override {
        float cos_theta_i = Frame::cos_theta(wi), cos_theta_o = Frame::cos_theta(wo);
        if (cos_theta_i <= 0.f || cos_theta_o <= 0.f) return 0.f;
        float f_i = fresnel_dielectric(cos_theta_i, m_eta).F;
        return warp::square_to_cosine_hemisphere_pdf(wo) * (1.f - specular_probability(f_i));
    }

    /// eval and pdf of the views wi[0..n) at one wo, the albedo (a texture) and wo's Fresnel
    /// term evaluated once (the same products as eval and pdf).
    void eval_pdf_views(const BsdfContext &, const SurfaceInteraction &si, const Vec3f *wi, size_t n, Vec3f wo,
                        Spectrum *f, float *pdf) const override {
        std::fill(f, f + n, Spectrum(0.f));
        std::fill(pdf, pdf + n, 0.f);
        const float cos_theta_o = Frame::cos_theta(wo);
        if (cos_theta_o <= 0.f) return;
        const Spectrum albedo = diffuse_albedo(si);
        const float f_o = fresnel_dielectric(cos_theta_o, m_eta).F, cosine = warp::square_to_cosine_hemisphere_pdf(wo);
        for (size_t c = 0; c < n; ++c) {
            const float cos_theta_i = Frame::cos_theta(wi[c]);
            if (cos_theta_i <= 0.f) continue;
            const float f_i = fresnel_dielectric(cos_theta_i, m_eta).F;
            f[c] = albedo * (cosine * m_inv_eta_2 * (1.f - f_i) * (1.f - f_o));
            pdf[c] = cosine * (1.f - specular_probability(f_i));
        }
    }

    std::optional<float> delta_probability(const SurfaceInteraction &, Vec3f wi) const override {
        const float cos_theta_i = Frame::cos_theta(wi);
        return cos_theta_i > 0.f ? specular_probability(fresnel_dielectric(cos_theta_i, m_eta).F) : 0.f;
    }

    float roughness(const SurfaceInteraction &) const override { return 1.f; }

private:
    float specular_probability(float f_i) const {
        float ps = f_i * m_specular_sampling_weight, pd = (1.f - f_i) * (1.f - m_specular_sampling_weight);
        return ps / (ps + pd);
    }
    /// Base reflectance after the internal coating bounces: rho / (1 - F_dr,int [rho]).
    Spectrum diffuse_albedo(const SurfaceInteraction &si) const {
        Spectrum diff = m_diffuse_reflectance->eval(si);
        Spectrum denom = m_nonlinear ? Spectrum(1.f) - diff * m_fdr_int : Spectrum(1.f - m_fdr_int);
        return diff / denom;
    }

    float m_eta, m_inv_eta_2, m_fdr_int, m_specular_sampling_weight;
    bool m_nonlinear;
    std::shared_ptr<Texture> m_diffuse_reflectance, m_specular_reflectance;
};

MVPT_REGISTER_PLUGIN("bsdf", "plastic", [](const Properties &p, const LoadContext &) {
    return std::make_shared<SmoothPlastic>(p);
});

} // namespace mvpt
