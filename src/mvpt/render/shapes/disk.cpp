// Analytic disk (Mitsuba's `disk`): the unit disk in the z = 0 plane with
// normal +z, placed by `to_world`; uv = (r, phi / 2pi).
#include "../../core/warp.h"
#include "analytic.h"
#include "instance.h"
#include "mesh.h"

namespace mvpt {

class Disk final : public AnalyticShape {
public:
    Disk(const Properties &props, const Transform &to_world) {
        m_to_world = to_world;
        if (props.get_bool("flip_normals", false)) m_to_world = m_to_world * Transform::scale({1.f, 1.f, -1.f});
        if (!m_to_world.matrix().is_finite()) props.fail("to_world", "to_world must be finite");
        m_to_object = m_to_world.inverse();
        m_normal = m_to_world.normal({0.f, 0.f, 1.f});
        float area = Pi * norm(cross(m_to_world.vector({1.f, 0.f, 0.f}), m_to_world.vector({0.f, 1.f, 0.f})));
        if (!(area > 0.f) || !std::isfinite(area)) props.fail("to_world", "the disk's to_world is degenerate");
        m_normal = normalize(m_normal);
        m_inv_area = 1.f / area;
        attach_shape_children(*this, props);
    }

    double intersect_t(const double o[3], const double d[3], double tmin, double tmax) const override {
        double lo[3], ld[3];
        xform_point(m_to_object.matrix(), o, lo);
        xform_vector(m_to_object.matrix(), d, ld);
        double t = -lo[2] / ld[2];
        if (!(t >= tmin && t <= tmax)) return std::nan("");
        double x = lo[0] + t * ld[0], y = lo[1] + t * ld[1];
        return x * x + y * y <= 1.0 ? t : std::nan("");
    }

    void fill_interaction(const Ray &ray, float t, uint32_t, Vec2f, SurfaceInteraction &si) const override {
        double o[3] = {ray.o.x, ray.o.y, ray.o.z}, d[3] = {ray.d.x, ray.d.y, ray.d.z}, lo[3], ld[3];
        xform_point(m_to_object.matrix(), o, lo);
        xform_vector(m_to_object.matrix(), d, ld);
        double tl = -lo[2] / ld[2];
        float x = float(lo[0] + tl * ld[0]), y = float(lo[1] + tl * ld[1]);
        si.t = t;
        si.p = m_to_world.point({x, y, 0.f}); // exactly in the disk's plane
        fill_local(x, y, si.uv, si.sh_frame);
        si.n = m_normal;
    }

    /// dp/du = (cos phi, sin phi, 0), dp/dv = 2 pi r (-sin phi, cos phi, 0) at the local point
    /// r (cos phi, sin phi, 0) (u = r, v = phi / 2 pi).
    std::pair<Vec3f, Vec3f> uv_partials(uint32_t, Point3f p) const override {
        const Point3f local = m_to_object.point(p);
        const float r = std::sqrt(local.x * local.x + local.y * local.y);
        const float c = r > 0.f ? local.x / r : 1.f, s = r > 0.f ? local.y / r : 0.f;
        return {m_to_world.vector({c, s, 0.f}), m_to_world.vector(Vec3f(-s, c, 0.f) * (2.f * Pi * r))};
    }

    float area() const override { return 1.f / m_inv_area; }
    BoundingBox bounds() const override {
        BoundingBox b;
        for (float x : {-1.f, 1.f})
            for (float y : {-1.f, 1.f}) b.expand(m_to_world.point({x, y, 0.f}));
        return b;
    }

    ShapeSample sample_area(Vec2f u) const override {
        Vec2f p = warp::square_to_uniform_disk_concentric(u);
        ShapeSample s;
        s.p = m_to_world.point({p.x, p.y, 0.f});
        s.n = m_normal;
        Frame unused;
        fill_local(p.x, p.y, s.uv, unused);
        s.pdf_a = m_inv_area;
        return s;
    }

private:
    void fill_local(float x, float y, Vec2f &uv, Frame &frame) const {
        float r = std::sqrt(x * x + y * y);
        float v = std::atan2(y, x) * InvTwoPi;
        if (v < 0.f) v += 1.f;
        uv = {r, v};
        float cos_phi = r != 0.f ? x / r : 1.f, sin_phi = r != 0.f ? y / r : 0.f;
        frame = frame_from_dpdu(m_normal, m_to_world.vector({cos_phi, sin_phi, 0.f}));
    }

    Transform m_to_world, m_to_object;
    Normal3f m_normal;
    float m_inv_area = 1.f;
};

MVPT_REGISTER_PLUGIN("shape", "disk", [](const Properties &props, const LoadContext &) {
    return make_maybe_animated(props, [&](const Transform &to_world) { return std::make_shared<Disk>(props, to_world); });
});

} // namespace mvpt
