// The `isotropic` and `hg` phase functions (one family: isotropic is g = 0).
#include "../../core/warp.h"
#include "../../core/plugin.h"
#include "../phase.h"

namespace mvpt {

float henyey_greenstein(float cos_propagation, float g) {
    float denom = 1.f + g * g - 2.f * g * cos_propagation;
    return InvFourPi * (1.f - g * g) / (denom * std::sqrt(denom));
}

namespace {

class HenyeyGreenstein final : public PhaseFunction {
public:
    explicit HenyeyGreenstein(float g) : m_g(g) {}

    float eval(Vec3f wi, Vec3f wo) const override { return henyey_greenstein(-dot(wi, wo), m_g); }

    Vec3f sample(Vec3f wi, Vec2f u) const override {
        // Inverse of the CDF of cos (the cosine to the propagation direction -wi).
        float cos_t;
        if (std::abs(m_g) < 1e-3f) {
            cos_t = 1.f - 2.f * u.x;
        } else {
            float s = (1.f - m_g * m_g) / (1.f - m_g + 2.f * m_g * u.x);
            cos_t = std::clamp((1.f + m_g * m_g - s * s) / (2.f * m_g), -1.f, 1.f);
        }
        float sin_t = std::sqrt(std::max(0.f, 1.f - cos_t * cos_t)), phi = 2.f * Pi * u.y;
        Frame f(-wi);
        return f.to_world(Vec3f(sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t));
    }

private:
    float m_g;
};

} // namespace

MVPT_REGISTER_PLUGIN("phase", "isotropic", [](const Properties &, const LoadContext &) {
    return std::make_shared<HenyeyGreenstein>(0.f);
});
MVPT_REGISTER_PLUGIN("phase", "hg", [](const Properties &p, const LoadContext &) {
    float g = p.get_float("g", 0.8f);
    if (!(g > -1.f && g < 1.f)) p.fail("g", "the asymmetry g must lie in (-1, 1), got " + std::to_string(g));
    return std::make_shared<HenyeyGreenstein>(g);
});

} // namespace mvpt
