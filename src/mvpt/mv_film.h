// Films of multi-view path tracing: per-thread splat buffers in fixed point, merged
// once per pass into per-view accumulators (docs/multiview-path-tracing.md §5, §8).
//
// Contributions land in any view's pixel from any thread, so a floating-point sum
// would depend on the order in which threads add them. Integer addition is
// associative: each contribution is rounded once to a multiple of 2^-30, summed
// exactly, and the images are bit-identical for any thread count.
#pragma once

#include "core/math.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace mvpt {

/// Channels of a splat: W*L (3), native-only radiance E (3), W, contribution count.
inline constexpr int SplatChannels = 8;
inline constexpr double SplatScale = 0x1p30;
/// Largest magnitude a single contribution may have (larger ones are dropped and counted).
inline constexpr double SplatMax = 0x1p32;

/// What every shared contribution adds to a pixel: W*L and W, half a cache line (the
/// contributions of a sample land in as many views' pixels: a smaller buffer misses less).
struct alignas(32) SplatPixel {
    int64_t lw[3] = {}, w = 0;
};

/// A value rounded to the fixed-point grid (to nearest, in the default rounding mode).
inline int64_t to_fixed(double x) { return std::llrint(x * SplatScale); }

/// One view's part of a splat buffer: per pixel W*L and W, the native-only radiance E
/// (added once per native sample) and the number of contributions, in separate arrays.
struct SplatView {
    std::vector<SplatPixel> shared;
    std::vector<int64_t> native; ///< E, 3 per pixel
    std::vector<uint32_t> count;
    /// Bytes per pixel of an allocated view (for memory estimates).
    static constexpr size_t bytes_per_pixel = sizeof(SplatPixel) + 3 * sizeof(int64_t) + sizeof(uint32_t);
    bool empty() const { return shared.empty(); }
    void allocate(size_t pixels) {
        shared.assign(pixels, SplatPixel{});
        native.assign(3 * pixels, 0);
        count.assign(pixels, 0);
    }
    /// Channel c (SplatChannels' order) of pixel p.
    int64_t channel(size_t p, int c) const {
        return c < 3 ? shared[p].lw[c] : c < 6 ? native[3 * p + size_t(c - 3)] : c == 6 ? shared[p].w : int64_t(count[p]);
    }
    /// Adds `o` (of the same size) into this view and zeroes it.
    void take(SplatView &o) {
        for (size_t p = 0; p < shared.size(); ++p) {
            for (int c = 0; c < 3; ++c) shared[p].lw[c] += o.shared[p].lw[c];
            shared[p].w += o.shared[p].w;
            count[p] += o.count[p];
        }
        for (size_t i = 0; i < native.size(); ++i) native[i] += o.native[i];
        std::fill(o.shared.begin(), o.shared.end(), SplatPixel{});
        std::fill(o.native.begin(), o.native.end(), 0);
        std::fill(o.count.begin(), o.count.end(), 0u);
    }
};

/// One thread's splat buffer: per view, a SplatView allocated on first use.
class SplatBuffer {
public:
    explicit SplatBuffer(const std::vector<size_t> &pixels_per_view) : m_pixels(pixels_per_view), m_data(pixels_per_view.size()) {}

    /// Whether a value may be splatted: finite and below SplatMax in magnitude.
    static bool fits(float x) { return std::abs(x) < float(SplatMax); }
    static bool fits(const Spectrum &s) { return fits(s[0]) & fits(s[1]) & fits(s[2]); }

    /// Add one shared contribution W*L, W; false (nothing added) when a value does not fit.
    bool add(int slot, uint32_t pixel, const Spectrum &lw, float w) {
        if (!(fits(lw) & fits(w))) return false;
        add_fitting(slot, pixel, lw[0], lw[1], lw[2], w);
        return true;
    }
    /// The same for the native view's own pixel, with the radiance E only it estimates.
    bool add(int slot, uint32_t pixel, const Spectrum &lw, float w, const Spectrum &e) {
        if (!fits(e) || !add(slot, pixel, lw, w)) return false;
        add_native(slot, pixel, e);
        return true;
    }
    /// Add W*L (per channel) and W that fit, and count the contribution.
    void add_fitting(int slot, uint32_t pixel, float lw_r, float lw_g, float lw_b, float w) {
        SplatView &v = view_of(slot);
        SplatPixel &p = v.shared[pixel];
        p.lw[0] += to_fixed(lw_r);
        p.lw[1] += to_fixed(lw_g);
        p.lw[2] += to_fixed(lw_b);
        p.w += to_fixed(w);
        ++v.count[pixel];
    }
    /// Add the native-only radiance E that fits.
    void add_native(int slot, uint32_t pixel, const Spectrum &e) {
        int64_t *p = &view_of(slot).native[3 * size_t(pixel)];
        p[0] += to_fixed(e[0]);
        p[1] += to_fixed(e[1]);
        p[2] += to_fixed(e[2]);
    }
    /// The buffer of view `slot` (empty if nothing was splatted there).
    SplatView &view(int slot) { return m_data[slot]; }
    /// The buffer of view `slot`, allocated on first use: for adding to it.
    SplatView &view_of(int slot) {
        SplatView &v = m_data[slot];
        if (v.empty()) v.allocate(m_pixels[slot]);
        return v;
    }

private:
    std::vector<size_t> m_pixels;
    std::vector<SplatView> m_data;
};

/// Where one thread's contributions go: its splat buffer, and per view a count of the
/// contributions dropped as not finite (or beyond SplatMax).
struct MvSplatSink {
    SplatBuffer &buffer;
    uint64_t *dropped;
    /// A contribution W*L, W to a view that shares the sample.
    void shared(int slot, uint32_t pixel, const Spectrum &lw, float w) {
        if (!buffer.add(slot, pixel, lw, w)) ++dropped[slot];
    }
    /// The contribution to the native view's own pixel, with its native-only radiance E
    /// (emission seen directly, paths through purely specular first vertices) divided by n_l.
    void native(int slot, uint32_t pixel, const Spectrum &lw, float w, const Spectrum &e) {
        if (!buffer.add(slot, pixel, lw, w, e)) ++dropped[slot];
    }
};

/// Accumulators of one view over all passes.
struct MvFilm {
    std::vector<double> lw, e;     ///< sums of W*L and of native-only radiance (3 per pixel)
    std::vector<double> w;         ///< sum of W
    // (The sums of the balance estimates of the passes and of their squares live in the
    // renderer's FilmBuffer, as for path tracing.)
    /// Per pixel, luminance of the passes' native-only part E and shared part S (balance
    /// estimate minus E): sums and sums of squares, for the adaptive maps.
    std::vector<double> e_sum, e_sq, s_sum, s_sq;
    std::vector<uint32_t> native;  ///< native samples taken so far (the next sample index)
    std::vector<uint64_t> received;///< contributions received
    std::vector<uint16_t> map;     ///< n_k(i) of the current pass
    double level = 0.0;            ///< the level c the adaptive map was last solved for

    explicit MvFilm(size_t n = 0) : lw(3 * n, 0.0), e(3 * n, 0.0), w(n, 0.0), e_sum(n, 0.0), e_sq(n, 0.0), s_sum(n, 0.0), s_sq(n, 0.0), native(n, 0), received(n, 0), map(n, 1) {}
};

} // namespace mvpt
