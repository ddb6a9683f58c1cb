// Smooth conductor: a perfect mirror with the conductor Fresnel reflectance
// (Mitsuba 3's `conductor`). One-sided: black from below.
#include "../../core/plugin.h"
#include "../bsdf.h"
#include "../fresnel.h"
#include "../texture.h"
#include "conductor_ior.h"

namespace mvpt {

class SmoothConductor final : public Bsdf {
public:
    explicit SmoothConductor(const Properties &props) {
        m_specular_reflectance = get_texture(props, "specular_reflectance", 1.f);
        m_ior = read_conductor_ior(props);
        m_flags = BsdfDeltaReflection;
    }

    std::pair<BsdfSample, Spectrum> sample(const BsdfContext &, const SurfaceInteraction &si, Vec3f wi, float,
                                           Vec2f) const override {
        BsdfSample bs;
        float cos_theta_i = Frame::cos_theta(wi);
        if (cos_theta_i <= 0.f) return {bs, {}};
        bs.wo = Vec3f(-wi.x, -wi.y, wi.z);
        bs.pdf = 1.f;
        bs.sampled_type = BsdfDeltaReflection;
        Spectrum F = fresnel_conductor(cos_theta_i, m_ior.eta->eval(si), m_ior.k->eval(si));
        return {bs, m_specular_reflectance->eval(si) * F};
    }

    Spectrum eval(const BsdfContext &, const SurfaceInteraction &, Vec3f, Vec3f) const override { return {}; }
    float pdf(const BsdfContext &, const SurfaceInteraction &, Vec3f, Vec3f) const override { return 0.f; }
    float roughness(const SurfaceInteraction &) const override { return 0.f; }

private:
    std::shared_ptr<Texture> m_specular_reflectance;
    ConductorIor m_ior;
};

MVPT_REGISTER_PLUGIN("bsdf", "conductor", [](const Properties &p, const LoadContext &) {
    return std::make_shared<SmoothConductor>(p);
});

} // namespace mvpt
