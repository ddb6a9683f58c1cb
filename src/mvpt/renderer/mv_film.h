// Accumulators of multi-view path tracing over passes (docs/multiview-path-tracing.md §5,
// §8), per view: the pixel estimates, what the estimators and the adaptive maps need of the
// passes so far, and the fold that adds one pass (its fixed-point sums, splat_film.h).
#pragma once

#include "../integrators/mvpath.h"
#include "../render/splat_film.h"

#include <cstdint>
#include <vector>

namespace mvpt {

class StateReader;
class StateWriter;

/// The accumulators of one view over all passes. Per pixel, each pass gives one estimate v
/// (balance: W*L + E + beta (1 - sum W), beta from the earlier passes; weighted: W*L + E); the
/// image is their mean and its variance comes from their spread, as for path tracing.
struct MvFilm {
    MvEstimator estimator = MvEstimator::Balance;
    bool control_variate = true;
    uint32_t passes = 0;            ///< passes folded so far (every pixel takes part in each)
    std::vector<double> sum;        ///< sum of v, 3 per pixel
    std::vector<float> m2;          ///< sum of squared deviations of v from the running mean (Welford), 3 per pixel
    std::vector<float> w_sum;       ///< sum of W (1 per pass in expectation for the balance estimator)
    /// Weighted estimator: sums of W*L and of E (3 per pixel) and of W, its own terms.
    std::vector<double> lw, e, w;
    /// For the adaptive maps (empty when they never run), per pixel: the sum and the sum of
    /// squares of the passes' native-only part E (mean over channels), and the sum of squares
    /// of the shared part S = v - E (its sum is that of v minus that of E).
    std::vector<float> e_sum, e_sq, s_sq;
    std::vector<uint32_t> native;   ///< native samples taken so far (the next sample index)
    std::vector<uint32_t> received; ///< contributions received (saturating)
    /// n_k(i) of the current pass over the view's sample window: the crop window's pixels
    /// and, around them, `margin` pixels of the filter's reach that take one sample per pass.
    std::vector<uint16_t> map;
    int width = 0, height = 0, margin = 0; ///< the crop window's size; the margin of the map
    double level = 0.0;             ///< the level c the adaptive map was last solved for
    uint64_t nonfinite = 0;         ///< contributions dropped as not finite (or too large)

    MvFilm() = default;
    /// `adaptive`: keep the statistics of the adaptive maps.
    MvFilm(int width, int height, int margin, MvEstimator estimator, bool control_variate, bool adaptive);
    /// Bytes per pixel of a film (for memory estimates).
    static size_t bytes_per_pixel(MvEstimator estimator, bool adaptive);
    size_t pixels() const { return native.size(); }
    /// n of crop-window pixel p this pass.
    uint16_t n(size_t p) const {
        const size_t x = p % size_t(width), y = p / size_t(width), w = size_t(width + 2 * margin);
        return map[(y + size_t(margin)) * w + x + size_t(margin)];
    }
    /// Sets n of the crop window's pixels (row-major, as many as pixels()).
    void set_map(const std::vector<uint16_t> &crop);
    /// The sum of n over the crop window this pass (its native samples).
    uint64_t map_total = 0;

    /// Pixels [begin, end) of a pass whose sums `pass` holds from index `offset` on (read and
    /// cleared) into the accumulators; `passes` counts it once every pixel is folded.
    void fold(MvPassFilm &pass, uint32_t offset, size_t begin, size_t end);
    /// Pixel p's estimate (RGB) and the variance of that mean (RGB).
    void develop(size_t p, float rgb[3], float variance[3]) const;
    /// Every accumulator into a state file, and back (a StateError if the file's do not fit).
    void save(StateWriter &out) const;
    void load(StateReader &in);
    /// Adds the accumulators of `other` (the same view, disjoint passes): sums add, the
    /// squared deviations combine with the difference of the means (Chan et al.).
    void merge(const MvFilm &other);
    /// Mean over passes of the sum of W of pixel p (1 in expectation for the balance estimator).
    float weight_sum(size_t p) const { return passes ? float(double(w_sum[p]) / passes) : 0.f; }
};

} // namespace mvpt
