// The film of every rendering method (renderer/film.h): Welford's running deviations give the
// variance of the pixel mean that the estimates' two-pass variance gives, also for estimates
// weighing less than one (thinned passes); merging the films of disjoint estimates gives the
// film of all of them; a film goes through a state file unchanged, and a state of another film
// is refused.
#include "mvpt/renderer/film.h"
#include "mvpt/renderer/render_state.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

using namespace mvpt;

namespace {
/// Heavy-tailed estimates, like a path tracer's: mostly small, now and then a firefly.
std::vector<double> estimates(std::mt19937 &rng, int n) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<double> out;
    for (int i = 0; i < n; ++i) out.push_back(u(rng) < 0.05 ? 50.0 * u(rng) : u(rng));
    return out;
}

void add_grey(Film &film, size_t p, double v) {
    const double rgb[3] = {v, 0.5 * v, 2.0 * v};
    film.add(p, rgb);
}

/// The mean and the variance of the mean, from all estimates at once.
void two_pass(const std::vector<double> &x, double &mean, double &var) {
    mean = 0.0;
    for (double v : x) mean += v;
    mean /= double(x.size());
    double ss = 0.0;
    for (double v : x) ss += (v - mean) * (v - mean);
    var = x.size() > 1 ? ss / double(x.size() - 1) / double(x.size()) : 0.0;
}
} // namespace

TEST(Film, WelfordGivesTheVarianceOfTheMean) {
    std::mt19937 rng(7);
    Film film(4, 1);
    const int counts[4] = {0, 1, 2, 1000};
    std::vector<std::vector<double>> x(4);
    for (size_t p = 0; p < 4; ++p) {
        x[p] = estimates(rng, counts[p]);
        for (double v : x[p]) add_grey(film, p, v);
    }
    for (size_t p = 0; p < 4; ++p) {
        float rgb[3], var[3];
        film.develop(p, rgb, var);
        EXPECT_EQ(film.samples(p), uint32_t(counts[p]));
        if (counts[p] == 0) {
            EXPECT_EQ(rgb[0], 0.f);
            continue;
        }
        double mean, v;
        two_pass(x[p], mean, v);
        EXPECT_NEAR(rgb[0], mean, 1e-6 * mean) << "pixel " << p;
        EXPECT_NEAR(rgb[2], 2.0 * mean, 2e-6 * mean) << "pixel " << p;
        EXPECT_NEAR(var[0], v, 1e-5 * v + 1e-12) << "pixel " << p;
        EXPECT_NEAR(var[1], 0.25 * v, 1e-5 * v + 1e-12) << "pixel " << p;
    }
}

TEST(Film, MergedFilmsAreTheFilmOfAllEstimates) {
    std::mt19937 rng(11);
    Film all(3, 2), a(3, 2), b(3, 2);
    // Per pixel, how many estimates go to a and to b (some pixels have none in one of them).
    const int split[6][2] = {{0, 5}, {5, 0}, {1, 1}, {3, 700}, {400, 2}, {0, 0}};
    for (size_t p = 0; p < 6; ++p) {
        const std::vector<double> x = estimates(rng, split[p][0] + split[p][1]);
        for (size_t i = 0; i < x.size(); ++i) {
            add_grey(all, p, x[i]);
            add_grey(i < size_t(split[p][0]) ? a : b, p, x[i]);
        }
    }
    a.merge(b);
    for (size_t p = 0; p < 6; ++p) {
        float rgb[3], var[3], rgb_all[3], var_all[3];
        a.develop(p, rgb, var);
        all.develop(p, rgb_all, var_all);
        EXPECT_EQ(a.samples(p), all.samples(p));
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(rgb[c], rgb_all[c], 1e-6 * std::abs(rgb_all[c])) << "pixel " << p;
            EXPECT_NEAR(var[c], var_all[c], 1e-4 * var_all[c] + 1e-12) << "pixel " << p;
        }
    }
}

TEST(Film, WeightedEstimatesGiveThePrecisionWeightedMean) {
    // Estimates of weight q whose variance is 1/q that of a weight-1 estimate (a thinned
    // pass): the mean weights them by q, and the variance of the mean is that of k estimates
    // of total weight sum(q), from their spread.
    std::mt19937 rng(5);
    std::normal_distribution<double> normal(0.0, 1.0);
    const double sigma = 0.5, mu = 2.0;
    const double weights[5] = {1.0, 1.0, 1.0, 0.25, 1.0};
    Film film(1, 1);
    constexpr int Trials = 20000;
    double mean_sum = 0.0, mean_sq = 0.0, var_sum = 0.0;
    for (int trial = 0; trial < Trials; ++trial) {
        Film f(1, 1);
        for (double q : weights) {
            const double v = mu + sigma / std::sqrt(q) * normal(rng), rgb[3] = {v, v, v};
            f.add(0, rgb, q);
            if (q < 1.0) f.short_weight += 1.0 - q; // what the renderer adds after the pass
        }
        float rgb[3], var[3];
        f.develop(0, rgb, var);
        mean_sum += rgb[0], mean_sq += double(rgb[0]) * rgb[0], var_sum += var[0];
        if (trial == 0) film = f;
    }
    const double total = 4.25, mean = mean_sum / Trials, spread = mean_sq / Trials - mean * mean;
    const double expected = sigma * sigma / total; // the precision-weighted mean's variance
    EXPECT_NEAR(mean, mu, 4.0 * std::sqrt(expected / Trials));
    EXPECT_NEAR(spread, expected, 0.05 * expected);
    EXPECT_NEAR(var_sum / Trials, expected, 0.05 * expected); // unbiased, as for weight 1
    EXPECT_DOUBLE_EQ(film.weight(0), total);
    // Weighing the thinned estimate as a whole one is found out: its mean would be another.
    Film unweighted(1, 1), weighted(1, 1);
    const double a[3] = {1.0, 1.0, 1.0}, b[3] = {4.0, 4.0, 4.0};
    unweighted.add(0, a), unweighted.add(0, b);
    weighted.add(0, a), weighted.add(0, b, 0.5), weighted.short_weight = 0.5;
    float u[3], w[3], var[3];
    unweighted.develop(0, u, var), weighted.develop(0, w, var);
    EXPECT_FLOAT_EQ(u[0], 2.5f);
    EXPECT_FLOAT_EQ(w[0], 2.0f);
}

TEST(Film, MergedWeightedFilmsAreTheFilmOfAllEstimates) {
    // Two films, each with a thinned estimate (added after the earlier estimates' weights are
    // known, as the renderer adds them), merge into the film of all nine estimates.
    std::mt19937 rng(13);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    Film a(1, 1), b(1, 1), all(1, 1);
    for (int i = 0; i < 9; ++i) {
        const double q = i == 4 ? 0.3 : i == 8 ? 0.6 : 1.0, v = u(rng), rgb[3] = {v, 2.0 * v, v * v};
        Film &part = i < 5 ? a : b;
        part.add(0, rgb, q), all.add(0, rgb, q);
        part.short_weight += 1.0 - q, all.short_weight += 1.0 - q;
    }
    a.merge(b);
    float rgb[3], var[3], rgb_all[3], var_all[3];
    a.develop(0, rgb, var), all.develop(0, rgb_all, var_all);
    EXPECT_DOUBLE_EQ(a.weight(0), 9.0 - 0.7 - 0.4);
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(rgb[c], rgb_all[c], 1e-6 * std::abs(rgb_all[c]));
        EXPECT_NEAR(var[c], var_all[c], 1e-4 * var_all[c]);
    }
}

TEST(Film, GoesThroughAStateFileUnchanged) {
    const std::string path = ::testing::TempDir() + "film-state.bin";
    std::mt19937 rng(3);
    Film pt(5, 3), mv(5, 3, 2, MvEstimator::Weighted, false, true);
    for (size_t p = 0; p < pt.pixels(); ++p)
        for (double v : estimates(rng, int(p))) add_grey(pt, p, v), add_grey(mv, p, v);
    mv.native[4] = 9, mv.received[4] = 17, mv.w_sum[4] = 0.75f, mv.lw[5] = 1.5, mv.e_sq[2] = 3.f, mv.level = 0.25;
    mv.short_weight = 0.375;
    mv.set_map(std::vector<uint16_t>(mv.pixels(), 3));
    pt.nonfinite = 2;
    {
        StateWriter out(path, "{}");
        pt.save(out), mv.save(out);
        out.commit();
    }
    StateReader in(path);
    Film pt2(5, 3), mv2(5, 3, 2, MvEstimator::Weighted, false, true);
    pt2.load(in), mv2.load(in);
    in.finish();
    EXPECT_EQ(pt2.count, pt.count);
    EXPECT_EQ(pt2.sum, pt.sum);
    EXPECT_EQ(pt2.m2, pt.m2);
    EXPECT_EQ(pt2.nonfinite, 2u);
    EXPECT_EQ(mv2.count, mv.count);
    EXPECT_EQ(mv2.native, mv.native);
    EXPECT_EQ(mv2.received, mv.received);
    EXPECT_EQ(mv2.w_sum, mv.w_sum);
    EXPECT_EQ(mv2.lw, mv.lw);
    EXPECT_EQ(mv2.e_sq, mv.e_sq);
    EXPECT_EQ(mv2.map, mv.map);
    EXPECT_EQ(mv2.map_total, 3u * mv.pixels());
    EXPECT_EQ(mv2.level, 0.25);
    EXPECT_EQ(mv2.short_weight, 0.375);
    std::remove(path.c_str());
}

TEST(Film, RefusesTheStateOfAnotherFilm) {
    const std::string path = ::testing::TempDir() + "film-state-other.bin";
    {
        StateWriter out(path, "{}");
        Film(4, 4).save(out);
        Film(4, 4, 1, MvEstimator::Balance, true, false).save(out);
        out.commit();
    }
    StateReader in(path);
    Film smaller(4, 3);
    EXPECT_THROW(smaller.load(in), StateError);
    StateReader in2(path);
    Film pt(4, 4), other_estimator(4, 4, 1, MvEstimator::Weighted, true, false);
    pt.load(in2);
    EXPECT_THROW(other_estimator.load(in2), StateError);
    std::remove(path.c_str());
}

namespace {
/// Adds to `pass` at view-pixel `key` the sums W*L + E = s (RGB, E's mean e) and W = w.
void add_sums(MvPassFilm &pass, uint32_t key, const double s[3], double w, double e) {
    SplatEntry entry;
    for (int c = 0; c < 3; ++c) entry.lw[c] = to_fixed(s[c]);
    entry.w = to_fixed(w), entry.e[0] = to_fixed(e);
    entry.key = key, entry.count = 1;
    pass.add(entry);
}
} // namespace

TEST(Film, FirstTwoPassesTakeEachOthersRatioAsBeta) {
    // Two pixels, two passes: pixel 0 gets (S, W) = ((0.3, 0.6, 0.9), 0.5) then ((0.8, 0.8, 0.8), 2);
    // pixel 1 nothing, then ((0.2, 0.2, 0.2), 0.25). Each pass takes the other's S / W as beta:
    // pixel 0: v1 = S1 + (0.4)(1 - 0.5), v2 = S2 + (0.6, 1.2, 1.8)(1 - 2); pixel 1: v1 = 0.8, v2 = 0.2.
    const double s1[3] = {0.3, 0.6, 0.9}, s2[3] = {0.8, 0.8, 0.8}, s3[3] = {0.2, 0.2, 0.2};
    const double v1[3] = {0.5, 0.8, 1.1}, v2[3] = {0.2, -0.4, -1.0};
    Film film(2, 1, 0, MvEstimator::Balance, true, true), plain(2, 1, 0, MvEstimator::Balance, true, true);
    MvPassFilm pass({SplatFootprint::box(2, 1)}, false);
    add_sums(pass, 0, s1, 0.5, 0.1);
    film.hold(pass, 0, 0, 2);
    film.holding = true;
    EXPECT_EQ(film.count[0], 0u);
    EXPECT_EQ(film.native[0], 1u);
    add_sums(pass, 0, s2, 2.0, 0.0);
    add_sums(pass, 1, s3, 0.25, 0.0);
    film.fold(pass, 0, 0, 2);
    // The same estimates added one by one.
    for (const double *v : {v1, v2}) plain.add(0, v);
    const double p1[3] = {0.8, 0.8, 0.8};
    for (const double *v : {p1, s3}) plain.add(1, v);
    for (size_t p = 0; p < 2; ++p) {
        float rgb[3], var[3], want[3], want_var[3];
        film.develop(p, rgb, var);
        plain.develop(p, want, want_var);
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(rgb[c], want[c], 1e-6) << p << " " << c;
            EXPECT_NEAR(var[c], want_var[c], 1e-6) << p << " " << c;
        }
        EXPECT_EQ(film.count[p], 2u);
        EXPECT_EQ(film.native[p], 2u);
    }
    EXPECT_FLOAT_EQ(film.weight_sum(0), 1.25f); // (0.5 + 2) / 2
    EXPECT_FLOAT_EQ(film.e_sum[0], 0.1f);
}

TEST(Film, AHeldPassReleasedIsThePassWithoutBeta) {
    const double s[3] = {0.3, 0.6, 0.9};
    Film held(1, 1, 0, MvEstimator::Balance, true, false), folded(1, 1, 0, MvEstimator::Balance, true, false);
    MvPassFilm pass({SplatFootprint::box(1, 1)}, false);
    add_sums(pass, 0, s, 0.5, 0.0);
    held.hold(pass, 0, 0, 1);
    held.holding = true;
    held.release(0, 1);
    add_sums(pass, 0, s, 0.5, 0.0);
    folded.fold(pass, 0, 0, 1);
    EXPECT_EQ(held.count, folded.count);
    EXPECT_EQ(held.sum, folded.sum);
    EXPECT_EQ(held.w_sum, folded.w_sum);
    EXPECT_EQ(held.native, folded.native);
}
