// Camera paths for animated shots: keyframes (time + look-at pose, or a 4x4 camera-to-world
// matrix) read from a JSON file and interpolated linearly or smoothly.
//
// Key file (times in seconds of scene time; "up" defaults to [0, 1, 0]; "matrix" is row-major,
// 16 numbers or 4 rows, a rigid camera-to-world transform as in Mitsuba's <matrix>):
//   {"interpolation": "smooth",
//    "keys": [{"time": 0, "position": [0, 1, 5], "target": [0, 0, 0], "up": [0, 1, 0]},
//             {"time": 2, "matrix": [1, 0, 0, 0,  0, 1, 0, 0,  0, 0, 1, 5,  0, 0, 0, 1]}]}
// A bare array of keys is accepted too.
//
// Interpolation works on (position, target, up); a matrix key becomes position = its
// translation, target = position + its z axis (one unit ahead), up = its y axis. `linear`
// interpolates the three linearly, `smooth` (the default) by a cubic Hermite spline with
// Catmull-Rom tangents for non-uniform key times, m_k = (p_{k+1} - p_{k-1}) / (t_{k+1} - t_{k-1})
// (one-sided differences at the ends), which passes through every key and is C1 in time.
// The pose at time t is then look_at(position, target, up); outside the keys the end poses hold.
#pragma once

#include "../core/transform.h"
#include "json.h"

#include <filesystem>
#include <string>
#include <vector>

namespace mvpt {

/// How a camera path blends its keys.
enum class PathInterpolation { Linear, Smooth };

/// One keyframe: a look-at pose at a time, and where it was written.
struct CameraKey {
    float time = 0.f;
    Vec3f position{0.f}, target{0.f, 0.f, 1.f}, up{0.f, 1.f, 0.f};
    FileLoc loc;
};

class CameraPath {
public:
    /// Read keys from a parsed key file; errors name the file:line:col of the offending value.
    static CameraPath from_json(const JsonValue &doc);
    /// Read and parse a key file.
    static CameraPath read(const std::filesystem::path &path);

    /// Interpolated position, target and up at `time`.
    void eval(float time, Vec3f *position, Vec3f *target, Vec3f *up) const;
    /// Camera-to-world pose at `time` (Mitsuba's look_at); a degenerate interpolated pose
    /// (target on the position, or up along the view direction) is a SceneError.
    Transform pose(float time) const;

    const std::vector<CameraKey> &keys() const { return m_keys; }
    PathInterpolation interpolation = PathInterpolation::Smooth;
    /// Where the interpolation was set in the file (for error messages), or the file itself.
    FileLoc loc;

private:
    std::vector<CameraKey> m_keys;
};

/// "linear" or "smooth" -> PathInterpolation; false for anything else.
bool parse_path_interpolation(const std::string &name, PathInterpolation *out);

} // namespace mvpt
