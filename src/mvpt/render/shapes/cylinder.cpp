// Analytic open cylinder (Mitsuba's `cylinder`, no end caps): axis p0 -> p1,
// a radius, and `to_world`; uv = (phi / 2pi, height fraction).
#include "../../core/warp.h"
#include "analytic.h"
#include "instance.h"
#include "mesh.h"

namespace mvpt {

class Cylinder final : public AnalyticShape {
public:
    Cylinder(const Properties &props, const Transform &to_world) {
        float radius = props.get_float("radius", 1.f);
        Point3f p0 = props.get_vector("p0", Point3f(0.f)), p1 = props.get_vector("p1", Point3f(0.f, 0.f, 1.f));
        m_flip_normals = props.get_bool("flip_normals", false);
        Vec3f axis = p1 - p0;
        float length = norm(axis);
        if (!(length > 0.f) || !std::isfinite(length)) props.fail("p1", "the cylinder's p0 and p1 must differ");
        // Object space is the unit cylinder x^2 + y^2 = 1, z in [0, 1].
        Frame f(axis / length);
        Matrix4 frame;
        for (int i = 0; i < 3; ++i) {
            frame.m[i][0] = f.s[i];
            frame.m[i][1] = f.t[i];
            frame.m[i][2] = f.n[i];
        }
        m_to_world = to_world * Transform::translate(p0) * Transform(frame, frame.transpose()) *
                     Transform::scale({radius, radius, length});
        if (!m_to_world.matrix().is_finite()) props.fail("to_world", "to_world must be finite");
        m_to_object = m_to_world.inverse();
        float r_w = norm(m_to_world.vector({1.f, 0.f, 0.f})), l_w = norm(m_to_world.vector({0.f, 0.f, 1.f}));
        if (!(r_w > 0.f) || !(l_w > 0.f)) props.fail("radius", "the cylinder's radius must be non-zero");
        if (m_to_world.flips_handedness()) m_flip_normals = !m_flip_normals;
        m_inv_area = 1.f / (2.f * Pi * r_w * l_w);
        attach_shape_children(*this, props);
    }

    double intersect_t(const double o[3], const double d[3], double tmin, double tmax) const override {
        double lo[3], ld[3];
        xform_point(m_to_object.matrix(), o, lo);
        xform_vector(m_to_object.matrix(), d, ld);
        double tn, tf;
        if (!solve_quadratic(ld[0] * ld[0] + ld[1] * ld[1], 2.0 * (ld[0] * lo[0] + ld[1] * lo[1]),
                             lo[0] * lo[0] + lo[1] * lo[1] - 1.0, tn, tf))
            return std::nan("");
        for (double t : {tn, tf}) {
            double z = lo[2] + t * ld[2];
            if (t >= tmin && t <= tmax && z >= 0.0 && z <= 1.0) return t;
        }
        return std::nan("");
    }

    void fill_interaction(const Ray &ray, float t, uint32_t, Vec2f, SurfaceInteraction &si) const override {
        double o[3] = {ray.o.x, ray.o.y, ray.o.z}, d[3] = {ray.d.x, ray.d.y, ray.d.z}, lo[3], ld[3], tn, tf;
        xform_point(m_to_object.matrix(), o, lo);
        xform_vector(m_to_object.matrix(), d, ld);
        double th = t;
        if (solve_quadratic(ld[0] * ld[0] + ld[1] * ld[1], 2.0 * (ld[0] * lo[0] + ld[1] * lo[1]),
                            lo[0] * lo[0] + lo[1] * lo[1] - 1.0, tn, tf))
            th = std::abs(tn - t) <= std::abs(tf - t) ? tn : tf;
        double x = lo[0] + th * ld[0], y = lo[1] + th * ld[1], z = lo[2] + th * ld[2], r = std::sqrt(x * x + y * y);
        if (r > 0) { x /= r; y /= r; } // re-projected onto the surface
        si.t = t;
        set_surface(float(x), float(y), float(z), si.p, si.n, si.uv, &si.sh_frame);
    }

    /// dp/du = 2 pi (-y, x, 0), dp/dv = (0, 0, 1) at the local point (x, y, z).
    std::pair<Vec3f, Vec3f> uv_partials(uint32_t, Point3f p) const override {
        const Point3f local = m_to_object.point(p);
        return {m_to_world.vector(Vec3f(-local.y, local.x, 0.f) * (2.f * Pi)), m_to_world.vector({0.f, 0.f, 1.f})};
    }

    float area() const override { return 1.f / m_inv_area; }
    BoundingBox bounds() const override {
        Vec3f x1 = m_to_world.vector({1.f, 0.f, 0.f}), x2 = m_to_world.vector({0.f, 1.f, 0.f});
        Vec3f x(std::sqrt(x1.x * x1.x + x2.x * x2.x), std::sqrt(x1.y * x1.y + x2.y * x2.y),
                std::sqrt(x1.z * x1.z + x2.z * x2.z));
        Point3f p0 = m_to_world.point(Point3f(0.f)), p1 = m_to_world.point({0.f, 0.f, 1.f});
        BoundingBox b;
        for (Point3f p : {p0 - x, p0 + x, p1 - x, p1 + x}) b.expand(p);
        return b;
    }

    ShapeSample sample_area(Vec2f u) const override {
        float phi = 2.f * Pi * u.y;
        ShapeSample s;
        set_surface(std::cos(phi), std::sin(phi), u.x, s.p, s.n, s.uv, nullptr);
        s.pdf_a = m_inv_area;
        return s;
    }

private:
    void set_surface(float x, float y, float z, Point3f &p, Normal3f &n, Vec2f &uv, Frame *frame) const {
        p = m_to_world.point({x, y, z});
        float phi = std::atan2(y, x);
        if (phi < 0.f) phi += 2.f * Pi;
        uv = {phi * InvTwoPi, z};
        Vec3f dp_du = m_to_world.vector(Vec3f(-y, x, 0.f) * (2.f * Pi)), dp_dv = m_to_world.vector({0.f, 0.f, 1.f});
        n = normalize(cross(dp_du, dp_dv));
        if (m_flip_normals) n = -n;
        if (frame) *frame = frame_from_dpdu(n, dp_du);
    }

    Transform m_to_world, m_to_object;
    float m_inv_area = 1.f;
    bool m_flip_normals = false;
};

MVPT_REGISTER_PLUGIN("shape", "cylinder", [](const Properties &props, const LoadContext &) {
    return make_maybe_animated(props, [&](const Transform &to_world) { return std::make_shared<Cylinder>(props, to_world); });
});

} // namespace mvpt
