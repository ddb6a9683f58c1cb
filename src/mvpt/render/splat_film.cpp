#include "splat_film.h"

#include "../core/sampler.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace mvpt {

SplatFootprint SplatFootprint::of(int crop_x, int crop_y, int width, int height, const ReconstructionFilter &filter,
                                  uint64_t tap_key) {
    SplatFootprint f = box(width, height);
    f.crop_x = crop_x, f.crop_y = crop_y, f.tap_key = tap_key;
    if (!filter.is_box()) {
        const auto *tabulated = dynamic_cast<const TabulatedFilter *>(&filter);
        if (!tabulated) throw std::runtime_error("multi-view path tracing splats with box and tabulated filters only");
        f.filter = &filter;
        f.radius = filter.radius();
        f.peak = filter.peak_1d() * filter.peak_1d();
        f.table = tabulated->table().data();
        f.table_size = tabulated->table().size();
        f.table_scale = float(f.table_size) / (2.f * f.radius);
    }
    return f;
}

MvPassFilm::MvPassFilm(const std::vector<SplatFootprint> &views, bool e_rgb)
    : m_footprint(views), m_e_channels(e_rgb ? 3 : 1) {
    size_t total = 0;
    m_offset.push_back(0);
    for (const SplatFootprint &v : views) {
        total += v.pixels();
        if (total >= UINT32_MAX) throw std::runtime_error("multi-view path tracing renders at most 2^32 - 2 view-pixels");
        m_offset.push_back(uint32_t(total));
    }
    m_size = total;
    m_shared = std::make_unique_for_overwrite<Shared[]>(total);
    m_e = std::make_unique_for_overwrite<int64_t[]>(size_t(m_e_channels) * total);
    m_count = std::make_unique_for_overwrite<uint32_t[]>(total);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, total, size_t(1) << 16), [&](const tbb::blocked_range<size_t> &r) {
        std::fill(m_shared.get() + r.begin(), m_shared.get() + r.end(), Shared{});
        std::fill(m_e.get() + size_t(m_e_channels) * r.begin(), m_e.get() + size_t(m_e_channels) * r.end(), 0);
        std::fill(m_count.get() + r.begin(), m_count.get() + r.end(), 0u);
    });
}

void MvPassFilm::add(const SplatEntry &e) {
    auto add = [](int64_t &to, int64_t v) {
        if (v != 0) std::atomic_ref<int64_t>(to).fetch_add(v, std::memory_order_relaxed);
    };
    Shared &s = m_shared[e.key];
    for (int c = 0; c < 3; ++c) add(s.lw[c], e.lw[c]);
    add(s.w, e.w);
    for (int c = 0; c < m_e_channels; ++c) add(m_e[size_t(m_e_channels) * e.key + size_t(c)], e.e[c]);
    std::atomic_ref<uint32_t>(m_count[e.key]).fetch_add(e.count, std::memory_order_relaxed);
}

SplatEntry MvPassFilm::take(uint32_t key) {
    SplatEntry out;
    Shared &s = m_shared[key];
    for (int c = 0; c < 3; ++c) out.lw[c] = s.lw[c];
    for (int c = 0; c < m_e_channels; ++c) out.e[c] = m_e[size_t(m_e_channels) * key + size_t(c)];
    out.w = s.w;
    out.count = m_count[key];
    out.key = key;
    s = Shared{};
    for (int c = 0; c < m_e_channels; ++c) m_e[size_t(m_e_channels) * key + size_t(c)] = 0;
    m_count[key] = 0;
    return out;
}

SplatCache::SplatCache(MvPassFilm &film, size_t entries)
    : m_film(&film), m_e_rgb(film.e_channels() == 3), m_entries(entries ? entries : entries_for(film.views())) {
    entries = m_entries.size();
    if (entries == 0 || (entries & (entries - 1)) != 0) throw std::invalid_argument("splat cache size must be a power of two");
    m_mask = uint32_t(entries - 1);
    // Each view a block of 2^(bx + by) entries, the largest power of two that fits once per
    // view, about square (2^bx wide, no wider than the widest window needs). With more views
    // than blocks of 16 x 16 fit, those blocks overlap, spread by the golden ratio.
    const size_t views = std::max<size_t>(film.views(), 1);
    int widest = 1;
    for (size_t s = 0; s < film.views(); ++s) widest = std::max(widest, film.footprint(int(s)).width);
    uint32_t block_bits = 8;
    while (block_bits < 30 && views << (block_bits + 1) <= entries) ++block_bits;
    m_bits_x = block_bits - block_bits / 2;
    while (m_bits_x > 4 && (1 << (m_bits_x - 1)) >= widest) --m_bits_x;
    m_bits_y = block_bits - m_bits_x;
    const bool apart = views << block_bits <= entries;
    for (size_t s = 0; s < film.views(); ++s) {
        const SplatFootprint &f = film.footprint(int(s));
        m_offset.push_back(film.offset(int(s)));
        m_box.push_back(f.is_box());
        m_tap_key.push_back(f.tap_key);
        m_peak.push_back(f.peak);
        m_crop.insert(m_crop.end(), {f.crop_x, f.crop_y});
        m_base.push_back(apart ? uint32_t(s << block_bits)
                               : uint32_t(((uint64_t(s) * 0x9E3779B97F4A7C15ull) >> 32) * entries >> 32));
    }
}

namespace {
/// floor(v) as an int for |v| < 2^31 (std::floor is a library call on baseline x86-64).
inline int floor_int(float v) {
    const int i = int(v);
    return i - (float(i) > v);
}

constexpr int MaxTaps = 2 * SplatFootprint::MaxRadius;

/// The pixels i in [lo, hi) of one axis whose centre i + 1/2 lies within the radius of x, and
/// their weights h(x - i - 1/2) into w (the same operations as ReconstructionFilter::eval_1d):
/// how many, the first into `first`. (Inlined into each instruction set's add_footprint.)
[[gnu::always_inline]] inline int footprint_taps(const SplatFootprint &f, float x, int lo, int hi, float *w,
                                                 int *first) {
    const int i0 = std::max(lo, floor_int(x - 0.5f - f.radius) + 1);
    const int i1 = std::min(hi - 1, -floor_int(-(x - 0.5f + f.radius)) - 1); // ceil - 1
    int n = 0;
    for (int i = i0; i <= i1 && n < MaxTaps; ++i) {
        const float t = (x - (float(i) + 0.5f) + f.radius) * f.table_scale;
        w[n++] = t >= 0.f && t < float(f.table_size) ? f.table[size_t(t)] : 0.f;
    }
    *first = i0;
    return n;
}
} // namespace

double SplatFootprint::mean_writes() const {
    if (is_box()) return 1.0;
    // Over a 16 x 16 grid of positions in a pixel away from the window's edges: every tap of weight
    // TapThreshold or more, a smaller one with probability |h| / TapThreshold.
    constexpr int Grid = 16;
    constexpr int Far = 1 << 20;
    double sum = 0.0;
    for (int gy = 0; gy < Grid; ++gy)
        for (int gx = 0; gx < Grid; ++gx) {
            float wx[MaxTaps], wy[MaxTaps];
            int first;
            const int nx = footprint_taps(*this, (float(gx) + 0.5f) / Grid, -Far, Far, wx, &first);
            const int ny = footprint_taps(*this, (float(gy) + 0.5f) / Grid, -Far, Far, wy, &first);
            for (int j = 0; j < ny; ++j)
                for (int i = 0; i < nx; ++i)
                    sum += std::min(1.0, double(std::abs(wx[i] * wy[j])) / double(SplatCache::TapThreshold));
        }
    return sum / double(Grid * Grid);
}

MVPT_MULTI_ISA void SplatCache::add_footprint(int slot, Vec2f film, uint64_t sample, const float v[4], const float *e) {
    // Per axis, the pixels of the crop window within the filter's radius and their weights.
    const SplatFootprint &f = m_film->footprint(slot);
    float wx[MaxTaps], wy[MaxTaps];
    int x0, y0;
    const int nx = footprint_taps(f, film.x, f.crop_x, f.crop_x + f.width, wx, &x0);
    const int ny = footprint_taps(f, film.y, f.crop_y, f.crop_y + f.height, wy, &y0);
    const int hx = floor_int(film.x) - x0, hy = floor_int(film.y) - y0; // the tap that holds x
    const int e_channels = m_e_rgb ? 3 : 1;
    // Small taps by systematic sampling: the running sum of |h| / TapThreshold over them, shifted
    // by one uniform number u, keeps a tap when it crosses an integer (probability
    // |h| / TapThreshold), with weight ±TapThreshold (h's sign: filters with negative lobes).
    float run = float(mix_bits(sample + m_tap_key[size_t(slot)]) >> 40) * 0x1p-24f; // u
    float next = 1.f; // the integer after run (each step adds less than 1)
    const uint32_t wx0 = uint32_t(x0 - f.crop_x), wy0 = uint32_t(y0 - f.crop_y); // in the window
    for (int j = 0; j < ny; ++j) {
        const uint32_t row = (wy0 + uint32_t(j)) * uint32_t(f.width) + wx0;
        for (int i = 0; i < nx; ++i) {
            float h = wx[i] * wy[j];
            if (std::abs(h) < TapThreshold) {
                run += std::abs(h) * (1.f / TapThreshold);
                if (run < next) { // not kept (h == 0 never is)
                    if ((i == hx) & (j == hy)) at(slot, row + uint32_t(i), wx0 + uint32_t(i), wy0 + uint32_t(j)).count += 1;
                    continue;
                }
                next += 1.f;
                h = std::copysign(TapThreshold, h);
            }
            SplatEntry &entry = at(slot, row + uint32_t(i), wx0 + uint32_t(i), wy0 + uint32_t(j));
            add_fixed(entry.lw, simd::load<simd::f32x4>(v) * h); // (lw[3] and w are contiguous)
            if (e)
                for (int c = 0; c < e_channels; ++c) entry.e[c] += to_fixed(e[c] * h);
            entry.count += (i == hx) & (j == hy);
        }
    }
}

void SplatCache::replace(SplatEntry &e, uint32_t key) {
    if (e.key != UINT32_MAX) {
        retire(e);
        ++m_displaced;
    } else {
        m_used.push_back(uint32_t(&e - m_entries.data()));
    }
    e = SplatEntry{};
    e.key = key;
}

void SplatCache::retire(const SplatEntry &e) {
    SplatEntry &slot = m_victims[m_victim_count % VictimDepth];
    if (m_victim_count >= VictimDepth) m_film->add(slot); // retired VictimDepth entries ago
    slot = e;
    m_film->prefetch(e.key);
    ++m_victim_count;
}

void SplatCache::flush() {
    for (size_t i = 0; i < std::min(m_victim_count, VictimDepth); ++i) m_film->add(m_victims[i]);
    m_victim_count = 0;
    // The entries' sums prefetched VictimDepth entries ahead of their adds.
    const size_t n = m_used.size();
    for (size_t i = 0; i < std::min(n, VictimDepth); ++i) m_film->prefetch(m_entries[m_used[i]].key);
    for (size_t i = 0; i < n; ++i) {
        if (i + VictimDepth < n) m_film->prefetch(m_entries[m_used[i + VictimDepth]].key);
        SplatEntry &e = m_entries[m_used[i]];
        m_film->add(e);
        e = SplatEntry{};
    }
    m_used.clear();
}

void SplatCache::discard() {
    for (uint32_t i : m_used) m_entries[i] = SplatEntry{};
    m_used.clear();
    m_victim_count = 0;
}

} // namespace mvpt
