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

/// One pixel of a splat buffer: one cache line.
struct alignas(64) SplatPixel {
    int64_t c[SplatChannels] = {};
};

/// A value rounded to the fixed-point grid (to nearest, in the default rounding mode).
inline int64_t to_fixed(double x) { return std::llrint(x * SplatScale); }

/// One thread's splat buffer: per view, one SplatPixel per pixel, allocated on first use.
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
        int64_t *p = pixel_of(slot, pixel);
        p[0] += to_fixed(lw_r);
        p[1] += to_fixed(lw_g);
        p[2] += to_fixed(lw_b);
        p[6] += to_fixed(w);
        p[7] += 1;
    }
    /// Add the native-only radiance E that fits.
    void add_native(int slot, uint32_t pixel, const Spectrum &e) {
        int64_t *p = pixel_of(slot, pixel);
        p[3] += to_fixed(e[0]);
        p[4] += to_fixed(e[1]);
        p[5] += to_fixed(e[2]);
    }
    /// The buffer of view `slot` (empty if nothing was splatted there).
    std::vector<SplatPixel> &view(int slot) { return m_data[slot]; }

private:
    int64_t *pixel_of(int slot, uint32_t pixel) {
        std::vector<SplatPixel> &buf = m_data[slot];
        if (buf.empty()) buf.resize(m_pixels[slot]);
        return buf[pixel].c;
    }
    std::vector<size_t> m_pixels;
    std::vector<std::vector<SplatPixel>> m_data;
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
