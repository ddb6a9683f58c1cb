// Keyframed transforms (Mitsuba 3's <animation> syntax): scale and translation
// interpolate linearly, rotation by quaternion slerp; end poses hold outside.
#pragma once

#include "transform.h"

#include <string>
#include <vector>

namespace mvpt {

struct Quaternion {
    double w = 1, x = 0, y = 0, z = 0;
};

/// One keyframe decomposed as T * R * S.
struct TransformKey {
    float time = 0;
    Vec3f scale{1, 1, 1};
    Quaternion rotation;
    Vec3f translation{0, 0, 0};
    Transform original;
};

class AnimatedTransform {
public:
    AnimatedTransform() = default;
    /// A transform that does not move.
    explicit AnimatedTransform(const Transform &t);
    /// Keys need not be sorted; fails with `error` set (and returns false) on a shear.
    static bool from_keys(std::vector<std::pair<float, Transform>> keys, AnimatedTransform &out, std::string &error);

    bool is_animated() const { return m_keys.size() > 1; }
    Transform eval(float time) const;
    /// Time range covered by the keyframes (equal ends for a static transform).
    float t_begin() const { return m_keys.empty() ? 0.f : m_keys.front().time; }
    float t_end() const { return m_keys.empty() ? 0.f : m_keys.back().time; }
    const std::vector<TransformKey> &keys() const { return m_keys; }

private:
    std::vector<TransformKey> m_keys;
};

} // namespace mvpt
