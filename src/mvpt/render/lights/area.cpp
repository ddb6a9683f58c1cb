// Area emitter (Mitsuba's `area`): radiance, constant or a texture looked up
// at the surface uv, leaving the front side of its shape.
#include "../../core/plugin.h"
#include "../light.h"
#include "area.h"
#include "../shape.h"
#include "../shapes/mesh.h"
#include "../shapes/sphere.h"
#include "../texture.h"

namespace mvpt {

class AreaLight final : public Light {
public:
    explicit AreaLight(const Properties &props) {
        m_radiance = get_uv_texture(props, "radiance", Color3f(1.f), SpectrumUse::Emission);
        if (m_radiance->is_constant()) {
            Color3f c = m_radiance->mean();
            if (!c.is_finite() || c.r < 0 || c.g < 0 || c.b < 0)
                props.fail("radiance", "'radiance' must be finite and non-negative");
        }
        m_flags = LightSurface;
    }

    void set_shape(const Shape *s) override { m_shape = s; }
    const Shape *shape() const override { return m_shape; }
    bool uniform_radiance() const override { return m_radiance->is_constant(); }
    /// A constant-radiance parallelogram mesh: sample_li below reduces to QuadEmitter's sampling.
    std::optional<QuadEmitter> quad() const {
        QuadEmitter q;
        auto *mesh = dynamic_cast<const TriangleMesh *>(m_shape);
        if (!m_radiance->is_constant() || !mesh || !mesh->parallelogram(q.origin, q.e1, q.e2, q.n, q.inv_area))
            return std::nullopt;
        q.radiance = m_radiance->eval(Vec2f(0.f, 0.f));
        return q;
    }
    std::optional<SphereEmitter> sphere() const {
        // (With uv wanted, sample_li fills them: no closed form then.)
        const std::optional<SphereGeometry> g = m_shape ? sphere_geometry(*m_shape) : std::nullopt;
        if (!m_radiance->is_constant() || !g || m_shape->sample_uv) return std::nullopt;
        return SphereEmitter{g->center, float(g->radius), g->flip_normals, m_radiance->eval(Vec2f(0.f, 0.f))};
    }

    // Mitsuba samples a spatially varying radiance texture by the texture's own
    // density mapped onto the shape; here the shape's solid-angle sampling is
    // used for both cases (same expectation, different noise).
    std::pair<LightSample, Spectrum> sample_li(Point3f ref, Vec2f u, float) const override {
        // Filled in place (one named result): returning a copied pair is slower.
        std::pair<LightSample, Spectrum> result;
        LightSample &ls = result.first;
        auto [ss, pdf] = m_shape->sample_solid_angle(ref, u);
        ls.p = ss.p;
        ls.n = ss.n;
        Vec3f d = ss.p - ref;
        ls.dist = norm(d);
        if (!(pdf > 0.f) || !(ls.dist > 0.f)) return result;
        ls.d = d / ls.dist;
        ls.pdf = pdf;
        if (dot(ls.n, ls.d) >= 0.f) return result; // back side of a one-sided emitter
        result.second = m_radiance->eval(ss.uv) / pdf;
        return result;
    }

    float pdf_li(Point3f ref, const SurfaceInteraction &si, Vec3f d) const override {
        if (dot(si.n, d) >= 0.f) return 0.f;
        return m_shape->pdf_solid_angle(ref, si);
    }

    /// Emission towards `w` from the front side (Mitsuba tests the shading normal).
    Spectrum eval(const SurfaceInteraction &si, Vec3f w) const override {
        return dot(si.sh_frame.n, w) > 0.f ? m_radiance->eval(si.uv) : Spectrum();
    }

private:
    std::shared_ptr<Texture> m_radiance;
    const Shape *m_shape = nullptr;
};

std::optional<QuadEmitter> quad_emitter(const Light &light) {
    if (auto *a = dynamic_cast<const AreaLight *>(&light)) return a->quad();
    return std::nullopt;
}

std::optional<SphereEmitter> sphere_emitter(const Light &light) {
    if (auto *a = dynamic_cast<const AreaLight *>(&light)) return a->sphere();
    return std::nullopt;
}

MVPT_REGISTER_PLUGIN("emitter", "area", [](const Properties &p, const LoadContext &) {
    return std::make_shared<AreaLight>(p);
});

} // namespace mvpt
