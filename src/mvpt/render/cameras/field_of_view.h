// The field of view of a perspective sensor (Mitsuba 3's `parse_fov`): `fov` + `fov_axis`,
// or a 35 mm equivalent `focal_length`, as the tangents of the half angles along x and y.
// Shared by the perspective/thinlens cameras and the camera rigs (which need the frustum
// to shear views onto a common focal plane).
#pragma once

#include "../../core/math.h"
#include "../../core/properties.h"

#include <cmath>
#include <cstdlib>
#include <string>

namespace mvpt {

/// tan(fov_x / 2) and tan(fov_y / 2) of a sensor with a `width` x `height` film; pixels are
/// square for every fov_axis (tan_x / W == tan_y / H). Errors go through `props.fail`.
inline void read_field_of_view(const Properties &props, int width, int height, float *tan_x, float *tan_y) {
    float aspect = float(width) / float(height);
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
        *tan_x = t; *tan_y = t / aspect;
    } else if (axis == "y") {
        *tan_y = t; *tan_x = t * aspect;
    } else if (axis == "diagonal") {
        float diag = std::sqrt(float(width) * width + float(height) * height);
        *tan_x = t * width / diag; *tan_y = t * height / diag;
    } else {
        props.fail("fov_axis", "'fov_axis' must be x, y, diagonal, smaller or larger, got '" + axis + "'");
    }
}

} // namespace mvpt
