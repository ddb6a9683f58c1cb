// Prefix shift T_{l->k} of multi-view path tracing and its validity tests
// (docs/multiview-path-tracing.md §3), with the film densities G of §4.
#pragma once

#include "../../core/math.h"
#include "../../render/camera.h"

#include <algorithm>
#include <cstdint>
#include <vector>

namespace mvpt {

/// A rendered view as the multi-view method sees it.
struct MvView {
    const Camera *camera = nullptr;
    uint32_t scene_index = 0; ///< index among the scene's sensors (the sampler's view number)
    float t0 = 0.f, dt = 0.f; ///< shutter open time and length
};

/// Sensor `scene_index` of a scene, `cam`, as the method sees it.
inline MvView mv_view(const Camera &cam, uint32_t scene_index) {
    return {&cam, scene_index, cam.shutter_open, cam.shutter_close - cam.shutter_open};
}

/// The shared first vertex y of a native sample of view l.
struct MvVertex {
    Point3f p;
    Normal3f n;     ///< geometric normal
    float time = 0.f; ///< scene time of the native sample
    Vec2f lens;     ///< xi on the unit disk
    float side = 0.f; ///< n . (u_l - y): the side of the surface the native lens point is on
    /// A point in a medium (§10): n is zero, G is per unit volume and length, every side faces.
    bool in_medium = false;
};

/// Which test rejected a shift (§3, cheap tests first); counted per view.
enum class ShiftTest : int { Time = 0, Orientation, Image, Bsdf, Visibility, Selection, Count };

/// Whether strategy j -> k can produce k's samples with a density in time (§3 test 1), a
/// symmetric relation. When shapes move (`scene_moves`) the time is kept: zero-length
/// shutters (Dirac deltas) pair only with each other. Otherwise time is mapped affinely
/// between shutters, a bijection when both have length or both have none; a shutter of
/// length facing an instant is fine only when that camera does not move (then its time
/// changes nothing and integrates out), since otherwise many of its times would map to one.
inline bool time_compatible(const MvView &j, const MvView &k, bool scene_moves) {
    if ((j.dt == 0.f) == (k.dt == 0.f)) return true;
    if (scene_moves) return false;
    const MvView &timed = j.dt > 0.f ? j : k;
    return !timed.camera->is_animated();
}

/// Whether some pair of `views` can share a native sample at all in time (§3 test 1): a pair
/// that is time_compatible and, when shapes move (`scene_moves`), whose shutters overlap over a
/// positive length or are one instant (shutters that only touch, as a shot's frames with a
/// shutter of 1.0, share a set of times of measure zero). False for fewer than two views.
inline bool views_share_in_time(const std::vector<MvView> &views, bool scene_moves) {
    if (views.size() < 2) return false;
    // Without moving shapes two views of the same kind (instant or timed) always pair.
    if (!scene_moves) return views.size() > 2 || time_compatible(views[0], views[1], false);
    std::vector<std::pair<float, float>> timed; // (open, close)
    std::vector<float> instants;
    for (const MvView &v : views)
        if (v.dt > 0.f) timed.emplace_back(v.t0, v.t0 + v.dt);
        else instants.push_back(v.t0);
    std::sort(timed.begin(), timed.end());
    std::sort(instants.begin(), instants.end());
    for (size_t i = 1; i < instants.size(); ++i)
        if (instants[i] == instants[i - 1]) return true;
    float close = -INFINITY; // the latest close of the shutters opened so far
    for (const auto &[t0, t1] : timed) {
        if (t0 < close) return true;
        close = std::max(close, t1);
    }
    return false;
}

/// Time of the shifted sample in view `k` (§3 test 1). When shapes move (`scene_moves`) the
/// time is kept and must lie in k's shutter; otherwise it is mapped affinely between the
/// shutters, so every view can share. False when the time test fails.
inline bool shift_time(const MvView &l, const MvView &k, float t, bool scene_moves, float *t_k) {
    if (!time_compatible(l, k, scene_moves)) return false;
    if (scene_moves) {
        if (k.dt == 0.f ? t != k.t0 : !(t >= k.t0 && t <= k.t0 + k.dt)) return false;
        *t_k = t;
        return true;
    }
    *t_k = l.dt > 0.f && k.dt > 0.f ? k.t0 + (t - l.t0) * (k.dt / l.dt) : k.t0 + 0.5f * k.dt;
    return true;
}

/// Density factor of time between strategies (§5): dt_k / dt_j when time is kept, 1 under the
/// affine map or between zero-length shutters.
inline float time_density_ratio(const MvView &k, const MvView &j, bool scene_moves) {
    return scene_moves && j.dt > 0.f ? k.dt / j.dt : 1.f;
}

} // namespace mvpt
