// The fixed-point splats of multi-view path tracing (splat_film.h): exact integer sums whatever
// the order, the cache size or the number of threads; contributions that are not finite or too
// large rejected whole, whichever channel holds the bad value.
#include "mvpt/splat_film.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <thread>

using namespace mvpt;

namespace {
/// Every view-pixel's sums of `film`, read and cleared.
std::vector<SplatEntry> take_all(MvPassFilm &film) {
    std::vector<SplatEntry> out;
    for (uint32_t k = 0; k < film.size(); ++k) out.push_back(film.take(k));
    return out;
}

void expect_same(const std::vector<SplatEntry> &a, const std::vector<SplatEntry> &b, int e_channels) {
    ASSERT_EQ(a.size(), b.size());
    for (size_t k = 0; k < a.size(); ++k) {
        for (int c = 0; c < 3; ++c) ASSERT_EQ(a[k].lw[c], b[k].lw[c]) << "pixel " << k << " channel " << c;
        for (int c = 0; c < e_channels; ++c) ASSERT_EQ(a[k].e[c], b[k].e[c]) << "pixel " << k << " E channel " << c;
        ASSERT_EQ(a[k].w, b[k].w) << "pixel " << k;
        ASSERT_EQ(a[k].count, b[k].count) << "pixel " << k;
    }
}

/// A random contribution: (slot, pixel, W*L, W, E or none).
struct Contribution {
    int slot;
    uint32_t pixel;
    Spectrum lw;
    float w;
    bool native;
    Spectrum e;
};

std::vector<Contribution> random_contributions(const std::vector<size_t> &pixels, size_t n, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    std::vector<Contribution> out;
    for (size_t i = 0; i < n; ++i) {
        Contribution c;
        c.slot = int(rng() % pixels.size());
        c.pixel = uint32_t(rng() % pixels[size_t(c.slot)]);
        c.lw = Spectrum(u(rng), 1e-6f * u(rng), 300.f * u(rng) - 100.f);
        c.w = u(rng);
        c.native = u(rng) < 0.2f;
        c.e = Spectrum(2.f * u(rng), u(rng), 0.f);
        out.push_back(c);
    }
    return out;
}

void add_to(SplatCache &cache, const Contribution &c) {
    bool ok = c.native ? cache.add(c.slot, c.pixel, c.lw, c.w, c.e) : cache.add(c.slot, c.pixel, c.lw, c.w);
    ASSERT_TRUE(ok);
}
} // namespace

TEST(SplatFilm, SumsAreExactAndOrderFree) {
    for (bool e_rgb : {false, true}) {
        MvPassFilm a({4}, e_rgb), b({4}, e_rgb);
        SplatCache ca(a), cb(b, 1); // b's cache holds one entry: every other pixel displaces it
        const float v[3] = {0.1f, 1e-7f, 3.5f};
        for (int i = 0; i < 3; ++i) ca.add(0, 2, Spectrum(v[i], 2 * v[i], 0.f), v[i]);
        for (int i = 2; i >= 0; --i) {
            cb.add(0, 2, Spectrum(v[i], 2 * v[i], 0.f), v[i]);
            cb.add(0, 1, Spectrum(0.f), 0.f); // displaces pixel 2
        }
        ca.add(0, 2, Spectrum(1.f), 0.5f, Spectrum(0.25f, 0.5f, 0.75f));
        cb.add(0, 2, Spectrum(1.f), 0.5f, Spectrum(0.25f, 0.5f, 0.75f));
        ca.flush(), cb.flush();
        const SplatEntry x = a.take(2), y = b.take(2);
        for (int c = 0; c < 3; ++c) EXPECT_EQ(x.lw[c], y.lw[c]);
        EXPECT_EQ(x.w, y.w);
        EXPECT_EQ(x.count, 4u);
        EXPECT_EQ(x.w, to_fixed(0.1f) + to_fixed(1e-7f) + to_fixed(3.5f) + to_fixed(0.5f));
        // The native contribution adds E into W*L + E, and E alone (its mean, or RGB).
        EXPECT_EQ(x.lw[0], to_fixed(0.1f) + to_fixed(1e-7f) + to_fixed(3.5f) + to_fixed(1.25f));
        if (e_rgb) EXPECT_EQ(x.e[2], to_fixed(0.75f));
        else EXPECT_EQ(x.e[0], to_fixed(0.5f));
        EXPECT_EQ(a.take(1).count, 0u); // other pixels untouched
        EXPECT_EQ(b.take(2).count, 0u); // take() clears
    }
}

TEST(SplatFilm, IndependentOfCacheSizeAndThreads) {
    const std::vector<size_t> pixels = {37, 1, 200, 64};
    const auto contribs = random_contributions(pixels, 20000, 5);
    MvPassFilm ref(pixels, true);
    {
        SplatCache cache(ref, 1);
        for (const Contribution &c : contribs) add_to(cache, c);
        cache.flush();
    }
    const auto expected = take_all(ref);
    for (size_t entries : {size_t(2), size_t(64), size_t(1) << 15})
        for (int threads : {1, 3}) {
            MvPassFilm film(pixels, true);
            std::vector<std::thread> pool;
            for (int t = 0; t < threads; ++t)
                pool.emplace_back([&, t] {
                    SplatCache cache(film, entries);
                    for (size_t i = size_t(t); i < contribs.size(); i += size_t(threads)) add_to(cache, contribs[i]);
                    cache.flush();
                });
            for (auto &th : pool) th.join();
            expect_same(take_all(film), expected, 3);
        }
}

TEST(SplatFilm, DiscardAddsNothing) {
    MvPassFilm film({8}, false);
    SplatCache cache(film, 4);
    cache.add(0, 3, Spectrum(1.f), 1.f);
    cache.discard();
    cache.flush();
    EXPECT_EQ(film.take(3).w, 0);
}

TEST(SplatFilm, RejectsWholeContributionsThatDoNotFit) {
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = INFINITY, big = float(SplatMax);
    for (int channel = 0; channel < 4; ++channel)
        for (float bad : {nan, inf, -inf, big, -big}) {
            MvPassFilm film({1}, true);
            SplatCache cache(film);
            float x[4] = {1.f, 1.f, 1.f, 1.f};
            x[channel] = bad;
            EXPECT_FALSE(cache.add(0, 0, Spectrum(x[0], x[1], x[2]), x[3])) << "channel " << channel << " value " << bad;
            // The native view's radiance E is checked too, before anything is added.
            Spectrum e(1.f);
            if (channel < 3) {
                e[channel] = bad;
                EXPECT_FALSE(cache.add(0, 0, Spectrum(1.f), 1.f, e));
            }
            cache.flush();
            const SplatEntry t = film.take(0);
            EXPECT_EQ(t.count, 0u);
            for (int c = 0; c < 3; ++c) EXPECT_EQ(t.lw[c], 0) << "channel " << c;
            EXPECT_EQ(t.w, 0);
        }
    // W*L and E that fit but whose sum does not.
    MvPassFilm film({1}, false);
    SplatCache cache(film);
    EXPECT_FALSE(cache.add(0, 0, Spectrum(0.75f * big), 1.f, Spectrum(0.75f * big)));
    EXPECT_TRUE(cache.add(0, 0, Spectrum(std::nextafter(big, 0.f)), 1.f, Spectrum(-1.f)));
    cache.flush();
    EXPECT_EQ(film.take(0).e[0], to_fixed(-1.f));
}
