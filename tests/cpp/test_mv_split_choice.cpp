// The choice of the splits of the shared vertex (mv_split_choice.h): the variance split of
// synthetic pilots with known parts, whatever the order and grouping of their records, and the
// B that minimises (a + r / B)(c0 + B c1).
#include "mvpt/integrators/multiview/mv_split_choice.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

using namespace mvpt;

namespace {

/// A pilot of `pixels` pairs of samples whose estimates are mu + y + s_b: y of variance var_y
/// per sample, s_b of variance var_s per split; each sample's E and splits in separate records
/// when `separate`, in a shuffled order.
MvSplitProbe synthetic_pilot(int pixels, double var_y, double var_s, bool separate, uint32_t seed) {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> y(0.0, std::sqrt(var_y)), s(0.0, std::sqrt(var_s));
    MvSplitProbe probe;
    for (int p = 0; p < pixels; ++p)
        for (int64_t index = 0; index < 2; ++index) {
            MvPilotSample x;
            x.key = SampleKey{index, 0, p / 64, p % 64};
            x.sharing = 9;
            const double shared = 5.0 + y(rng);
            for (double &v : x.split) v = shared + s(rng);
            if (separate) { // E (no split) in a record of its own
                MvPilotSample e;
                e.key = x.key;
                e.e = 1.0;
                probe.samples.push_back(e);
            } else {
                x.e = 1.0;
            }
            probe.samples.push_back(x);
        }
    std::shuffle(probe.samples.begin(), probe.samples.end(), rng);
    return probe;
}

} // namespace

TEST(MvSplitChoice, StatisticsSeparateTheVarianceOfYFromThatOfTheSplits) {
    // With eps far above the squared means every pixel weighs 1/eps: a and r times eps / pixels
    // estimate var_y and var_s. 40000 pixels: the estimates' relative error is about 1 %.
    const int pixels = 40000;
    const double eps = 1e6;
    for (bool separate : {false, true}) {
        const SplitStatistics st = split_statistics({synthetic_pilot(pixels, 0.5, 4.0, separate, 7)}, eps);
        EXPECT_EQ(st.pixels, uint64_t(pixels));
        EXPECT_NEAR(st.a * eps / pixels, 0.5, 0.05) << separate;
        EXPECT_NEAR(st.r * eps / pixels, 4.0, 0.2) << separate;
        EXPECT_GT(st.c0, 1.0);
        EXPECT_GT(st.c1, 1.0);
    }
}

TEST(MvSplitChoice, ChoiceMinimisesVarianceTimesCost) {
    // (1 + 16 / B)(1 + B) is least at B = 4 (25), and 3 is within 5 % of it (25.3), 2 not (27).
    EXPECT_EQ(choose_splits({1.0, 16.0, 1.0, 1.0, 100}), 3);
    // (1 + 100 / B)(1 + B): least at 10 (121), 5 within 5 % of it (126), 4 not (130).
    EXPECT_EQ(choose_splits({1.0, 100.0, 1.0, 1.0, 100}), 5);
    // Splitting removes nothing: one split; it removes all: the most.
    EXPECT_EQ(choose_splits({1.0, 0.0, 1.0, 1.0, 100}), 1);
    EXPECT_EQ(choose_splits({-0.1, 1.0, 0.0, 1.0, 100}), 1); // (no cost once per sample)
    EXPECT_EQ(choose_splits({-0.1, 1.0, 100.0, 1.0, 100}), MaxChosenSplits);
    // Dearer splits: fewer ((1 + 16 / B)(1 + 2 B): least at 3, 44.3; 2 within 5 %, 45).
    EXPECT_EQ(choose_splits({1.0, 16.0, 1.0, 2.0, 100}), 2);
    // A cap (a time budget's) bounds the choice.
    EXPECT_EQ(choose_splits({1.0, 100.0, 1.0, 1.0, 100}, 3), 3);
    // No statistics: one split.
    EXPECT_EQ(choose_splits(SplitStatistics{}), 1);
}

TEST(MvSplitChoice, BudgetBoundsTheSplitsByThePassesThatFit) {
    const SplitStatistics st{1.0, 16.0, 1.0, 0.5, 100};
    // Six passes of 0.1 (1 + 0.5 B) seconds in 2.5 s: 1 + 0.5 B <= 4.17, B <= 6.
    EXPECT_EQ(splits_fitting(st, 0.1, 2.5, 6.0), 6);
    // A larger part no split changes (the splats) leaves room for fewer: 2 + 0.5 B <= 4.17.
    SplitStatistics splats = st;
    splats.c0 = 2.0;
    EXPECT_EQ(splits_fitting(splats, 0.1, 2.5, 6.0), 4);
    // None fits: one split; no passes wanted any more: no bound.
    EXPECT_EQ(splits_fitting(st, 1.0, 2.4, 6.0), 1);
    EXPECT_EQ(splits_fitting(st, 1.0, 2.4, 0.0), MaxChosenSplits);
}

// Paths of purely specular first vertices split K ways (delta_splits): K balances the variance
// r_d / K that splitting removes against the cost K d1, at the splits B of the shared vertex.
TEST(MvSplitChoice, DeltaSplitsBalanceVarianceAndCost) {
    SplitStatistics s;
    s.a = 1.0, s.r = 1.0, s.c0 = 4.0, s.c1 = 1.0;
    EXPECT_EQ(choose_delta_splits(s, 2), 1); // no specular first vertices
    s.r_d = 4.0, s.d1 = 0.25;
    // (1.5 + 4/K)(6 + K/4) is least near K = sqrt(6 * 4 / (1.5 * 0.25)) = 8.
    const int k = choose_delta_splits(s, 2);
    EXPECT_GE(k, 7);
    EXPECT_LE(k, 9);
    auto v = [&](int kk) { return (s.a + s.r / 2 + s.r_d / kk) * (s.c0 + 2 * s.c1 + kk * s.d1); };
    for (int kk = 1; kk <= MaxDeltaSplits; ++kk) EXPECT_LE(v(k), v(kk) + 1e-12);
    // Costlier paths: fewer of them.
    s.d1 = 1.0;
    EXPECT_LT(choose_delta_splits(s, 2), k);
    // Without variance between the paths there is nothing to split.
    s.r_d = 0.0;
    EXPECT_EQ(choose_delta_splits(s, 2), 1);
}

TEST(MvSplitChoice, StatisticsSeparateSpecularPathsFromSplits) {
    // Half the pixels' samples are shared (y of variance 0.5, splits of 4), half have a specular
    // first vertex whose eight paths vary by 2 around a camera part of variance 1: r takes the
    // splits' variance, r_d the paths', a both camera parts; a specular sample costs d1 per path.
    const int pixels = 40000;
    const double eps = 1e6;
    MvSplitProbe probe = synthetic_pilot(pixels / 2, 0.5, 4.0, false, 11);
    std::mt19937_64 rng(12);
    std::normal_distribution<double> cam(0.0, 1.0), path(0.0, std::sqrt(2.0));
    for (int p = pixels / 2; p < pixels; ++p)
        for (int64_t index = 0; index < 2; ++index) {
            MvPilotSample x;
            x.key = SampleKey{index, 0, p / 64, p % 64};
            x.delta = true;
            const double at = 3.0 + cam(rng);
            for (double &v : x.split) v = at + path(rng);
            probe.samples.push_back(x);
        }
    const SplitStatistics st = split_statistics({probe}, eps);
    EXPECT_EQ(st.pixels, uint64_t(pixels));
    EXPECT_NEAR(st.r * eps / (pixels / 2), 4.0, 0.2);
    EXPECT_NEAR(st.r_d * eps / (pixels / 2), 2.0, 0.1);
    EXPECT_NEAR(st.a * eps / pixels, 0.75, 0.06); // (0.5 + 1) / 2
    EXPECT_NEAR(st.d1, 0.5, 1e-9);                // one path per specular sample, half the samples
    // These shared samples are cheap (c0 about 0.7): one path and one split are best. Where a
    // native sample's fixed part costs more, as on a wide rig, more paths pay.
    EXPECT_EQ(choose_delta_splits(st, choose_splits(st)), 1);
    SplitStatistics costly = st;
    costly.c0 += 10.0;
    EXPECT_GT(choose_delta_splits(costly, choose_splits(costly)), 1);
}

TEST(MvSplitChoice, PredictedGainIsPathTracingsVarianceOverAPassAtItsCost) {
    // Shared samples (|S| = 9: a pixel's pass gathers nine views' samples, each bringing the
    // variance of its own share) against path-traced pairs of variance 20 at each pixel: the
    // pilot predicts var_pt / (9 (var_y + var_s / B) (c0 + B c1)). With eps far above the
    // squared means every pixel weighs 1/eps (a shared one 9 / eps).
    const int pixels = 40000;
    const double eps = 1e6, var_pt = 20.0;
    MvSplitProbe probe = synthetic_pilot(pixels, 0.5, 4.0, false, 21);
    EXPECT_EQ(predicted_gain(split_statistics({probe}, eps), 2, 1), 0.0); // no path-traced pairs: no prediction
    std::mt19937_64 rng(22);
    std::normal_distribution<double> pt(0.0, std::sqrt(var_pt));
    for (int p = 0; p < pixels; ++p) probe.path_traced.push_back({6.0 + pt(rng), 6.0 + pt(rng)});
    const SplitStatistics st = split_statistics({probe}, eps);
    EXPECT_EQ(st.shared.pixels, uint64_t(pixels));
    EXPECT_EQ(st.pt_pixels, uint64_t(pixels));
    EXPECT_NEAR(st.pt_v * eps, var_pt, 0.05 * var_pt);
    for (int b : {1, 2, 8}) {
        const double expected = var_pt / (9.0 * (0.5 + 4.0 / b) * (st.c0 + b * st.c1));
        EXPECT_NEAR(predicted_gain(st, b, 1), expected, 0.05 * expected) << b;
    }
}
