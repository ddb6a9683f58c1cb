#include "splat_film.h"

#include <stdexcept>

namespace mvpt {

MvPassFilm::MvPassFilm(const std::vector<size_t> &pixels, bool e_rgb) : m_e_channels(e_rgb ? 3 : 1) {
    size_t total = 0;
    m_offset.push_back(0);
    for (size_t n : pixels) {
        total += n;
        if (total >= UINT32_MAX) throw std::runtime_error("multi-view path tracing renders at most 2^32 - 2 view-pixels");
        m_offset.push_back(uint32_t(total));
    }
    m_shared.resize(total);
    m_e.assign(size_t(m_e_channels) * total, 0);
    m_count.assign(total, 0);
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
    : m_film(&film), m_e_rgb(film.e_channels() == 3), m_entries(entries) {
    if (entries == 0 || (entries & (entries - 1)) != 0) throw std::invalid_argument("splat cache size must be a power of two");
    m_mask = uint32_t(entries - 1);
    for (size_t s = 0; s < film.views(); ++s) {
        m_offset.push_back(film.offset(int(s)));
        // Views start at multiples of the golden ratio of the cache: the same pixel of
        // different views falls on different entries.
        m_base.push_back(uint32_t(((uint64_t(s) * 0x9E3779B97F4A7C15ull) >> 32) * entries >> 32));
    }
}

void SplatCache::replace(SplatEntry &e, uint32_t key) {
    if (e.key != UINT32_MAX) m_film->add(e);
    e = SplatEntry{};
    e.key = key;
}

void SplatCache::flush() {
    for (SplatEntry &e : m_entries)
        if (e.key != UINT32_MAX) {
            m_film->add(e);
            e = SplatEntry{};
        }
}

void SplatCache::discard() {
    for (SplatEntry &e : m_entries) e = SplatEntry{};
}

} // namespace mvpt
