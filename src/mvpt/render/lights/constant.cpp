// Constant environment emitter (Mitsuba's `constant`): uniform radiance from
// every direction at infinity, sampled uniformly over the sphere.
#include "../../core/warp.h"
#include "../../core/plugin.h"
#include "../light.h"

namespace mvpt {

class ConstantEnvironment final : public Light {
public:
    explicit ConstantEnvironment(const Properties &props) {
        m_radiance = props.get_color("radiance", Color3f(1.f), SpectrumUse::Emission);
        if (!m_radiance.is_finite() || m_radiance.r < 0 || m_radiance.g < 0 || m_radiance.b < 0)
            props.fail("radiance", "'radiance' must be finite and non-negative");
        m_flags = LightInfinite;
    }

    void set_scene_bounds(Point3f center, float radius) override {
        m_center = center;
        m_radius = radius;
    }

    std::pair<LightSample, Spectrum> sample_li(Point3f ref, Vec2f u, float) const override {
        LightSample ls;
        ls.d = warp::square_to_uniform_sphere(u);
        ls.n = -ls.d;
        ls.dist = 2.f * std::max(m_radius, norm(ref - m_center));
        ls.p = ref + ls.d * ls.dist;
        ls.pdf = warp::square_to_uniform_sphere_pdf();
        return {ls, m_radiance / ls.pdf};
    }

    float pdf_li(Point3f, const SurfaceInteraction &, Vec3f) const override {
        return warp::square_to_uniform_sphere_pdf();
    }

    Spectrum eval_environment(Vec3f) const override { return m_radiance; }

private:
    Color3f m_radiance;
    Point3f m_center{0.f};
    float m_radius = 1.f;
};

MVPT_REGISTER_PLUGIN("emitter", "constant", [](const Properties &p, const LoadContext &) {
    return std::make_shared<ConstantEnvironment>(p);
});

} // namespace mvpt
