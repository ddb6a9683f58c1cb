// Adaptive native-sample maps n_k(i) of multi-view path tracing
// (docs/multiview-path-tracing.md §8).
#pragma once

#include <cstdint>
#include <vector>

namespace mvpt {

/// What the map of one view is computed from: per-pixel statistics over `passes` passes of
/// the two parts of a pass estimate (luminance): the native-only part E (emission seen
/// directly, specular first vertices: only the pixel's own native samples estimate it) and
/// the shared part S (everything that other views' samples also bring).
struct AdaptiveInput {
    int width = 0, height = 0, passes = 0;
    const double *v_sum = nullptr;                ///< sums over passes of the pass estimate (RGB)
    const float *e_sum = nullptr, *e_sq = nullptr; ///< sums over passes of E and E^2 (mean of RGB)
    const float *s_sq = nullptr;                  ///< sums over passes of S^2, S = mean(v) - E
    const uint32_t *native = nullptr;             ///< native samples taken so far
    const uint32_t *received = nullptr;           ///< contributions received so far
    double previous_level = 0.0;                  ///< the level c of the last map (0: none)
    double eps = 0.0;                             ///< lower bound of the eps below
};

/// Set the native counts of the next pass so that the expected relative variance of a pass
/// estimate becomes even across the image. A pixel with n native samples and r contributions
/// per pass from other views has pass variance a/n + b/(n + r), a and b the variances of one
/// native-only and one shared contribution (estimated from the spread of E and S over the
/// passes times the counts of the passes); n_i solves (a/n + b/(n + r)) / (m^2 + eps) = c,
/// rounded and clamped to [1, max_n], with c chosen so that the map's total is at most
/// `budget` (>= the pixel count). a, b and r are smoothed over 3x3 pixels; eps =
/// max(in.eps, (view mean / 10)^2) judges dark pixels by absolute error. Without
/// statistics (fewer than 2 passes, a black image) the budget is spread evenly. Returns the
/// level c (0 without statistics); passed back as `previous_level`, it brackets the next
/// pass's search, whose statistics change little from pass to pass. Runs in parallel over
/// blocks of pixels of a fixed size: the map does not depend on the number of threads.
double adapt_native_map(const AdaptiveInput &in, int max_n, double budget, std::vector<uint16_t> &map);

} // namespace mvpt
