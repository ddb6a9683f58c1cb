// Perspective (pinhole) and thin-lens cameras, Mitsuba's `perspective` and
// `thinlens` sensors: camera space has +z forward, +x left, +y up.
#include "../../scene/plugin.h"
#include "../camera.h"
#include "sensor_common.h"

#include <cmath>

namespace mvpt {

class PerspectiveCamera final : public Camera {
public:
    PerspectiveCamera(const Properties &props, bool thin_lens) {
        read_sensor_common(*this, props);
        auto at = props.get_animated_transform("to_world");
        if (at.is_animated()) props.fail("to_world", "animated sensors are not supported yet");
        m_to_world = at.eval(0.f);
        // Rows of the linear part must be orthonormal: no scale or shear (Mitsuba's has_scale, tolerance 1e-3).
        const Matrix4 &m = m_to_world.matrix();
        for (int i = 0; i < 3; ++i)
            for (int j = i; j < 3; ++j) {
                double dot_ij = m.m[i][0] * m.m[j][0] + m.m[i][1] * m.m[j][1] + m.m[i][2] * m.m[j][2];
                if (std::abs(dot_ij - (i == j ? 1.0 : 0.0)) > 1e-3)
                    props.fail("to_world", "'to_world' of a sensor must be a rigid motion: scale or shear is not allowed");
            }
        m_near = props.get_float("near_clip", 1e-2f);
        m_far = props.get_float("far_clip", 1e4f);
        if (!(m_near > 0.f) || !(m_far > m_near))
            props.fail("near_clip", "need 0 < near_clip < far_clip, got " + std::to_string(m_near) + " and " + std::to_string(m_far));
        m_focus_distance = props.get_float("focus_distance", m_far);
        if (thin_lens) {
            m_aperture_radius = props.get_float("aperture_radius");
            if (!(m_aperture_radius >= 0.f)) props.fail("aperture_radius", "'aperture_radius' must be >= 0");
            if (!(m_focus_distance > 0.f)) props.fail("focus_distance", "'focus_distance' must be > 0");
        }
        float aspect = float(film.width) / float(film.height);
        std::string axis = props.get_string("fov_axis", "x");
        float fov;
        if (props.has("fov")) {
            if (props.has("focal_length")) props.fail("focal_length", "give either 'fov' or 'focal_length', not both");
            fov = props.get_float("fov");
        } else {
            // 35 mm film equivalent: the focal length fixes the diagonal field of view.
            std::string fl = props.get_string("focal_length", "50mm");
            float f = std::strtof(fl.c_str(), nullptr);
            if (!(f > 0.f)) props.fail("focal_length", "cannot read focal_length '" + fl + "' (expected e.g. \"50mm\")");
            fov = 2.f * std::atan(std::sqrt(36.f * 36.f + 24.f * 24.f) / (2.f * f)) * 180.f / Pi;
            axis = "diagonal";
        }
        if (!(fov > 0.f && fov < 180.f)) props.fail("fov", "'fov' must lie in (0, 180) degrees, got " + std::to_string(fov));
        float t = std::tan(deg_to_rad(fov) * 0.5f);
        if (axis == "smaller") axis = aspect > 1.f ? "y" : "x";
        else if (axis == "larger") axis = aspect > 1.f ? "x" : "y";
        if (axis == "x") {
            m_tan_x = t; m_tan_y = t / aspect;
        } else if (axis == "y") {
            m_tan_y = t; m_tan_x = t * aspect;
        } else if (axis == "diagonal") {
            float diag = std::sqrt(float(film.width) * film.width + float(film.height) * film.height);
            m_tan_x = t * film.width / diag; m_tan_y = t * film.height / diag;
        } else {
            props.fail("fov_axis", "'fov_axis' must be x, y, diagonal, smaller or larger, got '" + axis + "'");
        }
        m_origin = m_to_world.point(Point3f(0.f));
    }

    Ray generate_ray(Vec2f film_pos, Vec2f lens, float time) const override {
        // Point on the plane z = 1 in camera space.
        float u = film_pos.x / float(film.width), v = film_pos.y / float(film.height);
        Vec3f near_p(-(2.f * u - 1.f) * m_tan_x, -(2.f * v - 1.f) * m_tan_y, 1.f);
        Vec3f o_cam(0.f), d_cam;
        if (m_aperture_radius > 0.f) {
            o_cam = Vec3f(lens.x * m_aperture_radius, lens.y * m_aperture_radius, 0.f);
            d_cam = normalize(near_p * m_focus_distance - o_cam);
        } else {
            d_cam = normalize(near_p);
        }
        float inv_z = 1.f / d_cam.z;
        Ray r;
        r.o = m_aperture_radius > 0.f ? m_to_world.point(o_cam) : m_origin;
        r.d = normalize(m_to_world.vector(d_cam));
        r.tmin = m_near * inv_z;
        r.tmax = m_far * inv_z;
        r.time = time;
        return r;
    }

    float lens_radius() const override { return m_aperture_radius; }

private:
    Transform m_to_world;
    Point3f m_origin;
    float m_near, m_far, m_focus_distance, m_aperture_radius = 0.f;
    float m_tan_x = 1.f, m_tan_y = 1.f;
};

MVPT_REGISTER_PLUGIN("sensor", "perspective", [](const Properties &p, const LoadContext &) {
    return std::make_shared<PerspectiveCamera>(p, false);
});
MVPT_REGISTER_PLUGIN("sensor", "thinlens", [](const Properties &p, const LoadContext &) {
    return std::make_shared<PerspectiveCamera>(p, true);
});

} // namespace mvpt
