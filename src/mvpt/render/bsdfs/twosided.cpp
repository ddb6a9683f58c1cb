// Two-sided adapter: applies a one-sided BRDF on both sides, or a second
// BRDF on the back side, by mirroring directions through the shading plane
// (Mitsuba 3.9's `twosided`, which decides the side by the shading normal).
#include "../../core/plugin.h"
#include "../bsdf.h"
#include "bsdf_form.h"

#include <algorithm>

namespace mvpt {

class TwoSidedBsdf final : public Bsdf {
public:
    explicit TwoSidedBsdf(const Properties &props) {
        auto children = props.children_of_kind("bsdf");
        if (children.empty()) props.fail("", "twosided needs a nested one-sided bsdf");
        if (children.size() > 2)
            throw SceneError(children[2]->loc, "twosided accepts at most two nested bsdfs");
        m_brdf[0] = std::static_pointer_cast<Bsdf>(children[0]->object);
        m_brdf[1] = children.size() == 2 ? std::static_pointer_cast<Bsdf>(children[1]->object) : m_brdf[0];
        m_flags = m_brdf[0]->flags() | m_brdf[1]->flags();
        if (m_flags & BsdfTransmission)
            props.fail("", "twosided: only materials without a transmission component can be nested");
    }

    std::pair<BsdfSample, Spectrum> sample(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, float u1,
                                           Vec2f u2) const override {
        if (wi.z > 0.f) return m_brdf[0]->sample(ctx, si, wi, u1, u2);
        if (wi.z < 0.f) {
            std::pair<BsdfSample, Spectrum> result = m_brdf[1]->sample(ctx, si, flip(wi), u1, u2);
            result.first.wo = flip(result.first.wo);
            return result;
        }
        return {BsdfSample{}, {}};
    }

    Spectrum eval(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const override {
        if (wi.z > 0.f) return m_brdf[0]->eval(ctx, si, wi, wo);
        if (wi.z < 0.f) return m_brdf[1]->eval(ctx, si, flip(wi), flip(wo));
        return {};
    }

    float pdf(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const override {
        if (wi.z > 0.f) return m_brdf[0]->pdf(ctx, si, wi, wo);
        if (wi.z < 0.f) return m_brdf[1]->pdf(ctx, si, flip(wi), flip(wo));
        return 0.f;
    }

    /// Each side's BRDF over a run of views on that side, so that its vector loop serves them (the
    /// views of a shared vertex mostly see one side); a view in the shading plane gets zero.
    void eval_pdf_views(const BsdfContext &ctx, const SurfaceInteraction &si, const Vec3f *wi, size_t n, Vec3f wo,
                        Spectrum *f, float *pdf) const override {
        constexpr size_t Chunk = 64;
        Vec3f flipped[Chunk];
        for (size_t c = 0; c < n;) {
            const int s = side(wi[c]);
            size_t end = c + 1;
            while (end < n && end - c < Chunk && side(wi[end]) == s) ++end;
            if (s > 0) {
                m_brdf[0]->eval_pdf_views(ctx, si, wi + c, end - c, wo, f + c, pdf + c);
            } else if (s < 0) {
                for (size_t k = c; k < end; ++k) flipped[k - c] = flip(wi[k]);
                m_brdf[1]->eval_pdf_views(ctx, si, flipped, end - c, flip(wo), f + c, pdf + c);
            } else {
                std::fill(f + c, f + end, Spectrum(0.f));
                std::fill(pdf + c, pdf + end, 0.f);
            }
            c = end;
        }
    }

    std::optional<float> delta_probability(const SurfaceInteraction &si, Vec3f wi) const override {
        if (wi.z > 0.f) return m_brdf[0]->delta_probability(si, wi);
        if (wi.z < 0.f) return m_brdf[1]->delta_probability(si, flip(wi));
        return 0.f;
    }

    float roughness(const SurfaceInteraction &si) const override {
        return si.wi.z < 0.f ? m_brdf[1]->roughness(si) : m_brdf[0]->roughness(si);
    }

    /// The front and back BRDFs.
    std::pair<const Bsdf *, const Bsdf *> sides() const { return {m_brdf[0].get(), m_brdf[1].get()}; }

private:
    static Vec3f flip(Vec3f v) { return {v.x, v.y, -v.z}; }
    /// The side a direction is on: 1 front, -1 back, 0 in the shading plane.
    static int side(Vec3f v) { return int(v.z > 0.f) - int(v.z < 0.f); }
    std::shared_ptr<Bsdf> m_brdf[2];
};

std::optional<std::pair<const Bsdf *, const Bsdf *>> twosided_sides(const Bsdf &bsdf) {
    if (auto *t = dynamic_cast<const TwoSidedBsdf *>(&bsdf)) return t->sides();
    return std::nullopt;
}

MVPT_REGISTER_PLUGIN("bsdf", "twosided", [](const Properties &p, const LoadContext &) {
    return std::make_shared<TwoSidedBsdf>(p);
});

} // namespace mvpt
