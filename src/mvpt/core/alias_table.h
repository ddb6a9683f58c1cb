// Discrete distribution sampled in constant time by Walker's alias method [Walker 1977, "An
// efficient method for generating discrete random variables with general distributions";
// Vose 1991, "A linear algorithm for generating random numbers with a given distribution"]:
// one table entry per item, read once per sample, instead of a search through a CDF (whose
// dependent reads miss the cache in large tables such as an environment map's rows).
#pragma once

#include "math.h"

#include <cstdint>
#include <vector>

namespace mvpt {

class AliasTable {
public:
    /// One slot: its own item with probability q, else item `alias`.
    struct Entry {
        float q;
        uint32_t alias;
    };

    AliasTable() = default;
    /// `weights`: non-negative (all zero: an empty table, whose samples are item 0).
    explicit AliasTable(const std::vector<float> &weights) { build(weights); }

    void build(const std::vector<float> &weights) {
        const size_t n = weights.size();
        m_entries.assign(n, Entry{1.f, 0});
        double sum = 0;
        for (float w : weights) sum += std::max(0.f, w);
        m_sum = sum;
        if (n == 0 || !(sum > 0)) return;
        // Vose: the slots scaled to mean 1, below-average ones topped up by above-average ones.
        std::vector<double> scaled(n);
        std::vector<uint32_t> small, large;
        for (size_t i = 0; i < n; ++i) {
            scaled[i] = double(std::max(0.f, weights[i])) * double(n) / sum;
            (scaled[i] < 1.0 ? small : large).push_back(uint32_t(i));
        }
        while (!small.empty() && !large.empty()) {
            const uint32_t s = small.back(), l = large.back();
            small.pop_back();
            m_entries[s] = {float(std::max(scaled[s], 0.0)), l};
            scaled[l] -= 1.0 - scaled[s];
            if (scaled[l] < 1.0) {
                large.pop_back();
                small.push_back(l);
            }
        }
        // What remains is 1 up to rounding: those slots keep their own item. A zero-weight item
        // left here by rounding would be sampled, so it takes a positive item as alias.
        uint32_t positive = 0;
        while (!(weights[positive] > 0.f)) ++positive;
        for (uint32_t i : small) m_entries[i] = weights[i] > 0.f ? Entry{1.f, i} : Entry{0.f, positive};
        for (uint32_t i : large) m_entries[i] = {1.f, i};
    }

    size_t size() const { return m_entries.size(); }
    double sum() const { return m_sum; }
    bool empty() const { return !(m_sum > 0); }

    /// Item for u in [0, 1); `*u_reuse` is a number in [0, 1) uniform given the item (the
    /// fraction of u within the slot, rescaled to the part that chose the item). Branch-free.
    uint32_t sample(float u, float *u_reuse) const { return sample_from(slot_of(u), u, u_reuse); }

    /// `sample` in two steps, for staged loops whose table reads overlap: the slot of u ...
    size_t slot_of(float u) const {
        const float x = u * float(m_entries.size());
        return std::min(size_t(x), m_entries.size() - 1);
    }
    /// ... and the rest from there (`slot` = slot_of(u)).
    uint32_t sample_from(size_t slot, float u, float *u_reuse) const {
        const Entry e = m_entries[slot];
        const float frac = std::min(u * float(m_entries.size()) - float(slot), OneMinusEpsilon);
        const bool own = frac < e.q;
        *u_reuse = std::min(select(own, frac, frac - e.q) / select(own, e.q, 1.f - e.q), OneMinusEpsilon);
        return own ? uint32_t(slot) : e.alias;
    }
    /// The entry of a slot (to prefetch it).
    const Entry *entry(size_t slot) const { return m_entries.data() + slot; }

private:
    std::vector<Entry> m_entries;
    double m_sum = 0;
};

} // namespace mvpt
