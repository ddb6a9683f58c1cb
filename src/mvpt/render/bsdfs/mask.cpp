// Opacity mask: with probability `opacity` the nested BSDF scatters, otherwise
// light passes straight through as a null event (wo = -wi, weight 1)
// (Mitsuba 3's `mask`).
#include "../../core/plugin.h"
#include "../bsdf.h"
#include "../texture.h"

namespace mvpt {

class MaskBsdf final : public Bsdf {
public:
    explicit MaskBsdf(const Properties &props) {
        m_opacity = get_texture(props, "opacity", 0.5f);
        const ChildObject *child = props.child_of_kind("bsdf");
        if (!child) props.fail("", "mask needs a nested bsdf");
        m_nested = std::static_pointer_cast<Bsdf>(child->object);
        m_flags = m_nested->flags() | BsdfNull;
    }

    std::pair<BsdfSample, Spectrum> sample(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, float u1,
                                           Vec2f u2) const override {
        float opacity = eval_opacity(si);
        if (u1 < opacity) {
            auto [bs, weight] = m_nested->sample(ctx, si, wi, u1 / opacity, u2);
            bs.pdf *= opacity; // weight unchanged: opacity cancels between f and pdf
            return {bs, weight};
        }
        BsdfSample bs;
        bs.wo = -wi;
        bs.pdf = 1.f - opacity;
        bs.sampled_type = BsdfNull;
        return {bs, Spectrum(1.f)};
    }

    Spectrum eval(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const override {
        return m_nested->eval(ctx, si, wi, wo) * eval_opacity(si);
    }

    float pdf(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const override {
        return m_nested->pdf(ctx, si, wi, wo) * eval_opacity(si);
    }

    /// The nested BSDF's views (its vector loop), scaled by the opacity once evaluated.
    void eval_pdf_views(const BsdfContext &ctx, const SurfaceInteraction &si, const Vec3f *wi, size_t n, Vec3f wo,
                        Spectrum *f, float *pdf) const override {
        m_nested->eval_pdf_views(ctx, si, wi, n, wo, f, pdf);
        const float opacity = eval_opacity(si);
        for (size_t c = 0; c < n; ++c) f[c] = f[c] * opacity, pdf[c] *= opacity;
    }

    Spectrum null_transmission(const SurfaceInteraction &si) const override { return Spectrum(1.f - eval_opacity(si)); }

    float roughness(const SurfaceInteraction &si) const override { return m_nested->roughness(si); }

private:
    float eval_opacity(const SurfaceInteraction &si) const { return std::clamp(m_opacity->eval_1(si), 0.f, 1.f); }

    std::shared_ptr<Texture> m_opacity;
    std::shared_ptr<Bsdf> m_nested;
};

MVPT_REGISTER_PLUGIN("bsdf", "mask", [](const Properties &p, const LoadContext &) {
    return std::make_shared<MaskBsdf>(p);
});

} // namespace mvpt
