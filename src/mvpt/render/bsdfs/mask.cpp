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
        const float opacity = eval_opacity(si);
        // The nested BSDF's probability: the opacity, or its share of the lobes of a type mask.
        const bool restricted = ctx.type_mask != ~0u;
        const float p_nested = restricted ? restricted_opacity(ctx.type_mask, si, wi, opacity) : opacity;
        if (u1 < p_nested) {
            auto [bs, weight] = m_nested->sample(ctx, si, wi, u1 / p_nested, u2);
            bs.pdf *= p_nested; // f = opacity f_nested: without a mask the weight is the nested one
            return {bs, restricted ? weight * (opacity / p_nested) : weight};
        }
        if (restricted && !(ctx.type_mask & BsdfNull)) return {BsdfSample{}, {}}; // nothing of the kind
        BsdfSample bs;
        bs.wo = -wi;
        bs.pdf = 1.f - p_nested;
        bs.sampled_type = BsdfNull;
        return {bs, Spectrum(restricted ? (1.f - opacity) / bs.pdf : 1.f)};
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

    /// The null event's probability plus the nested BSDF's delta lobes' (when it has one).
    std::optional<float> delta_probability(const SurfaceInteraction &si, Vec3f wi) const override {
        const std::optional<float> nested = m_nested->delta_probability(si, wi);
        if (!nested) return std::nullopt;
        const float opacity = eval_opacity(si);
        return 1.f - opacity + opacity * *nested;
    }

    float roughness(const SurfaceInteraction &si) const override { return m_nested->roughness(si); }

private:
    /// The probability of the nested BSDF among the lobes of `type_mask` (BsdfDelta: the null event
    /// and the nested delta lobes; BsdfSmooth: the nested smooth lobes alone).
    float restricted_opacity(uint32_t type_mask, const SurfaceInteraction &si, Vec3f wi, float opacity) const {
        const float nested_delta = m_nested->delta_probability(si, wi).value_or(0.f);
        const float nested = opacity * ((type_mask & BsdfSmooth) ? 1.f - nested_delta : nested_delta);
        const float null = (type_mask & BsdfNull) ? 1.f - opacity : 0.f;
        return nested + null > 0.f ? nested / (nested + null) : 0.f;
    }

    float eval_opacity(const SurfaceInteraction &si) const { return std::clamp(m_opacity->eval_1(si), 0.f, 1.f); }

    std::shared_ptr<Texture> m_opacity;
    std::shared_ptr<Bsdf> m_nested;
};

MVPT_REGISTER_PLUGIN("bsdf", "mask", [](const Properties &p, const LoadContext &) {
    return std::make_shared<MaskBsdf>(p);
});

} // namespace mvpt
