// Adaptive native-sample maps n_k(i) of multi-view path tracing
// (docs/multiview-path-tracing.md §8).
#pragma once

#include <cstdint>
#include <vector>

namespace mvpt {

/// What the map of one view is computed from: per-pixel statistics over `passes` passes.
struct AdaptiveInput {
    int width = 0, height = 0, passes = 0;
    const double *sum = nullptr, *sum_sq = nullptr; ///< RGB sums of the pass estimates and of their squares
    const uint32_t *native = nullptr;               ///< native samples taken so far
    const uint64_t *received = nullptr;             ///< contributions received so far
};

/// Set the native counts of the next pass so that the expected relative variance of a pass
/// estimate becomes even across the image. With u_i the variance of one contribution relative
/// to the squared pixel value and r_i the contributions other views bring per pass, a pass
/// has relative variance ~ u_i / (n_i + r_i); n_i = u_i / c - r_i, rounded and clamped to
/// [1, max_n], with c chosen so that the map's total is at most `budget` (>= the pixel
/// count). u and r are smoothed over 3x3 pixels; pixels darker than a tenth of the view's
/// mean are judged by absolute error. Without statistics (fewer than 2 passes, a black
/// image) the budget is spread evenly.
void adapt_native_map(const AdaptiveInput &in, int max_n, double budget, std::vector<uint16_t> &map);

} // namespace mvpt
