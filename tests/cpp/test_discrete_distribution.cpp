// DiscreteDistribution::sample against its definition: the index is std::upper_bound's over
// the interior CDF (then past zero-probability items), for short tables (counted) and long
// ones (guide table), including zero weights, spikes and u on bucket and CDF boundaries.
#include "mvpt/core/distribution.h"

#include <gtest/gtest.h>

#include <random>

using namespace mvpt;

namespace {

/// The reference: binary search over the normalized CDF, as the implementation promises.
size_t reference_sample(const std::vector<float> &w, float u) {
    std::vector<double> cdf(w.size() + 1, 0.0);
    for (size_t i = 0; i < w.size(); ++i) cdf[i + 1] = cdf[i] + std::max(0.f, w[i]);
    double sum = cdf.back();
    if (sum > 0)
        for (double &c : cdf) c /= sum;
    size_t i = size_t(std::upper_bound(cdf.begin() + 1, cdf.end() - 1, double(u)) - cdf.begin()) - 1;
    while (i + 1 < w.size() && cdf[i + 1] == cdf[i]) ++i;
    return i;
}

} // namespace

TEST(DiscreteDistribution, SampleIsUpperBoundOfTheCdf) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> unit(0.f, 1.f);
    for (size_t n : {1, 2, 3, 16, 17, 18, 40, 257, 1000, 4097}) {
        for (int kind = 0; kind < 4; ++kind) {
            std::vector<float> w(n);
            for (size_t i = 0; i < n; ++i) {
                float x = unit(rng);
                if (kind == 1) x = (i % 3 == 0) ? 0.f : x;              // zero-probability items
                if (kind == 2) x = (i == n / 2) ? 1e6f : x * 1e-3f;     // one spike
                if (kind == 3) x = (i < n / 2) ? 0.f : 1.f;             // a zero half
                w[i] = x;
            }
            DiscreteDistribution d(w);
            std::vector<float> us;
            for (int k = 0; k < 4000; ++k) us.push_back(unit(rng));
            for (size_t j = 0; j <= 64; ++j) us.push_back(std::min(float(j) / 64.f, OneMinusEpsilon));
            for (float u : us) {
                float pmf;
                size_t got = d.sample(u, &pmf);
                ASSERT_EQ(got, reference_sample(w, u)) << "n " << n << " kind " << kind << " u " << u;
                if (d.sum() > 0) ASSERT_GT(pmf, 0.f) << "n " << n << " kind " << kind << " u " << u;
            }
        }
    }
}
