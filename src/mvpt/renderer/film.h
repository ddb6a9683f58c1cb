// The film of one view: the accumulators over passes of every rendering method. Per pixel,
// each pass gives one estimate v, added to the pixel's count, sum and sum of squared
// deviations; the image is the mean of the estimates and its variance comes from their
// spread. An estimate may weigh less than one (a thinned pass of multi-view path tracing, of
// variance about 1/q that of a whole pass, weighs q): the mean is then weighted by precision.
// Path tracing's estimate is a path's radiance (add). Multi-view path tracing's comes from a
// pass's fixed-point sums (fold, docs/multiview-path-tracing.md §5), and its film keeps what
// its estimators and adaptive maps (§8) need of the passes so far.
#pragma once

#include "../integrators/multiview/mv_estimator.h"
#include "../integrators/multiview/mvpath.h"
#include "../render/splat_film.h"

#include <cstdint>
#include <vector>

namespace mvpt {

class StateReader;
class StateWriter;

struct Film {
    int width = 0, height = 0;       ///< the crop window's size
    std::vector<uint32_t> count;     ///< estimates per pixel (path tracing: samples; multi-view: passes)
    std::vector<double> sum;         ///< sum of v, 3 per pixel
    std::vector<float> m2;           ///< sum of squared deviations of v from the running mean (Welford), 3 per pixel
    uint64_t nonfinite = 0;          ///< samples or contributions dropped as not finite (or too large)
    /// What the estimates' weights lack of one each, the same for every pixel: the sum of 1 - q
    /// over the thinned passes (multi-view; 0 for path tracing). Pixel p's weight is count - short_weight.
    double short_weight = 0.0;

    // Multi-view path tracing alone (empty for path tracing). Per pixel, a pass's estimate v is
    // (balance) W*L + E + beta (1 - sum W), beta from the earlier passes, or (weighted) W*L + E.
    MvEstimator estimator = MvEstimator::Balance;
    bool control_variate = true;
    std::vector<float> w_sum;        ///< sum of W (1 per pass in expectation for the balance estimator)
    /// Weighted estimator: sums of W*L and of E (3 per pixel) and of W, its own terms.
    std::vector<double> lw, e, w;
    /// For the adaptive maps (empty when they never run), per pixel: the sum and the sum of
    /// squares of the passes' native-only part E (mean over channels), and the sum of squares
    /// of the shared part S = v - E (its sum is that of v minus that of E).
    std::vector<float> e_sum, e_sq, s_sq;
    std::vector<uint32_t> native;    ///< native samples taken so far (the next sample index)
    std::vector<uint32_t> received;  ///< contributions received (saturating)
    /// n_k(i) of the current pass over the view's sample window: the crop window's pixels
    /// and, around them, `margin` pixels of the filter's reach that take one sample per pass.
    std::vector<uint16_t> map;
    /// Balance estimator with its control variate: the film's first pass is held until the
    /// second is folded, so that each takes the other's control variate
    /// (docs/multiview-path-tracing.md §5, "The first two passes"): meanwhile the pixels' count
    /// is 0, `sum` holds their W*L + E, `w_sum` their W and `e_sum` (if kept) E's mean.
    bool holding = false;
    /// The view's filter has negative lobes: W sums terms of both signs, and a held pass's
    /// ratio (W*L + E) / W is used only where W >= SignedRatioMinW (fold).
    bool signed_filter = false;
    static constexpr double SignedRatioMinW = 0.25;
    int margin = 0;                  ///< of the map
    double level = 0.0;              ///< the level c the adaptive map was last solved for
    uint64_t map_total = 0;          ///< the sum of n over the crop window this pass (its native samples)

    Film() = default;
    /// Path tracing's film.
    Film(int width, int height);
    /// Multi-view path tracing's film; `adaptive`: keep the statistics of the adaptive maps.
    Film(int width, int height, int margin, MvEstimator estimator, bool control_variate, bool adaptive);
    /// Bytes per pixel of a film (for memory estimates).
    static size_t bytes_per_pixel(bool multiview, MvEstimator estimator, bool adaptive);
    bool multiview() const { return !native.empty(); }
    size_t pixels() const { return count.size(); }

    /// The estimates' total weight at pixel p.
    double weight(size_t p) const { return double(count[p]) - short_weight; }
    /// Adds the estimate `v` (RGB) of weight `wt` to pixel p: `wt v` to its sum and, by
    /// Welford's update (West's, weighted), `wt` times the product of the deviations from the
    /// mean before and after it to the squared deviations.
    void add(size_t p, const double v[3], double wt = 1.0) {
        const double k = weight(p);
        const double to_before = count[p] > 0 ? 1.0 / k : 0.0, to_after = 1.0 / (k + wt);
        for (int c = 0; c < 3; ++c) {
            const double before = sum[3 * p + c] * to_before;
            sum[3 * p + c] += wt * v[c];
            m2[3 * p + c] += float(wt * (v[c] - before) * (v[c] - sum[3 * p + c] * to_after));
        }
        ++count[p];
    }
    /// Pixel p's estimate (RGB) and the variance of that mean (RGB).
    void develop(size_t p, float rgb[3], float variance[3]) const;
    /// The samples pixel p has taken (multi-view: native samples).
    uint32_t samples(size_t p) const { return multiview() ? native[p] : count[p]; }

    /// Multi-view: n of crop-window pixel p this pass.
    uint16_t n(size_t p) const {
        const size_t x = p % size_t(width), y = p / size_t(width), w = size_t(width + 2 * margin);
        return map[(y + size_t(margin)) * w + x + size_t(margin)];
    }
    /// Multi-view: sets n of the crop window's pixels (row-major, as many as pixels()).
    void set_map(const std::vector<uint16_t> &crop);
    /// Multi-view: pixels [begin, end) of a pass whose sums `pass` holds from index `offset` on
    /// (read and cleared), each as one estimate (the sums times `scale`: mv_pass_estimate) of
    /// weight `wt` (a thinned pass: scale 1/q, weight q; the caller adds 1 - q to short_weight
    /// once every pixel is folded).
    /// While `holding`, the pixels' held pass is added first, each of the two with the other's
    /// ratio (W*L + E) / W as beta.
    void fold(MvPassFilm &pass, uint32_t offset, size_t begin, size_t end, double scale = 1.0, double wt = 1.0);
    /// Multi-view: pixels [begin, end) of the film's first pass (whole), from `pass` as fold reads
    /// it, held (the caller sets `holding` once every pixel is).
    void hold(MvPassFilm &pass, uint32_t offset, size_t begin, size_t end);
    /// Multi-view: the held pass's pixels [begin, end) added as estimates without a control
    /// variate (no second pass came; the caller then clears `holding`).
    void release(size_t begin, size_t end);
    /// Multi-view: mean over passes of the sum of W of pixel p (1 in expectation for the balance estimator).
    float weight_sum(size_t p) const { return count[p] ? float(double(w_sum[p]) / weight(p)) : 0.f; }

    /// Every accumulator into a state file, and back (a StateError if the file's do not fit).
    void save(StateWriter &out) const;
    void load(StateReader &in);
    /// A StateError unless what load read is what `passes` passes can have produced: sums
    /// finite, at most `passes` estimates, a sample map of at most `max_native` per pixel.
    void check_loaded(int passes, int max_native) const;
    /// Adds the accumulators of `other` (the same view, disjoint passes): sums add, the
    /// squared deviations combine with the difference of the means (Chan et al.).
    void merge(const Film &other);

private:
    /// Pixel p's sums of `pass` (from `offset`), read and cleared, its native samples and the
    /// contributions it received counted.
    SplatEntry take_pass(MvPassFilm &pass, uint32_t offset, size_t p);
    /// Pixel p's held pass, taken out of the accumulators that held it.
    MvPassEstimate take_held(size_t p);
    /// Adds pass estimate `est` of weight `wt` to pixel p: the estimate and what the estimators
    /// and the adaptive maps keep of it.
    void add_pass(size_t p, const MvPassEstimate &est, double wt);
};

} // namespace mvpt
