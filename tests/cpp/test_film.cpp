// The film of every rendering method (renderer/film.h): Welford's running deviations give the
// variance of the pixel mean that the estimates' two-pass variance gives; merging the films of
// disjoint estimates gives the film of all of them; a film goes through a state file unchanged,
// and a state of another film is refused.
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

TEST(Film, GoesThroughAStateFileUnchanged) {
    const std::string path = ::testing::TempDir() + "film-state.bin";
    std::mt19937 rng(3);
    Film pt(5, 3), mv(5, 3, 2, MvEstimator::Weighted, false, true);
    for (size_t p = 0; p < pt.pixels(); ++p)
        for (double v : estimates(rng, int(p))) add_grey(pt, p, v), add_grey(mv, p, v);
    mv.native[4] = 9, mv.received[4] = 17, mv.w_sum[4] = 0.75f, mv.lw[5] = 1.5, mv.e_sq[2] = 3.f, mv.level = 0.25;
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
