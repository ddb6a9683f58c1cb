// Linear blend of two BSDFs by a weight texture: f = (1 - w) f0 + w f1
// (Mitsuba 3's `blendbsdf`). Sampling picks one nested BSDF with probability
// 1 - w or w, then reports the mixture density and weight the way Mitsuba 3.9
// does (see `sample`).
#include "../../core/plugin.h"
#include "../bsdf.h"
#include "../texture.h"

#include <algorithm>

namespace mvpt {

class BlendBsdf final : public Bsdf {
public:
    explicit BlendBsdf(const Properties &props) {
        auto children = props.children_of_kind("bsdf");
        if (children.size() != 2) props.fail("", "blendbsdf needs exactly two nested bsdfs");
        for (int i = 0; i < 2; ++i) m_bsdf[i] = std::static_pointer_cast<Bsdf>(children[i]->object);
        if (!props.has_texture("weight")) props.fail("weight", "blendbsdf needs a 'weight' (float or texture)");
        m_weight = get_texture(props, "weight", 0.5f);
        m_flags = m_bsdf[0]->flags() | m_bsdf[1]->flags();
    }

    /// Mixture density (1 - w) p0 + w p1 with the selected lobe's sampled density,
    /// and weight (mixture of f cos) / density, as Mitsuba 3.9.1. For a delta sample the
    /// other lobe's smooth density at that direction is added to the discrete
    /// probability, exactly as Mitsuba does (this mixes measures: a delta lobe blended
    /// with a smooth one is slightly under-weighted, in Mitsuba and here alike).
    std::pair<BsdfSample, Spectrum> sample(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, float u1,
                                           Vec2f u2) const override {
        float w = blend_weight(si);
        int sel = (u1 > w || w == 0.f) ? 0 : 1; // Mitsuba's rule; never pick a lobe of weight 0
        float w_sel = sel == 0 ? 1.f - w : w, w_other = 1.f - w_sel;
        float u1_nested = sel == 0 ? (u1 - w) / (1.f - w) : u1 / w;
        auto [bs, weight] = m_bsdf[sel]->sample(ctx, si, wi, u1_nested, u2);
        if (!(bs.pdf > 0.f) || weight.is_black()) return {bs, {}};
        const Bsdf &other = *m_bsdf[1 - sel];
        float pdf_sel = bs.pdf;
        bs.pdf = w_sel * pdf_sel + w_other * other.pdf(ctx, si, wi, bs.wo);
        Spectrum value = weight * (w_sel * pdf_sel) + other.eval(ctx, si, wi, bs.wo) * w_other;
        return {bs, value / bs.pdf};
    }

    Spectrum eval(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const override {
        float w = blend_weight(si);
        return m_bsdf[0]->eval(ctx, si, wi, wo) * (1.f - w) + m_bsdf[1]->eval(ctx, si, wi, wo) * w;
    }

    float pdf(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const override {
        float w = blend_weight(si);
        return m_bsdf[0]->pdf(ctx, si, wi, wo) * (1.f - w) + m_bsdf[1]->pdf(ctx, si, wi, wo) * w;
    }

    /// Both nested BSDFs' views (their vector loops), blended as eval and pdf blend them; in runs
    /// of at most 64 views (the second's values live on the stack).
    void eval_pdf_views(const BsdfContext &ctx, const SurfaceInteraction &si, const Vec3f *wi, size_t n, Vec3f wo,
                        Spectrum *f, float *pdf) const override {
        constexpr size_t Chunk = 64;
        Spectrum f1[Chunk];
        float pdf1[Chunk];
        const float w = blend_weight(si);
        for (size_t c = 0; c < n; c += Chunk) {
            const size_t m = std::min(Chunk, n - c);
            m_bsdf[0]->eval_pdf_views(ctx, si, wi + c, m, wo, f + c, pdf + c);
            m_bsdf[1]->eval_pdf_views(ctx, si, wi + c, m, wo, f1, pdf1);
            for (size_t k = 0; k < m; ++k) {
                f[c + k] = f[c + k] * (1.f - w) + f1[k] * w;
                pdf[c + k] = pdf[c + k] * (1.f - w) + pdf1[k] * w;
            }
        }
    }

    /// Roughness of the dominant nested BSDF at `si`.
    float roughness(const SurfaceInteraction &si) const override {
        return m_bsdf[blend_weight(si) > 0.5f ? 1 : 0]->roughness(si);
    }

private:
    float blend_weight(const SurfaceInteraction &si) const { return std::clamp(m_weight->eval_1(si), 0.f, 1.f); }

    std::shared_ptr<Bsdf> m_bsdf[2];
    std::shared_ptr<Texture> m_weight;
};

MVPT_REGISTER_PLUGIN("bsdf", "blendbsdf", [](const Properties &p, const LoadContext &) {
    return std::make_shared<BlendBsdf>(p);
});

} // namespace mvpt
