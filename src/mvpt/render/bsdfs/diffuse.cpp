// Lambertian reflection with cosine-weighted sampling.
#include "../../core/warp.h"
#include "../../core/plugin.h"
#include "../bsdf.h"
#include "../texture.h"
#include "bsdf_form.h"

namespace mvpt {

class DiffuseBsdf final : public Bsdf {
public:
    explicit DiffuseBsdf(const Properties &props) {
        m_reflectance = get_texture(props, "reflectance", 0.5f);
        m_constant = m_reflectance->is_constant();
        if (m_constant) m_constant_value = m_reflectance->eval(Vec2f(0.f, 0.f));
        m_flags = BsdfDiffuseReflection;
    }

    std::pair<BsdfSample, Spectrum> sample(const BsdfContext &, const SurfaceInteraction &si, Vec3f wi, float,
                                           Vec2f u2) const override {
        // Filled in place (one named result): returning a copied pair is slower.
        std::pair<BsdfSample, Spectrum> result;
        BsdfSample &bs = result.first;
        if (Frame::cos_theta(wi) <= 0.f) return result;
        bs.wo = warp::square_to_cosine_hemisphere(u2);
        bs.pdf = warp::square_to_cosine_hemisphere_pdf(bs.wo);
        bs.sampled_type = BsdfDiffuseReflection;
        if (bs.pdf <= 0.f) return result;
        result.second = reflectance(si);
        return result;
    }

    Spectrum eval(const BsdfContext &, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const override {
        if (Frame::cos_theta(wi) <= 0.f || Frame::cos_theta(wo) <= 0.f) return {};
        return reflectance(si) * (InvPi * Frame::cos_theta(wo));
    }

    float pdf(const BsdfContext &, const SurfaceInteraction &, Vec3f wi, Vec3f wo) const override {
        if (Frame::cos_theta(wi) <= 0.f) return 0.f;
        return warp::square_to_cosine_hemisphere_pdf(wo);
    }

    void eval_pdf_views(const BsdfContext &, const SurfaceInteraction &si, const Vec3f *wi, size_t n, Vec3f wo,
                        Spectrum *f, float *pdf) const override {
        float cos_o = Frame::cos_theta(wo);
        Spectrum fo = cos_o > 0.f ? m_reflectance->eval(si) * (InvPi * cos_o) : Spectrum(0.f);
        float po = warp::square_to_cosine_hemisphere_pdf(wo);
        for (size_t c = 0; c < n; ++c) {
            bool front = Frame::cos_theta(wi[c]) > 0.f;
            f[c] = front ? fo : Spectrum(0.f);
            pdf[c] = front ? po : 0.f;
        }
    }

    /// The reflectance as a LambertInfo (one-sided).
    LambertInfo form() const { return {m_constant_value, false, m_constant ? nullptr : m_reflectance.get()}; }

private:
    /// The reflectance texture at `si`, without a virtual call when it is constant.
    Color3f reflectance(const SurfaceInteraction &si) const { return m_constant ? m_constant_value : m_reflectance->eval(si); }

    std::shared_ptr<Texture> m_reflectance;
    bool m_constant = false;
    Color3f m_constant_value;
};

std::optional<LambertInfo> diffuse_form(const Bsdf &bsdf) {
    if (auto *d = dynamic_cast<const DiffuseBsdf *>(&bsdf)) return d->form();
    return std::nullopt;
}

MVPT_REGISTER_PLUGIN("bsdf", "diffuse", [](const Properties &p, const LoadContext &) {
    return std::make_shared<DiffuseBsdf>(p);
});

} // namespace mvpt
