// Point light (Mitsuba's `point`): isotropic radiant intensity from one
// position; a delta light, reached only by next-event estimation.
#include "../../core/plugin.h"
#include "../light.h"

namespace mvpt {

class PointLight final : public Light {
public:
    explicit PointLight(const Properties &props) {
        if (props.has("position")) {
            if (props.has("to_world")) props.fail("position", "give either 'position' or 'to_world', not both");
            m_position = AnimatedTransform(Transform::translate(props.get_vector("position", Vec3f(0.f))));
        } else {
            m_position = props.get_animated_transform("to_world");
        }
        m_intensity = props.get_color("intensity", Color3f(1.f), SpectrumUse::Emission);
        if (!m_intensity.is_finite() || m_intensity.r < 0 || m_intensity.g < 0 || m_intensity.b < 0)
            props.fail("intensity", "'intensity' must be finite and non-negative");
        m_flags = LightDeltaPosition;
    }

    std::pair<LightSample, Spectrum> sample_li(Point3f ref, Vec2f, float time) const override {
        LightSample ls;
        ls.p = m_position.eval(time).point(Point3f(0.f));
        ls.pdf = 1.f;
        ls.delta = true;
        Vec3f d = ls.p - ref;
        ls.dist = norm(d);
        if (!(ls.dist > 0.f)) return {ls, {}};
        ls.d = d / ls.dist;
        // Inverse-square law: E = I / r^2.
        return {ls, m_intensity / (ls.dist * ls.dist)};
    }

    float pdf_li(Point3f, const SurfaceInteraction &, Vec3f) const override { return 0.f; }
    bool moves() const override { return m_position.is_animated(); }

private:
    AnimatedTransform m_position;
    Color3f m_intensity;
};

MVPT_REGISTER_PLUGIN("emitter", "point", [](const Properties &p, const LoadContext &) {
    return std::make_shared<PointLight>(p);
});

} // namespace mvpt
