// The alias table of core/alias_table.h: each item's probability over all slots equals its
// weight's share, zero weights are never sampled, and the reused number is uniform given the item.
#include "mvpt/core/alias_table.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace mvpt;

namespace {
/// Probability of each item: the slots' own parts plus the parts aliased to it.
std::vector<double> item_probabilities(const AliasTable &t) {
    std::vector<double> p(t.size(), 0.0);
    for (size_t s = 0; s < t.size(); ++s) {
        const AliasTable::Entry &e = *t.entry(s);
        p[s] += double(e.q) / double(t.size());
        p[e.alias] += (1.0 - double(e.q)) / double(t.size());
    }
    return p;
}
} // namespace

TEST(AliasTable, ItemProbabilitiesMatchWeights) {
    for (size_t n : {1, 2, 5, 255, 512}) {
        std::vector<float> w(n);
        double sum = 0;
        for (size_t i = 0; i < n; ++i) {
            w[i] = (i % 7 == 3) ? 0.f : float((i * 2654435761u) % 1000) * 0.01f + (i == n / 2 ? 50.f : 0.f);
            sum += w[i];
        }
        AliasTable t(w);
        std::vector<double> p = item_probabilities(t);
        for (size_t i = 0; i < n; ++i) {
            EXPECT_NEAR(p[i], w[i] / sum, 1e-6) << n << " items, item " << i;
            if (w[i] == 0.f) EXPECT_EQ(p[i], 0.0) << n << " items, item " << i;
        }
    }
}

TEST(AliasTable, SamplesFollowWeightsAndReuseIsUniform) {
    const std::vector<float> w = {1.f, 0.f, 3.f, 0.5f, 0.f, 2.5f};
    AliasTable t(w);
    const int n = 600000, bins = 4;
    std::vector<double> count(w.size(), 0.0), reuse(w.size() * bins, 0.0);
    for (int k = 0; k < n; ++k) {
        const float u = (float(k) + 0.5f) / float(n); // a fine grid over [0, 1)
        float r;
        const uint32_t i = t.sample(u, &r);
        ASSERT_LT(i, w.size());
        ASSERT_GE(r, 0.f);
        ASSERT_LT(r, 1.f);
        count[i] += 1;
        reuse[i * bins + std::min(int(r * bins), bins - 1)] += 1;
    }
    for (size_t i = 0; i < w.size(); ++i) {
        EXPECT_NEAR(count[i] / n, w[i] / 7.0, 1e-4) << i;
        for (int b = 0; b < bins; ++b) // a grid: exact up to a slot boundary per bin
            EXPECT_NEAR(reuse[i * bins + b], count[i] / bins, 8.0) << i << " bin " << b;
    }
}

TEST(AliasTable, AllZeroIsEmpty) {
    AliasTable t(std::vector<float>(4, 0.f));
    EXPECT_TRUE(t.empty());
    float r;
    EXPECT_LT(t.sample(0.9f, &r), 4u);
}
