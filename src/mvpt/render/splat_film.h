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

#include "../core/math.h"
#include "../core/simd.h"
#include "filter.h"

#include <array>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace mvpt {

inline constexpr double SplatScale = 0x1p30;
/// Largest magnitude a single contribution may have (larger ones are dropped and counted).
inline constexpr double SplatMax = 0x1p32;

/// A value rounded to the fixed-point grid (to nearest, in the default rounding mode).
inline int64_t to_fixed(double x) { return std::llrint(x * SplatScale); }

/// Adds to_fixed of the four values v (W*L in RGB, W; each below SplatMax in magnitude) to
/// `sums` (an entry's lw[3], w). Where every |v| < 2^21 as one vector: x = v 2^30 + 1.5 2^52
/// holds v 2^30 rounded to an integer (to nearest even) in its low bits, exactly llrint's
/// result; other values take to_fixed per channel.
[[gnu::always_inline]] inline void add_fixed(int64_t *sums, simd::f32x4 v) {
    using namespace simd;
    const f32x4 mag = bit_cast<f32x4>(bit_cast<i32x4>(v) & 0x7fffffff);
    const i32x4 exact = mag < (f32x4{} + 0x1p21f);
    if (exact[0] & exact[1] & exact[2] & exact[3]) {
        const f64x4 magic = f64x4{} + 0x1.8p52;
        const f64x4 x = __builtin_convertvector(v, f64x4) * (f64x4{} + SplatScale) + magic;
        store(sums, load<i64x4>(sums) + (bit_cast<i64x4>(x) - bit_cast<i64x4>(magic)));
    } else {
        for (int c = 0; c < 4; ++c) sums[c] += to_fixed(v[c]);
    }
}

/// The fixed-point sums of one view-pixel: W*L + E (E: the native-only radiance, added by the
/// pixel's own native samples), W, E itself (its mean over the channels, or RGB: see
/// MvPassFilm) and the number of contributions. In a SplatCache it is keyed by the
/// view-pixel's index in the MvPassFilm (one cache line per entry).
struct alignas(64) SplatEntry {
    int64_t lw[3] = {}, w = 0, e[3] = {};
    uint32_t key = UINT32_MAX; ///< view-pixel index; UINT32_MAX: empty
    uint32_t count = 0;
};
static_assert(offsetof(SplatEntry, w) == 3 * sizeof(int64_t), "add_fixed adds lw[3], w as one vector");

/// Where a view's contributions land: its crop window (full-film pixels) and its pixel filter
/// (design doc §5, "Pixel filters"). A contribution at film position x adds h(x - c_i) times
/// its value to every pixel i of the window whose centre c_i lies within the filter's radius,
/// h the normalised filter (ReconstructionFilter::eval_1d, signed for filters with negative
/// lobes); with the box filter that is the pixel that holds x, with weight 1.
struct SplatFootprint {
    /// The largest filter radius (pixels) that multi-view path tracing splats with.
    static constexpr int MaxRadius = 16;
    int crop_x = 0, crop_y = 0, width = 0, height = 0;
    const ReconstructionFilter *filter = nullptr; ///< nullptr or a box: one pixel, weight 1
    float radius = 0.5f, peak = 1.f;              ///< the filter's radius and the largest |h(x, y)|
    /// The filter's table per axis (TabulatedFilter::table) and bins per pixel.
    const float *table = nullptr;
    size_t table_size = 0;
    float table_scale = 0.f;
    /// Sampler::dimension_key of the view's splat dimension: the number that decides which of a
    /// contribution's small taps are kept (SplatCache::add_footprint).
    uint64_t tap_key = 0;
    /// A box-filtered window of width x height pixels at the film's origin.
    static SplatFootprint box(int width, int height) {
        return {0, 0, width, height, nullptr, 0.5f, 1.f, nullptr, 0, 0.f, 0};
    }
    /// The crop window and filter of a film, for the view whose splat dimension has `tap_key`.
    static SplatFootprint of(int crop_x, int crop_y, int width, int height, const ReconstructionFilter &filter,
                             uint64_t tap_key);
    bool is_box() const { return filter == nullptr; }
    /// The splat cache entries a contribution adds to, on average over the positions in a pixel
    /// (SplatCache::add_footprint; 1 for a box): a part of its cost.
    double mean_writes() const;
    size_t pixels() const { return size_t(width) * size_t(height); }
};

/// The sums of the current pass of every rendered view, one array over all views' pixels
/// (view slot s starts at offset(s)); any thread adds to them (atomically), the pass's fold
/// reads and clears them. E is kept as the mean of its channels (what the adaptive maps
/// need), or in RGB (`e_rgb`: the weighted estimator separates it from W*L).
class MvPassFilm {
public:
    /// The shared part of a pixel's sums, W*L + E and W (half a cache line).
    struct alignas(32) Shared {
        int64_t lw[3], w;
    };

    MvPassFilm() = default;
    /// Sums for views of the windows `views` (at most 2^32 - 2 view-pixels in all), zeroed in
    /// parallel (on the calling task arena's threads): on one core, the kernel's zeroing of
    /// the pages of a display's worth of views (100 of 960x540: 2.3 GB) took seconds.
    MvPassFilm(const std::vector<SplatFootprint> &views, bool e_rgb);
    uint32_t offset(int slot) const { return m_offset[size_t(slot)]; }
    const SplatFootprint &footprint(int slot) const { return m_footprint[size_t(slot)]; }
    size_t views() const { return m_offset.size() - 1; }
    size_t size() const { return m_size; }
    /// Channels of E: 1 (the mean of R, G, B) or 3.
    int e_channels() const { return m_e_channels; }

    /// Adds the sums of a cache entry (any thread, concurrently).
    void add(const SplatEntry &e);
    /// Starts loading, for writing, the sums of view-pixel `key` (before add).
    [[gnu::always_inline]] void prefetch(uint32_t key) const {
        __builtin_prefetch(&m_shared[key], 1);
        __builtin_prefetch(&m_e[size_t(m_e_channels) * key], 1);
        __builtin_prefetch(&m_count[key], 1);
    }
    /// The sums of view-pixel `key`, read and cleared (one thread per view-pixel, no other adds).
    SplatEntry take(uint32_t key);
    /// Bytes per view-pixel (for memory estimates).
    static size_t bytes_per_pixel(bool e_rgb) {
        return sizeof(Shared) + (e_rgb ? 3 : 1) * sizeof(int64_t) + sizeof(uint32_t);
    }

private:
    std::vector<uint32_t> m_offset;
    std::vector<SplatFootprint> m_footprint;
    int m_e_channels = 1;
    size_t m_size = 0;
    std::unique_ptr<Shared[]> m_shared;
    std::unique_ptr<int64_t[]> m_e; ///< E, e_channels per pixel
    std::unique_ptr<uint32_t[]> m_count;
};

/// One thread's write-combining cache in front of an MvPassFilm: direct-mapped, a fixed
/// number of entries whatever the views and film sizes. An entry displaced by another
/// view-pixel is added to the film; flush() adds the rest at the end of a pass. Each view owns
/// a block of entries, as wide as the widest window (a power of two) and at least 16 rows high,
/// on which its pixels lie as on a torus, (x mod width, y mod height): a band of 16 rows of a
/// view's pixels, where a region of tiles shares its samples, then has an entry per pixel,
/// without conflicts between views (with many views a block is narrower than the window).
class SplatCache {
public:
    /// The entries for `views` views: a block of 32 x 32 per view (a region of tiles and its
    /// spread across the views), from 2^15 (2 MiB) to 2^17 (8 MiB).
    static size_t entries_for(size_t views) {
        size_t n = size_t(1) << 15;
        while (n < (size_t(1) << 17) && n < views * 1024) n *= 2;
        return n;
    }
    /// A cache of `entries` (a power of two; 0: entries_for the film's views).
    explicit SplatCache(MvPassFilm &film, size_t entries = 0);

    /// Whether a value may be splatted: finite and below SplatMax in magnitude.
    static bool fits(float x) { return std::abs(x) < float(SplatMax); }
    static bool fits(const Spectrum &s) { return fits(s[0]) & fits(s[1]) & fits(s[2]); }

    /// The entry of pixel `pixel` (window index) at (x, y) of the window of view `slot`, emptied
    /// (its old sums added to the film) if it held another view-pixel.
    SplatEntry &at(int slot, uint32_t pixel, uint32_t x, uint32_t y) {
        const uint32_t key = m_offset[size_t(slot)] + pixel;
        SplatEntry &e = m_entries[index(slot, x, y)];
        if (e.key != key) [[unlikely]] replace(e, key);
        return e;
    }
    /// The same for the pixel of view `slot`'s window that holds film position `film`.
    SplatEntry &at(int slot, uint32_t pixel, Vec2f film) {
        const int *crop = &m_crop[2 * size_t(slot)];
        return at(slot, pixel, uint32_t(int(film.x) - crop[0]), uint32_t(int(film.y) - crop[1]));
    }
    /// Whether the cache outgrows a core's L2 cache (more than 2 MiB, from 33 views on): then a
    /// sample's sharing views' entries, far apart, are mostly not in the core's caches, and
    /// prefetching them pays (81 views: -13 % time; 25 views: +3 % without this test).
    bool large() const { return m_entries.size() > (size_t(1) << 15); }
    /// Starts loading the entry that at(slot, pixel, film) will return. Always inlined: GCC
    /// takes a function whose only effect is a prefetch for pure, and drops calls to it.
    [[gnu::always_inline]] void prefetch(int slot, Vec2f film) const {
        const int *crop = &m_crop[2 * size_t(slot)];
        __builtin_prefetch(&m_entries[index(slot, uint32_t(int(film.x) - crop[0]), uint32_t(int(film.y) - crop[1]))]);
    }
    /// Add one shared contribution W*L, W at film position `film` (of the pixel with window
    /// index `pixel`, which the box filter uses) of the native sample whose Sampler::sample_hash
    /// is `sample`; false (nothing added) when a value does not fit.
    bool add(int slot, uint32_t pixel, Vec2f film, uint64_t sample, const Spectrum &lw, float w) {
        const float v[4] = {lw[0], lw[1], lw[2], w};
        if (!fits(v, m_peak[size_t(slot)])) return false;
        if (m_box[size_t(slot)]) add_fitting(at(slot, pixel, film), v[0], v[1], v[2], v[3]);
        else add_footprint(slot, film, sample, v, nullptr);
        return true;
    }
    /// The same for the native view's own pixel, with the radiance E only it estimates (added to
    /// W*L, and on its own as the mean of its channels or in RGB, as the film keeps it).
    bool add(int slot, uint32_t pixel, Vec2f film, uint64_t sample, const Spectrum &lw, float w, const Spectrum &e) {
        const Spectrum sum = lw + e;
        const float v[4] = {sum[0], sum[1], sum[2], w};
        if (!(fits(lw) & fits(e) & fits(v, m_peak[size_t(slot)]))) return false;
        const float e_kept[3] = {m_e_rgb ? e[0] : (e[0] + e[1] + e[2]) * (1.f / 3.f), e[1], e[2]};
        if (!fits(e_kept, m_e_rgb ? 3 : 1, m_peak[size_t(slot)])) return false;
        if (m_box[size_t(slot)]) {
            SplatEntry &entry = at(slot, pixel, film);
            add_fitting(entry, v[0], v[1], v[2], v[3]);
            for (int c = 0; c < (m_e_rgb ? 3 : 1); ++c) entry.e[c] += to_fixed(e_kept[c]);
        } else {
            add_footprint(slot, film, sample, v, e_kept);
        }
        return true;
    }
    /// Whether every value of v (and times the filter's peak weight) fits.
    static bool fits(const float *v, int n, float peak) {
        bool ok = true;
        for (int i = 0; i < n; ++i) ok &= fits(v[i]) & fits(v[i] * peak);
        return ok;
    }
    static bool fits(const float v[4], float peak) { return fits(v, 4, peak); }
    /// Whether view `slot` has a box filter (a contribution goes to one pixel, weight 1).
    bool is_box(int slot) const { return m_box[size_t(slot)]; }
    /// Add W*L (per channel) and W that fit, and count the contribution.
    static void add_fitting(SplatEntry &e, float lw_r, float lw_g, float lw_b, float w) {
        e.lw[0] += to_fixed(lw_r);
        e.lw[1] += to_fixed(lw_g);
        e.lw[2] += to_fixed(lw_b);
        e.w += to_fixed(w);
        ++e.count;
    }
    /// Add `v` (W*L, W) and `e` (E as the film keeps it, or none) that fit, spread over the
    /// pixels of view `slot` that the filter at film position `film` covers; counted in the
    /// pixel that holds `film`. Taps of weight |h| >= TapThreshold get h v; a smaller one is kept
    /// with probability |h| / TapThreshold and then gets ±TapThreshold v (h's sign; Russian
    /// roulette, unbiased),
    /// the choices made by one number of the native sample `sample` (systematic sampling over the
    /// small taps: each kept with exactly its probability).
    void add_footprint(int slot, Vec2f film, uint64_t sample, const float v[4], const float *e);
    /// The weight below which a footprint's taps are played by Russian roulette.
    static constexpr float TapThreshold = 0.0625f;
    /// How many entries were displaced by another view-pixel (added to the film before the
    /// end of the pass) since the cache was made.
    uint64_t displaced() const { return m_displaced; }
    /// Adds every entry to the film and empties the cache (the end of a pass).
    void flush();
    /// Empties the cache without adding anything (a pass that is abandoned).
    void discard();

private:
    /// The entry of (x, y) of view `slot`'s window: its block, the pixel on it as on a torus.
    size_t index(int slot, uint32_t x, uint32_t y) const {
        const uint32_t torus = ((y & ((1u << m_bits_y) - 1)) << m_bits_x) | (x & ((1u << m_bits_x) - 1));
        return (m_base[size_t(slot)] + torus) & m_mask;
    }
    void replace(SplatEntry &e, uint32_t key);
    /// Hands a displaced entry to the film: its sums' lines are prefetched now and added
    /// VictimDepth displacements later, so that the misses of several overlap (an atomic add
    /// to a line not in cache otherwise waits for it alone).
    void retire(const SplatEntry &e);
    static constexpr size_t VictimDepth = 8;

    MvPassFilm *m_film;
    std::array<SplatEntry, VictimDepth> m_victims; ///< displaced entries not yet added (a ring)
    size_t m_victim_count = 0;                     ///< entries retired since the last flush
    std::vector<uint32_t> m_used; ///< the entries that hold a view-pixel (flush visits only them)
    bool m_e_rgb;
    std::vector<uint32_t> m_offset; ///< the film's offset of each view
    std::vector<uint8_t> m_box;     ///< each view's filter is a box
    std::vector<uint64_t> m_tap_key; ///< each view's SplatFootprint::tap_key
    std::vector<float> m_peak;      ///< each view's largest filter weight
    std::vector<int> m_crop;        ///< each view's crop window origin (x, y)
    std::vector<uint32_t> m_base;   ///< where each view's block of entries starts
    std::vector<SplatEntry> m_entries;
    uint32_t m_mask;
    uint64_t m_displaced = 0;
    uint32_t m_bits_x, m_bits_y; ///< a view's block: 2^bits_x entries wide, 2^bits_y high
};

/// A native sample as reports name it, ordered as path tracing orders its samples for replay:
/// (sample index, view's scene index, y, x), full-film pixel; -1s for none.
using SampleKey = std::array<int64_t, 4>;
inline constexpr SampleKey NoSample{-1, -1, -1, -1};
/// Keeps the earlier of `key` and `first` in `first`.
inline void keep_first(SampleKey &first, const SampleKey &key) {
    if (key[1] >= 0 && (first[1] < 0 || key < first)) first = key;
}

/// Where one thread's contributions go: its splat cache, and per view a count of the
/// contributions dropped as not finite (or beyond SplatMax), and the first native sample that
/// had one dropped.
struct MvSplatSink {
    SplatCache &cache;
    uint64_t *dropped;
    SampleKey *first_dropped;
    /// A contribution W*L, W at film position `film` (window pixel `pixel`) of a view that
    /// shares the native sample with Sampler::sample_hash `sample`; false if dropped.
    bool shared(int slot, uint32_t pixel, Vec2f film, uint64_t sample, const Spectrum &lw, float w) {
        if (cache.add(slot, pixel, film, sample, lw, w)) return true;
        ++dropped[slot];
        return false;
    }
    /// The contribution to the native view, with its native-only radiance E (emission seen
    /// directly, paths through purely specular first vertices) divided by n_l; false if dropped.
    bool native(int slot, uint32_t pixel, Vec2f film, uint64_t sample, const Spectrum &lw, float w, const Spectrum &e) {
        if (cache.add(slot, pixel, film, sample, lw, w, e)) return true;
        ++dropped[slot];
        return false;
    }
    /// The native sample `key` had a contribution dropped.
    void lost(const SampleKey &key) { keep_first(*first_dropped, key); }
};

} // namespace mvpt
