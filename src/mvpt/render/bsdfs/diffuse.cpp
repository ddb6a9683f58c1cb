// Lambertian reflection with cosine-weighted sampling.
#include "../../core/warp.h"
#include "../../scene/plugin.h"
#include "../bsdf.h"
#include "../texture.h"

namespace mvpt {

class DiffuseBsdf final : public Bsdf {
public:
    explicit DiffuseBsdf(const Properties &props) {
        m_reflectance = props.get_texture("reflectance", 0.5f);
        m_flags = BsdfDiffuseReflection;
    }

    std::pair<BsdfSample, Spectrum> sample(const BsdfContext &, const SurfaceInteraction &si, Vec3f wi, float,
                                           Vec2f u2) const override {
        BsdfSample bs;
        if (Frame::cos_theta(wi) <= 0.f) return {bs, {}};
        bs.wo = warp::square_to_cosine_hemisphere(u2);
        bs.pdf = warp::square_to_cosine_hemisphere_pdf(bs.wo);
        bs.sampled_type = BsdfDiffuseReflection;
        if (bs.pdf <= 0.f) return {bs, {}};
        return {bs, m_reflectance->eval(si.uv)};
    }

    Spectrum eval(const BsdfContext &, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const override {
        if (Frame::cos_theta(wi) <= 0.f || Frame::cos_theta(wo) <= 0.f) return {};
        return m_reflectance->eval(si.uv) * (InvPi * Frame::cos_theta(wo));
    }

    float pdf(const BsdfContext &, const SurfaceInteraction &, Vec3f wi, Vec3f wo) const override {
        if (Frame::cos_theta(wi) <= 0.f) return 0.f;
        return warp::square_to_cosine_hemisphere_pdf(wo);
    }

    void eval_pdf_views(const BsdfContext &, const SurfaceInteraction &si, const Vec3f *wi, size_t n, Vec3f wo,
                        Spectrum *f, float *pdf) const override {
        float cos_o = Frame::cos_theta(wo);
        Spectrum fo = cos_o > 0.f ? m_reflectance->eval(si.uv) * (InvPi * cos_o) : Spectrum(0.f);
        float po = warp::square_to_cosine_hemisphere_pdf(wo);
        for (size_t c = 0; c < n; ++c) {
            bool front = Frame::cos_theta(wi[c]) > 0.f;
            f[c] = front ? fo : Spectrum(0.f);
            pdf[c] = front ? po : 0.f;
        }
    }

private:
    std::shared_ptr<Texture> m_reflectance;
};

MVPT_REGISTER_PLUGIN("bsdf", "diffuse", [](const Properties &p, const LoadContext &) {
    return std::make_shared<DiffuseBsdf>(p);
});

} // namespace mvpt
