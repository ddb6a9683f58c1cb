// Thin dielectric sheet: mirror reflection or straight pass-through, with the
// reflectance summed over all internal bounces R' = R + T R T + ... = 2R/(1+R)
// (Mitsuba 3's `thindielectric`). The transmission is a null event (wo = -wi).
#include "../../core/plugin.h"
#include "../bsdf.h"
#include "../fresnel.h"
#include "../ior.h"
#include "../texture.h"

namespace mvpt {

class ThinDielectric final : public Bsdf {
public:
    explicit ThinDielectric(const Properties &props) {
        float int_ior = read_ior(props, "int_ior", "bk7"), ext_ior = read_ior(props, "ext_ior", "air");
        m_eta = int_ior / ext_ior;
        if (props.has_texture("specular_reflectance"))
            m_specular_reflectance = get_texture(props, "specular_reflectance", 1.f);
        if (props.has_texture("specular_transmittance"))
            m_specular_transmittance = get_texture(props, "specular_transmittance", 1.f);
        m_flags = BsdfDeltaReflection | BsdfNull;
    }

    std::pair<BsdfSample, Spectrum> sample(const BsdfContext &, const SurfaceInteraction &si, Vec3f wi, float u1,
                                           Vec2f) const override {
        float r = fresnel_dielectric(std::abs(Frame::cos_theta(wi)), m_eta).F;
        r *= 2.f / (1.f + r); // geometric series of inter-reflections
        BsdfSample bs;
        Spectrum weight(1.f);
        if (u1 <= r) {
            bs.wo = Vec3f(-wi.x, -wi.y, wi.z);
            bs.pdf = r;
            bs.sampled_type = BsdfDeltaReflection;
            if (m_specular_reflectance) weight = m_specular_reflectance->eval(si);
        } else {
            bs.wo = -wi;
            bs.pdf = 1.f - r;
            bs.sampled_type = BsdfNull;
            if (m_specular_transmittance) weight = m_specular_transmittance->eval(si);
        }
        return {bs, weight};
    }

    Spectrum eval(const BsdfContext &, const SurfaceInteraction &, Vec3f, Vec3f) const override { return {}; }
    float pdf(const BsdfContext &, const SurfaceInteraction &, Vec3f, Vec3f) const override { return 0.f; }
    float roughness(const SurfaceInteraction &) const override { return 0.f; }

private:
    float m_eta;
    std::shared_ptr<Texture> m_specular_reflectance, m_specular_transmittance;
};

MVPT_REGISTER_PLUGIN("bsdf", "thindielectric", [](const Properties &p, const LoadContext &) {
    return std::make_shared<ThinDielectric>(p);
});

} // namespace mvpt
