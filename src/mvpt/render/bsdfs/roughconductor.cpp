// Rough conductor: Cook-Torrance microfacet reflection with the conductor
// Fresnel term [Walter et al. 2007] (Mitsuba 3's `roughconductor`). One-sided.
#include "roughconductor.h"

#include "../../core/simd.h"
#include "../../core/plugin.h"
#include "../bsdf.h"
#include "../bsdf_views.h"
#include "../texture.h"
#include "conductor_ior.h"
#include "bsdf_form.h"
#include "microfacet_params.h"

namespace mvpt {

/// rough_conductor_lobe<true, true> for the directions wi[0..n) and one wo: one vector loop.
MVPT_MULTI_ISA void rough_conductor_lobe_views(const RoughConductorLocal &l, bool beckmann, const Vec3f *wi, size_t n,
                                               Vec3f wo, Spectrum *f, float *pdf) {
    // One loop per distribution, its formulas alone in each.
    if (beckmann)
        lobe_over_views(wi, n, f, pdf, [&](Vec3f w, Spectrum &fc, float &pc) __attribute__((always_inline)) {
            rough_conductor_lobe<true, true>(l, true, w, wo, fc, pc);
        });
    else
        lobe_over_views(wi, n, f, pdf, [&](Vec3f w, Spectrum &fc, float &pc) __attribute__((always_inline)) {
            rough_conductor_lobe<true, true>(l, false, w, wo, fc, pc);
        });
}

class RoughConductor final : public Bsdf {
public:
    explicit RoughConductor(const Properties &props) {
        m_ior = read_conductor_ior(props);
        m_distr = read_microfacet_params(props);
        if (props.has_texture("specular_reflectance"))
            m_specular_reflectance = get_texture(props, "specular_reflectance", 1.f);
        m_flags = BsdfGlossyReflection;
        // Constant and isotropic with visible-normal sampling: a closed form (bsdf_form.h).
        auto constant = [](const std::shared_ptr<Texture> &t) { return !t || t->is_constant(); };
        if (constant(m_ior.eta) && constant(m_ior.k) && constant(m_specular_reflectance) && constant(m_distr.alpha_u) &&
            !m_distr.anisotropic() && m_distr.sample_visible) {
            const Vec2f uv(0.f, 0.f);
            RoughConductorInfo info;
            info.beckmann = m_distr.type == MicrofacetType::Beckmann;
            info.alpha = MicrofacetDistribution(m_distr.type, m_distr.alpha_u->eval_1(uv), m_distr.alpha_v->eval_1(uv))
                             .alpha_u();
            info.eta = m_ior.eta->eval(uv);
            info.k = m_ior.k->eval(uv);
            if (m_specular_reflectance) info.specular = m_specular_reflectance->eval(uv);
            m_form = info;
        }
    }

    std::pair<BsdfSample, Spectrum> sample(const BsdfContext &, const SurfaceInteraction &si, Vec3f wi, float,
                                           Vec2f u2) const override {
        // Filled in place (one named result): returning a copied pair is slower.
        std::pair<BsdfSample, Spectrum> result;
        BsdfSample &bs = result.first;
        if (Frame::cos_theta(wi) <= 0.f) return result;
        const RoughConductorLocal l = at(si, true);
        float pdf_m = 0.f;
        const Vec3f m = MicrofacetDistribution(m_distr.type, l.alpha_u, l.alpha_v, l.sample_visible).sample(wi, u2, &pdf_m);
        const RoughConductorSample s = rough_conductor_reflect(l, beckmann(), wi, m, pdf_m);
        bs.wo = s.wo;
        bs.sampled_type = BsdfGlossyReflection;
        if (!s.ok) return result;
        bs.pdf = s.pdf;
        result.second = s.weight;
        return result;
    }

    Spectrum eval(const BsdfContext &, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const override {
        Spectrum f;
        float pdf;
        if (below(wi, wo)) return f;
        const RoughConductorLocal l = at(si, true);
        with_distribution(beckmann(), [&](auto b) { rough_conductor_lobe<true, false>(l, b, wi, wo, f, pdf); });
        return f;
    }

    float pdf(const BsdfContext &, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const override {
        Spectrum f;
        float pdf = 0.f;
        if (below(wi, wo)) return pdf;
        const RoughConductorLocal l = at(si, false);
        with_distribution(beckmann(), [&](auto b) { rough_conductor_lobe<false, true>(l, b, wi, wo, f, pdf); });
        return pdf;
    }

    std::pair<Spectrum, float> eval_pdf(const BsdfContext &, const SurfaceInteraction &si, Vec3f wi,
                                        Vec3f wo) const override {
        std::pair<Spectrum, float> out{Spectrum(0.f), 0.f};
        if (below(wi, wo)) return out;
        const RoughConductorLocal l = at(si, true);
        with_distribution(beckmann(), [&](auto b) { rough_conductor_lobe<true, true>(l, b, wi, wo, out.first, out.second); });
        return out;
    }

    /// The textures once for all the views, and one vector loop over them.
    void eval_pdf_views(const BsdfContext &, const SurfaceInteraction &si, const Vec3f *wi, size_t n, Vec3f wo,
                        Spectrum *f, float *pdf) const override {
        rough_conductor_lobe_views(at(si, true), beckmann(), wi, n, wo, f, pdf);
    }

    float roughness(const SurfaceInteraction &si) const override { return m_distr.mean_alpha(si); }
    /// The constant parameters, when they are constant (and isotropic, with visible-normal sampling).
    const std::optional<RoughConductorInfo> &form() const { return m_form; }

private:
    bool beckmann() const { return m_distr.type == MicrofacetType::Beckmann; }
    /// The lobe's parameters at a hit (the colours only `with_colours`).
    RoughConductorLocal at(const SurfaceInteraction &si, bool with_colours) const {
        const MicrofacetDistribution distr = m_distr.at(si);
        RoughConductorLocal l;
        l.alpha_u = distr.alpha_u(), l.alpha_v = distr.alpha_v();
        l.sample_visible = distr.sample_visible();
        if (with_colours) {
            l.eta = m_ior.eta->eval(si), l.k = m_ior.k->eval(si);
            if (m_specular_reflectance) l.specular = m_specular_reflectance->eval(si);
        }
        return l;
    }

    ConductorIor m_ior;
    MicrofacetParams m_distr;
    std::shared_ptr<Texture> m_specular_reflectance;
    std::optional<RoughConductorInfo> m_form;
};

std::optional<RoughConductorInfo> rough_conductor_form(const Bsdf &bsdf) {
    if (auto *c = dynamic_cast<const RoughConductor *>(&bsdf)) return c->form();
    return std::nullopt;
}

MVPT_REGISTER_PLUGIN("bsdf", "roughconductor", [](const Properties &p, const LoadContext &) {
    return std::make_shared<RoughConductor>(p);
});

} // namespace mvpt
