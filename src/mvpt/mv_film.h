// Accumulators of multi-view path tracing over passes (docs/multiview-path-tracing.md §5,
// §8), per view: what the estimators and the adaptive maps need of the passes so far, and
// the fold that adds one pass (its fixed-point sums, splat_film.h) to them.
#pragma once

#include "integrators/mvpath.h"
#include "splat_film.h"

#include <cstdint>
#include <vector>

namespace mvpt {

/// What a pass adds to the pixel estimates of path tracing's film: sums over passes of the
/// pass estimate v (3 per pixel), of v^2, and the passes per pixel.
struct PassSums {
    double *sum, *sum_sq;
    uint32_t *count;
};

/// The accumulators of one view over all passes.
struct MvFilm {
    MvEstimator estimator = MvEstimator::Balance;
    bool control_variate = true;
    /// Balance: per pixel, sums over passes of W*L + E (RGB) and of W, in single precision:
    /// they only give the ratio estimate beta of the control variate (any value independent of
    /// the pass keeps the estimate unbiased) and the mean sum of W.
    std::vector<float> ratio;
    /// Weighted: sums of W*L and of E (3 per pixel) and of W, the estimator's own terms.
    std::vector<double> lw, e, w;
    /// For the adaptive maps, per pixel: the sum and the sum of squares of the passes'
    /// native-only part E (mean over channels), and the sum of squares of the shared part
    /// S = v - E (its sum is that of v minus that of E).
    std::vector<float> e_sum, e_sq, s_sq;
    std::vector<uint32_t> native;   ///< native samples taken so far (the next sample index)
    std::vector<uint32_t> received; ///< contributions received (saturating)
    /// n_k(i) of the current pass over the view's sample window: the crop window's pixels
    /// and, around them, `margin` pixels of the filter's reach that take one sample per pass.
    std::vector<uint16_t> map;
    int width = 0, height = 0, margin = 0; ///< the crop window's size; the margin of the map
    double level = 0.0;             ///< the level c the adaptive map was last solved for

    MvFilm() = default;
    MvFilm(int width, int height, int margin, MvEstimator estimator, bool control_variate);
    size_t pixels() const { return native.size(); }
    /// n of crop-window pixel p this pass.
    uint16_t n(size_t p) const {
        const size_t x = p % size_t(width), y = p / size_t(width), w = size_t(width + 2 * margin);
        return map[(y + size_t(margin)) * w + x + size_t(margin)];
    }
    /// Sets n of the crop window's pixels (row-major, as many as pixels()).
    void set_map(const std::vector<uint16_t> &crop);
    /// Bytes per pixel of a film (for memory estimates).
    static size_t bytes_per_pixel(MvEstimator estimator);

    /// Pixels [begin, end) of the pass whose sums `pass` holds from index `offset` on (read and
    /// cleared): the pass estimate v into `out` (balance with the control variate: v = W*L + E
    /// + beta (1 - W), beta from the earlier passes; else W*L + E) and the accumulators above.
    void fold(MvPassFilm &pass, uint32_t offset, size_t begin, size_t end, PassSums out);
    /// Mean over passes of the sum of W of pixel p (1 in expectation for the balance estimator).
    float weight_sum(size_t p, uint32_t passes) const;
};

} // namespace mvpt
