// Deterministic sample streams: every number is a pure function of
// (seed, view, pixel, sample index, dimension), so images do not depend on
// threads or scheduling (pbrt-v4's Hash(p, seed) approach).
#pragma once

#include "math.h"

#include <cstdint>

namespace mvpt {

/// SplitMix64 finaliser: a bijective 64-bit mixer.
inline uint64_t mix_bits(uint64_t v) {
    v ^= v >> 30;
    v *= 0xbf58476d1ce4e5b9ULL;
    v ^= v >> 27;
    v *= 0x94d049bb133111ebULL;
    v ^= v >> 31;
    return v;
}

/// Hash of several integers (order matters).
inline uint64_t hash_combine(uint64_t h, uint64_t v) { return mix_bits(h ^ (v + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2))); }
template <typename... Ts> inline uint64_t hash_ints(uint64_t first, Ts... rest) {
    uint64_t h = mix_bits(first + 0x9e3779b97f4a7c15ULL);
    ((h = hash_combine(h, uint64_t(rest))), ...);
    return h;
}

/// Map 32 random bits to a float in [0, 1).
inline float bits_to_unit_float(uint32_t bits) { return std::min(float(bits >> 8) * 0x1p-24f, OneMinusEpsilon); }

inline uint32_t reverse_bits(uint32_t x) {
    x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
    x = ((x >> 8) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8);
    return (x >> 16) | (x << 16);
}

/// Nested uniform (Owen) scrambling of a 32-bit fixed-point value by hashing
/// [Burley 2020, "Practical Hash-based Owen Scrambling", §3].
inline uint32_t owen_scramble(uint32_t x, uint32_t seed) {
    x = reverse_bits(x);
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return reverse_bits(x);
}

enum class SamplerKind { Independent, Sobol };

/// An unbounded stream of uniform numbers from one 64-bit seed, for the estimators that
/// draw as many numbers as they need (free-flight and ratio tracking in heterogeneous media).
class RandomStream {
public:
    explicit RandomStream(uint64_t seed = 0) : m_state(seed) {}
    float next_1d() { return bits_to_unit_float(uint32_t(mix_bits(m_state += 0x9e3779b97f4a7c15ULL))); }

private:
    uint64_t m_state;
};

/// One sample's stream of random numbers. `start` fixes (view, pixel, sample
/// index); each `next_*` call consumes one dimension. Integrators place
/// per-bounce blocks with `set_dimension` so that early exits never shift the
/// numbers of later bounces.
class Sampler {
public:
    Sampler(SamplerKind kind = SamplerKind::Independent, uint32_t seed = 0) : m_kind(kind), m_seed(seed) {}

    void start(uint32_t view, uint32_t px, uint32_t py, uint32_t sample_index, uint32_t dimension = 0) {
        m_pixel_hash = hash_ints(m_seed, view, px, py);
        m_sample_hash = hash_combine(m_pixel_hash, sample_index);
        m_index = sample_index;
        m_dim = dimension;
    }
    /// `start` from hashes computed elsewhere (independent_start_draws), at dimension `dimension`.
    void start_from(uint64_t pixel_hash, uint64_t sample_hash, uint32_t sample_index, uint32_t dimension) {
        m_pixel_hash = pixel_hash;
        m_sample_hash = sample_hash;
        m_index = sample_index;
        m_dim = dimension;
    }
    /// The same sample's stream under another `key`: every dimension drawn anew (the splits of
    /// a shared vertex, multiview-path-tracing.md §7), with either sampler.
    Sampler rekeyed(uint64_t key) const {
        Sampler s = *this;
        s.m_pixel_hash = hash_combine(m_pixel_hash, key);
        s.m_sample_hash = hash_combine(m_sample_hash, key);
        return s;
    }
    void set_dimension(uint32_t d) { m_dim = d; }
    uint32_t dimension() const { return m_dim; }
    SamplerKind kind() const { return m_kind; }
    uint32_t seed() const { return m_seed; }
    /// Hash of (seed, view, pixel, sample index): with `independent_bits(hash, dim)` it gives
    /// the independent sampler's numbers without the sampler (batched draws, sampler_batch.h).
    uint64_t sample_hash() const { return m_sample_hash; }
    /// 64 random bits of the independent sampler for dimension `dim` of the sample `hash`.
    static uint64_t independent_bits(uint64_t hash, uint32_t dim) { return mix_bits(hash + dimension_key(dim)); }
    /// What independent_bits adds to a sample's hash for dimension `dim`.
    static constexpr uint64_t dimension_key(uint32_t dim) { return 0x9e3779b97f4a7c15ULL * (uint64_t(dim) + 1); }

    float next_1d() {
        if (m_kind == SamplerKind::Independent) return bits_to_unit_float(uint32_t(independent_bits()));
        return sobol_1d();
    }
    /// A stream of its own for this (sample, dimension), whichever the sampler (one dimension).
    RandomStream next_stream() { return RandomStream(independent_bits()); }
    Vec2f next_2d() {
        if (m_kind == SamplerKind::Independent) {
            uint64_t r = independent_bits();
            return {bits_to_unit_float(uint32_t(r)), bits_to_unit_float(uint32_t(r >> 32))};
        }
        return sobol_2d();
    }

private:
    // The Sobol paths stay out of line so that the independent path inlines into integrators.
    [[gnu::noinline]] float sobol_1d() {
        uint64_t h = dimension_hash();
        return bits_to_unit_float(owen_scramble(sobol_dim0(shuffled_index(h)), uint32_t(h >> 32)));
    }
    [[gnu::noinline]] Vec2f sobol_2d() {
        uint64_t h = dimension_hash();
        uint32_t i = shuffled_index(h);
        uint64_t h2 = mix_bits(h);
        return {bits_to_unit_float(owen_scramble(sobol_dim0(i), uint32_t(h2))),
                bits_to_unit_float(owen_scramble(sobol_dim1(i), uint32_t(h2 >> 32)))};
    }

    /// 64 random bits of (sample, dimension) for the independent sampler: one mix per draw.
    uint64_t independent_bits() { return independent_bits(m_sample_hash, m_dim++); }
    /// Per (pixel, dimension) scrambling seed of the Sobol sampler, shared by all sample indices.
    uint64_t dimension_hash() { return mix_bits(m_pixel_hash + 0x9e3779b97f4a7c15ULL * (uint64_t(m_dim++) + 1)); }
    /// Owen-scrambled sample index: decorrelates padded dimension pairs while
    /// keeping every power-of-two prefix stratified [Burley 2020, §4].
    uint32_t shuffled_index(uint64_t h) const { return owen_scramble(m_index, uint32_t(h)); }
    static uint32_t sobol_dim0(uint32_t i) { return reverse_bits(i); }
    static uint32_t sobol_dim1(uint32_t i) {
        uint32_t x = 0, v = 0x80000000u;
        for (; i; i >>= 1, v ^= v >> 1)
            if (i & 1u) x ^= v;
        return x;
    }

    SamplerKind m_kind;
    uint32_t m_seed;
    uint64_t m_pixel_hash = 0, m_sample_hash = 0;
    uint32_t m_index = 0, m_dim = 0;
};

} // namespace mvpt
