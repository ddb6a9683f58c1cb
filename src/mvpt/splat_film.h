// The splats of one pass of multi-view path tracing (docs/multiview-path-tracing.md §5):
// fixed-point sums of every view's pixels, shared by all render threads, with a
// write-combining cache per thread in front of them.
//
// Contributions land in any view's pixel from any thread, so a floating-point sum would
// depend on the order in which threads add them. Integer addition is associative: each
// contribution is rounded once to a multiple of 2^-30 and summed exactly, so the images are
// bit-identical for any thread count. The pass sums exist once per view, whatever the number
// of threads; a thread keeps only a cache of fixed size (SplatCache) that sums the
// contributions to a pixel while they arrive close together (a pixel receives the native
// samples of every view that sees its region, and a thread renders a region in every view
// in a row) and hands them to the shared sums with one atomic add per channel.
#pragma once

#include "core/math.h"

#include <atomic>
#include <cmath>
#include <cstdint>
#include <vector>

namespace mvpt {

inline constexpr double SplatScale = 0x1p30;
/// Largest magnitude a single contribution may have (larger ones are dropped and counted).
inline constexpr double SplatMax = 0x1p32;

/// A value rounded to the fixed-point grid (to nearest, in the default rounding mode).
inline int64_t to_fixed(double x) { return std::llrint(x * SplatScale); }

/// The fixed-point sums of one view-pixel: W*L + E (E: the native-only radiance, added by the
/// pixel's own native samples), W, E itself (its mean over the channels, or RGB: see
/// MvPassFilm) and the number of contributions. In a SplatCache it is keyed by the
/// view-pixel's index in the MvPassFilm (one cache line per entry).
struct alignas(64) SplatEntry {
    int64_t lw[3] = {}, w = 0, e[3] = {};
    uint32_t key = UINT32_MAX; ///< view-pixel index; UINT32_MAX: empty
    uint32_t count = 0;
};

/// The sums of the current pass of every rendered view, one array over all views' pixels
/// (view slot s starts at offset(s)); any thread adds to them (atomically), the pass's fold
/// reads and clears them. E is kept as the mean of its channels (what the adaptive maps
/// need), or in RGB (`e_rgb`: the weighted estimator separates it from W*L).
class MvPassFilm {
public:
    /// The shared part of a pixel's sums, W*L + E and W (half a cache line).
    struct alignas(32) Shared {
        int64_t lw[3] = {}, w = 0;
    };

    MvPassFilm() = default;
    /// Sums for views of `pixels[s]` pixels (at most 2^32 - 2 view-pixels in all).
    MvPassFilm(const std::vector<size_t> &pixels, bool e_rgb);
    uint32_t offset(int slot) const { return m_offset[size_t(slot)]; }
    size_t views() const { return m_offset.size() - 1; }
    size_t size() const { return m_count.size(); }
    /// Channels of E: 1 (the mean of R, G, B) or 3.
    int e_channels() const { return m_e_channels; }

    /// Adds the sums of a cache entry (any thread, concurrently).
    void add(const SplatEntry &e);
    /// The sums of view-pixel `key`, read and cleared (one thread per view-pixel, no other adds).
    SplatEntry take(uint32_t key);
    /// Bytes per view-pixel (for memory estimates).
    static size_t bytes_per_pixel(bool e_rgb) {
        return sizeof(Shared) + (e_rgb ? 3 : 1) * sizeof(int64_t) + sizeof(uint32_t);
    }

private:
    std::vector<uint32_t> m_offset;
    int m_e_channels = 1;
    std::vector<Shared> m_shared;
    std::vector<int64_t> m_e; ///< E, e_channels per pixel
    std::vector<uint32_t> m_count;
};

/// One thread's write-combining cache in front of an MvPassFilm: direct-mapped, a fixed
/// number of entries whatever the views and film sizes. An entry displaced by another
/// view-pixel is added to the film; flush() adds the rest at the end of a pass.
class SplatCache {
public:
    static constexpr size_t DefaultEntries = size_t(1) << 15; // 2 MiB
    explicit SplatCache(MvPassFilm &film, size_t entries = DefaultEntries);

    /// Whether a value may be splatted: finite and below SplatMax in magnitude.
    static bool fits(float x) { return std::abs(x) < float(SplatMax); }
    static bool fits(const Spectrum &s) { return fits(s[0]) & fits(s[1]) & fits(s[2]); }

    /// The entry of pixel `pixel` of view `slot`, emptied (its old sums added to the film) if
    /// it held another view-pixel.
    SplatEntry &at(int slot, uint32_t pixel) {
        const uint32_t key = m_offset[size_t(slot)] + pixel;
        SplatEntry &e = m_entries[(m_base[size_t(slot)] + pixel) & m_mask];
        if (e.key != key) [[unlikely]] replace(e, key);
        return e;
    }
    /// Add one shared contribution W*L, W; false (nothing added) when a value does not fit.
    bool add(int slot, uint32_t pixel, const Spectrum &lw, float w) {
        if (!(fits(lw) & fits(w))) return false;
        add_fitting(at(slot, pixel), lw[0], lw[1], lw[2], w);
        return true;
    }
    /// The same for the native view's own pixel, with the radiance E only it estimates.
    bool add(int slot, uint32_t pixel, const Spectrum &lw, float w, const Spectrum &e) {
        const Spectrum sum = lw + e;
        if (!(fits(lw) & fits(w) & fits(e) & fits(sum))) return false;
        SplatEntry &entry = at(slot, pixel);
        add_fitting(entry, sum[0], sum[1], sum[2], w);
        if (m_e_rgb)
            for (int c = 0; c < 3; ++c) entry.e[c] += to_fixed(e[c]);
        else
            entry.e[0] += to_fixed((e[0] + e[1] + e[2]) * (1.f / 3.f));
        return true;
    }
    /// Add W*L (per channel) and W that fit, and count the contribution.
    static void add_fitting(SplatEntry &e, float lw_r, float lw_g, float lw_b, float w) {
        e.lw[0] += to_fixed(lw_r);
        e.lw[1] += to_fixed(lw_g);
        e.lw[2] += to_fixed(lw_b);
        e.w += to_fixed(w);
        ++e.count;
    }
    /// Adds every entry to the film and empties the cache (the end of a pass).
    void flush();
    /// Empties the cache without adding anything (a pass that is abandoned).
    void discard();

private:
    void replace(SplatEntry &e, uint32_t key);

    MvPassFilm *m_film;
    bool m_e_rgb;
    std::vector<uint32_t> m_offset; ///< the film's offset of each view
    std::vector<uint32_t> m_base;   ///< where each view's pixels start in the cache (spread apart)
    std::vector<SplatEntry> m_entries;
    uint32_t m_mask;
};

/// Where one thread's contributions go: its splat cache, and per view a count of the
/// contributions dropped as not finite (or beyond SplatMax).
struct MvSplatSink {
    SplatCache &cache;
    uint64_t *dropped;
    /// A contribution W*L, W to a view that shares the sample.
    void shared(int slot, uint32_t pixel, const Spectrum &lw, float w) {
        if (!cache.add(slot, pixel, lw, w)) ++dropped[slot];
    }
    /// The contribution to the native view's own pixel, with its native-only radiance E
    /// (emission seen directly, paths through purely specular first vertices) divided by n_l.
    void native(int slot, uint32_t pixel, const Spectrum &lw, float w, const Spectrum &e) {
        if (!cache.add(slot, pixel, lw, w, e)) ++dropped[slot];
    }
};

} // namespace mvpt
