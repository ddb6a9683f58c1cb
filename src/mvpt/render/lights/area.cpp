// Area emitter: constant radiance on the front side of its shape.
#include "../../scene/plugin.h"
#include "../light.h"
#include "../shape.h"

namespace mvpt {

class AreaLight final : public Light {
public:
    explicit AreaLight(const Properties &props) {
        m_radiance = props.get_color("radiance", Color3f(1.f));
        if (!m_radiance.is_finite() || m_radiance.r < 0 || m_radiance.g < 0 || m_radiance.b < 0)
            props.fail("radiance", "'radiance' must be finite and non-negative");
        m_flags = LightSurface;
    }

    void set_shape(const Shape *s) override { m_shape = s; }
    const Shape *shape() const override { return m_shape; }

    std::pair<LightSample, Spectrum> sample_li(Point3f ref, Vec2f u, float) const override {
        auto [ss, pdf] = m_shape->sample_solid_angle(ref, u);
        LightSample ls;
        ls.p = ss.p;
        ls.n = ss.n;
        Vec3f d = ss.p - ref;
        ls.dist = norm(d);
        if (!(pdf > 0.f) || !(ls.dist > 0.f)) return {ls, {}};
        ls.d = d / ls.dist;
        ls.pdf = pdf;
        if (dot(ls.n, ls.d) >= 0.f) return {ls, {}}; // back side of a one-sided emitter
        return {ls, m_radiance / pdf};
    }

    float pdf_li(Point3f ref, const SurfaceInteraction &si, Vec3f d) const override {
        if (dot(si.n, d) >= 0.f) return 0.f;
        return m_shape->pdf_solid_angle(ref, si);
    }

    Spectrum eval(const SurfaceInteraction &si, Vec3f w) const override {
        return dot(si.n, w) > 0.f ? m_radiance : Spectrum();
    }

private:
    Color3f m_radiance;
    const Shape *m_shape = nullptr;
};

MVPT_REGISTER_PLUGIN("emitter", "area", [](const Properties &p, const LoadContext &) {
    return std::make_shared<AreaLight>(p);
});

} // namespace mvpt
