// Distant directional emitter (Mitsuba's `directional`): irradiance arriving
// along one direction (the local +z of to_world, or `direction`), from beyond
// the scene's bounding sphere.
#include "../../core/plugin.h"
#include "../light.h"

namespace mvpt {

class DirectionalLight final : public Light {
public:
    explicit DirectionalLight(const Properties &props) {
        if (props.has("direction")) {
            if (props.has("to_world")) props.fail("direction", "give either 'direction' or 'to_world', not both");
            Vec3f d = props.get_vector("direction", Vec3f(0, 0, 1));
            float len = norm(d);
            if (!(len > 0.f) || !std::isfinite(len)) props.fail("direction", "'direction' must be a non-zero finite vector");
            m_direction = d / len;
        } else {
            Transform t = props.get_transform("to_world");
            m_direction = t.vector(Vec3f(0, 0, 1));
            float len = norm(m_direction);
            if (!(len > 0.f) || !std::isfinite(len)) props.fail("to_world", "'to_world' maps +z to a degenerate direction");
            m_direction = m_direction / len;
        }
        m_irradiance = props.get_color("irradiance", Color3f(1.f), SpectrumUse::Emission);
        if (!m_irradiance.is_finite() || m_irradiance.r < 0 || m_irradiance.g < 0 || m_irradiance.b < 0)
            props.fail("irradiance", "'irradiance' must be finite and non-negative");
        m_flags = LightInfinite | LightDeltaDirection;
    }

    void set_scene_bounds(Point3f center, float radius) override {
        m_center = center;
        m_radius = radius;
    }

    std::pair<LightSample, Spectrum> sample_li(Point3f ref, Vec2f, float) const override {
        LightSample ls;
        ls.d = -m_direction;
        ls.n = m_direction;
        // A point beyond the scene's bounding sphere (or beyond `ref` when it lies outside).
        ls.dist = 2.f * std::max(m_radius, norm(ref - m_center));
        ls.p = ref + ls.d * ls.dist;
        ls.pdf = 1.f;
        ls.delta = true;
        return {ls, m_irradiance};
    }

    float pdf_li(Point3f, const SurfaceInteraction &, Vec3f) const override { return 0.f; }

private:
    /// Direction of propagation (world space).
    Vec3f m_direction{0, 0, 1};
    Color3f m_irradiance;
    Point3f m_center{0.f};
    float m_radius = 1.f;
};

MVPT_REGISTER_PLUGIN("emitter", "directional", [](const Properties &p, const LoadContext &) {
    return std::make_shared<DirectionalLight>(p);
});

} // namespace mvpt
