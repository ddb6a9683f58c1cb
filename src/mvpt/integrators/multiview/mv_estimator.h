// One pixel's estimate in one pass of multi-view path tracing (docs/multiview-path-tracing.md
// §5), from the pass's fixed-point sums of the pixel (render/splat_film.h): what the film
// (renderer/film.h) accumulates over passes.
#pragma once

#include "../../render/splat_film.h"
#include "mvpath.h"

namespace mvpt {

/// A pixel's pass: its estimate v (RGB), its sum of weights W and its native-only part E
/// (mean over channels); for the weighted estimator also its own terms per channel, the sum
/// of W*L without E and E.
struct MvPassEstimate {
    double v[3] = {}, w = 0.0, e_mean = 0.0;
    double lw[3] = {}, e[3] = {};
};

/// The estimate of a pixel whose pass sums are `t`. Balance: W*L + E, plus with the control
/// variate beta (1 - sum W), `beta` (RGB, null without it) the mean of the earlier passes'
/// estimates: E[sum W] = 1 exactly when D sums over every valid strategy, and beta is
/// independent of this pass, so the estimate stays unbiased while the noise of how many
/// contributions happened to land in the pixel cancels. Weighted: W*L + E, whose ratio the
/// film forms over all passes. `scale` multiplies the sums: that of a pass cut short, whose
/// regions were rendered each with probability 1/scale (docs/multiview-path-tracing.md, "A
/// first pass cut short").
inline MvPassEstimate mv_pass_estimate(const SplatEntry &t, MvEstimator estimator, const double *beta,
                                       double scale = 1.0) {
    MvPassEstimate out;
    const double to_real = scale / SplatScale;
    out.w = double(t.w) * to_real;
    if (estimator == MvEstimator::Balance) {
        for (int c = 0; c < 3; ++c) out.v[c] = double(t.lw[c]) * to_real + (beta ? beta[c] * (1.0 - out.w) : 0.0);
        out.e_mean = double(t.e[0]) * to_real; // (the balance sums keep only E's mean over channels)
        return out;
    }
    for (int c = 0; c < 3; ++c) {
        out.v[c] = double(t.lw[c]) * to_real;
        out.lw[c] = double(t.lw[c] - t.e[c]) * to_real;
        out.e[c] = double(t.e[c]) * to_real;
        out.e_mean += out.e[c] / 3.0;
    }
    return out;
}

} // namespace mvpt
