// A perspective or thin-lens camera in one pose as plain data, and the shift geometry of
// docs/multiview-path-tracing.md §3–§4 computed from it. It is the one implementation
// behind PerspectiveCamera::shift_geometry, and lets multi-view path tracing shift a
// sample to every static view in one loop over contiguous data, without a virtual call
// or a pose evaluation per view.
#pragma once

#include "camera.h"
#include "cameras/camera_pose.h"

namespace mvpt {

/// Pose and intrinsics of a perspective (pinhole) or thin-lens camera at one instant.
struct CameraProjection {
    CameraPose pose;
    float near_clip = 1e-2f, far_clip = 1e4f;
    float aperture_radius = 0.f;   ///< 0 for a pinhole
    float inv_focus_distance = 0.f;
    float tan_x = 1.f, tan_y = 1.f; ///< half-extent of the plane z = 1 seen by the full film
    float ppo_x = 0.f, ppo_y = 0.f; ///< principal point offset (fractions of the film size)
    float width = 1.f, height = 1.f; ///< full film size in pixels
    float film_distance = 1.f;     ///< f = (W/2) / tan(fov_x/2), in pixels

    /// Film position (pixels) of the point (qx, qy) of the plane z = 1 (Mitsuba's sample_to_camera
    /// inverted: film x grows to the camera's right = -x, film y downwards = -y).
    Vec2f film_from_plane(float qx, float qy) const {
        return {(0.5f * (1.f - qx / tan_x) - ppo_x) * width, (0.5f * (1.f - qy / tan_y) - ppo_y) * height};
    }
};

/// Camera::shift_geometry for camera `c` (design doc §3 projection through the focus plane,
/// §4 film density G = f^2 cos(phi) / (cos^3(theta) d^2)). False when y's camera-space depth
/// lies outside [near, far].
inline bool shift_geometry(const CameraProjection &c, Point3f y, Normal3f n_y, Vec2f lens, ShiftGeometry *out) {
    Point3f p = c.pose.to_camera(y);
    if (!(p.z >= c.near_clip && p.z <= c.far_clip)) return false;
    // Thin lens: the ray u -> p meets the focus plane z = f_d at P = u + (p - u) f_d / p.z, and
    // q = P / f_d = u (1/f_d - 1/p.z) + p / p.z; a pinhole (u = 0) gives q = p / p.z.
    float inv_z = 1.f / p.z;
    float qx = p.x * inv_z, qy = p.y * inv_z;
    Vec3f u_cam(0.f, 0.f, 0.f);
    if (c.aperture_radius > 0.f) {
        float k = c.aperture_radius * (c.inv_focus_distance - inv_z);
        qx += lens.x * k;
        qy += lens.y * k;
        u_cam = Vec3f(lens.x * c.aperture_radius, lens.y * c.aperture_radius, 0.f);
        out->lens_point = c.pose.to_world(u_cam);
    } else {
        out->lens_point = c.pose.origin;
    }
    out->film = c.film_from_plane(qx, qy);
    // theta from the camera-space vector lens point -> y; phi between n_y and y -> u.
    Vec3f w_cam = p - u_cam;
    float d2 = squared_norm(w_cam), d = std::sqrt(d2);
    float cos_theta = w_cam.z / d;
    Vec3f w = y - out->lens_point;
    float cos_phi = absdot(n_y, w) / (norm(n_y) * norm(w));
    out->density = sqr(c.film_distance) * cos_phi / (cos_theta * cos_theta * cos_theta * d2);
    out->visible_length = d - c.near_clip / cos_theta;
    return true;
}

} // namespace mvpt
