// Smooth dielectric interface: Fresnel-weighted choice between mirror
// reflection and Snell refraction (Mitsuba 3's `dielectric`). Two-sided.
#include "../../core/plugin.h"
#include "../bsdf.h"
#include "../fresnel.h"
#include "../ior.h"
#include "../texture.h"

namespace mvpt {

class SmoothDielectric final : public Bsdf {
public:
    explicit SmoothDielectric(const Properties &props) {
        float int_ior = read_ior(props, "int_ior", "bk7"), ext_ior = read_ior(props, "ext_ior", "air");
        m_eta = int_ior / ext_ior;
        if (props.has_texture("specular_reflectance"))
            m_specular_reflectance = get_texture(props, "specular_reflectance", 1.f);
        if (props.has_texture("specular_transmittance"))
            m_specular_transmittance = get_texture(props, "specular_transmittance", 1.f);
        m_flags = BsdfDeltaReflection | BsdfDeltaTransmission;
    }

    std::pair<BsdfSample, Spectrum> sample(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, float u1,
                                           Vec2f) const override {
        FresnelDielectric fr = fresnel_dielectric(Frame::cos_theta(wi), m_eta);
        BsdfSample bs;
        Spectrum weight(1.f);
        if (u1 <= fr.F) { // reflection, chosen with probability F
            bs.wo = Vec3f(-wi.x, -wi.y, wi.z);
            bs.pdf = fr.F;
            bs.sampled_type = BsdfDeltaReflection;
            if (m_specular_reflectance) weight = m_specular_reflectance->eval(si);
        } else {
            bs.wo = refract(wi, fr.cos_theta_t, fr.eta_ti);
            bs.pdf = 1.f - fr.F;
            bs.eta = fr.eta_it;
            bs.sampled_type = BsdfDeltaTransmission;
            if (m_specular_transmittance) weight = m_specular_transmittance->eval(si);
            // Radiance is scaled by the solid-angle compression across the interface [Veach 1997, §5.2].
            if (ctx.mode == TransportMode::Radiance) weight *= fr.eta_ti * fr.eta_ti;
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

MVPT_REGISTER_PLUGIN("bsdf", "dielectric", [](const Properties &p, const LoadContext &) {
    return std::make_shared<SmoothDielectric>(p);
});

} // namespace mvpt
