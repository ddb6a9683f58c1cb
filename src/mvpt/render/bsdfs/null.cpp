// The `null` BSDF: an invisible surface that light passes straight through (wo = -wi,
// weight 1), used to bound participating media without refraction (Mitsuba 3's `null`).
#include "../../core/plugin.h"
#include "../bsdf.h"

namespace mvpt {

namespace {

class NullBsdf final : public Bsdf {
public:
    NullBsdf() { m_flags = BsdfNull; }

    std::pair<BsdfSample, Spectrum> sample(const BsdfContext &, const SurfaceInteraction &, Vec3f wi, float,
                                           Vec2f) const override {
        BsdfSample bs;
        bs.wo = -wi;
        bs.pdf = 1.f;
        bs.sampled_type = BsdfNull;
        return {bs, Spectrum(1.f)};
    }
    Spectrum eval(const BsdfContext &, const SurfaceInteraction &, Vec3f, Vec3f) const override { return Spectrum(0.f); }
    float pdf(const BsdfContext &, const SurfaceInteraction &, Vec3f, Vec3f) const override { return 0.f; }
    Spectrum null_transmission(const SurfaceInteraction &) const override { return Spectrum(1.f); }
};

} // namespace

MVPT_REGISTER_PLUGIN("bsdf", "null", [](const Properties &, const LoadContext &) {
    return std::make_shared<NullBsdf>();
});

} // namespace mvpt
