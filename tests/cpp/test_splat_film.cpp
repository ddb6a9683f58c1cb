// The fixed-point splats of multi-view path tracing (splat_film.h): exact integer sums whatever
// the order, the cache size or the number of threads; contributions that are not finite or too
// large rejected whole, whichever channel holds the bad value.
#include "mvpt/core/plugin.h"
#include "mvpt/core/sampler.h"
#include "mvpt/render/splat_film.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <thread>

using namespace mvpt;

namespace {
/// Box-filtered views of n[s] pixels.
std::vector<SplatFootprint> boxes(const std::vector<size_t> &n) {
    std::vector<SplatFootprint> out;
    for (size_t v : n) out.push_back(SplatFootprint::box(int(v), 1));
    return out;
}

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
    const Vec2f film(0.f, 0.f);
    bool ok = c.native ? cache.add(c.slot, c.pixel, film, 0, c.lw, c.w, c.e) : cache.add(c.slot, c.pixel, film, 0, c.lw, c.w);
    ASSERT_TRUE(ok);
}
} // namespace

TEST(SplatFilm, SumsAreExactAndOrderFree) {
    for (bool e_rgb : {false, true}) {
        MvPassFilm a(boxes({4}), e_rgb), b(boxes({4}), e_rgb);
        SplatCache ca(a), cb(b, 1); // b's cache holds one entry: every other pixel displaces it
        const float v[3] = {0.1f, 1e-7f, 3.5f};
        for (int i = 0; i < 3; ++i) ca.add(0, 2, Vec2f(0.f, 0.f), 0, Spectrum(v[i], 2 * v[i], 0.f), v[i]);
        for (int i = 2; i >= 0; --i) {
            cb.add(0, 2, Vec2f(0.f, 0.f), 0, Spectrum(v[i], 2 * v[i], 0.f), v[i]);
            cb.add(0, 1, Vec2f(0.f, 0.f), 0, Spectrum(0.f), 0.f); // displaces pixel 2
        }
        ca.add(0, 2, Vec2f(0.f, 0.f), 0, Spectrum(1.f), 0.5f, Spectrum(0.25f, 0.5f, 0.75f));
        cb.add(0, 2, Vec2f(0.f, 0.f), 0, Spectrum(1.f), 0.5f, Spectrum(0.25f, 0.5f, 0.75f));
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
    MvPassFilm ref(boxes(pixels), true);
    {
        SplatCache cache(ref, 1);
        for (const Contribution &c : contribs) add_to(cache, c);
        cache.flush();
    }
    const auto expected = take_all(ref);
    for (size_t entries : {size_t(2), size_t(64), size_t(1) << 15})
        for (int threads : {1, 3}) {
            MvPassFilm film(boxes(pixels), true);
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
    MvPassFilm film(boxes({8}), false);
    SplatCache cache(film, 4);
    cache.add(0, 3, Vec2f(0.f, 0.f), 0, Spectrum(1.f), 1.f);
    cache.discard();
    cache.flush();
    EXPECT_EQ(film.take(3).w, 0);
}

TEST(SplatFilm, RejectsWholeContributionsThatDoNotFit) {
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = INFINITY, big = float(SplatMax);
    for (int channel = 0; channel < 4; ++channel)
        for (float bad : {nan, inf, -inf, big, -big}) {
            MvPassFilm film(boxes({1}), true);
            SplatCache cache(film);
            float x[4] = {1.f, 1.f, 1.f, 1.f};
            x[channel] = bad;
            EXPECT_FALSE(cache.add(0, 0, Vec2f(0.f, 0.f), 0, Spectrum(x[0], x[1], x[2]), x[3])) << "channel " << channel << " value " << bad;
            // The native view's radiance E is checked too, before anything is added.
            Spectrum e(1.f);
            if (channel < 3) {
                e[channel] = bad;
                EXPECT_FALSE(cache.add(0, 0, Vec2f(0.f, 0.f), 0, Spectrum(1.f), 1.f, e));
            }
            cache.flush();
            const SplatEntry t = film.take(0);
            EXPECT_EQ(t.count, 0u);
            for (int c = 0; c < 3; ++c) EXPECT_EQ(t.lw[c], 0) << "channel " << c;
            EXPECT_EQ(t.w, 0);
        }
    // W*L and E that fit but whose sum does not.
    MvPassFilm film(boxes({1}), false);
    SplatCache cache(film);
    EXPECT_FALSE(cache.add(0, 0, Vec2f(0.f, 0.f), 0, Spectrum(0.75f * big), 1.f, Spectrum(0.75f * big)));
    EXPECT_TRUE(cache.add(0, 0, Vec2f(0.f, 0.f), 0, Spectrum(std::nextafter(big, 0.f)), 1.f, Spectrum(-1.f)));
    cache.flush();
    EXPECT_EQ(film.take(0).e[0], to_fixed(-1.f));
}

namespace {
std::shared_ptr<ReconstructionFilter> make_filter(const std::string &type) {
    Properties p("rfilter", type);
    return std::static_pointer_cast<ReconstructionFilter>((*PluginRegistry::find("rfilter", type))(p, LoadContext{}));
}
} // namespace

TEST(SplatFilm, FootprintSpreadsWithTheFilterDensity) {
    // A contribution at film position x adds h(x - c_i) v to every pixel i of the crop window
    // whose centre c_i is within the radius (h: the normalised filter, negative in places for
    // mitchell and lanczos), and counts in the pixel that holds x; pixels outside the crop
    // window get nothing. Taps with |h| below SplatCache::TapThreshold are kept with probability
    // |h| / threshold and then add ±threshold v (h's sign): over many native samples each such
    // tap is kept that often, and every contribution keeps floor or ceil of the sum of
    // |h| / threshold of its small taps.
    constexpr float Tau = SplatCache::TapThreshold;
    constexpr int Samples = 4000;
    for (const char *type : {"tent", "gaussian", "mitchell", "lanczos"}) {
        auto filter = make_filter(type);
        const float r = filter->radius();
        bool negative_taps = false;
        // A 10 x 8 crop window at (20, 30) of the full film.
        MvPassFilm film({SplatFootprint::of(20, 30, 10, 8, *filter, Sampler::dimension_key(5))}, false);
        SplatCache cache(film, 8); // small: entries are displaced while the footprint is added
        for (Vec2f x : {Vec2f(25.3f, 33.8f), Vec2f(20.2f, 30.9f), Vec2f(19.7f, 37.7f), Vec2f(29.99f, 36.01f)}) {
            std::vector<int> kept(80, 0);
            std::vector<float> h(80, 0.f);
            double small_sum = 0.0;
            for (int p = 0; p < 80; ++p) {
                const float dx = x.x - (float(20 + p % 10) + 0.5f), dy = x.y - (float(30 + p / 10) + 0.5f);
                h[size_t(p)] = std::abs(dx) < r && std::abs(dy) < r ? filter->eval_1d(dx) * filter->eval_1d(dy) : 0.f;
                if (std::abs(h[size_t(p)]) < Tau) small_sum += std::abs(h[size_t(p)]) / Tau;
                negative_taps |= h[size_t(p)] < 0.f;
            }
            for (uint64_t sample = 0; sample < Samples; ++sample) {
                ASSERT_TRUE(cache.add(0, 0, x, mix_bits(sample), Spectrum(2.f, 1.f, 0.5f), 0.25f, Spectrum(0.f, 3.f, 0.f)));
                cache.flush();
                uint32_t counted = 0;
                int kept_small = 0;
                for (int p = 0; p < 80; ++p) {
                    const SplatEntry e = film.take(uint32_t(p));
                    const int px = 20 + p % 10, py = 30 + p / 10;
                    const float hp = h[size_t(p)];
                    const bool holds = px == int(std::floor(x.x)) && py == int(std::floor(x.y));
                    ASSERT_EQ(e.count, holds ? 1u : 0u) << type;
                    counted += e.count;
                    if (std::abs(hp) >= Tau) {
                        ASSERT_EQ(e.w, to_fixed(0.25f * hp)) << type << " pixel " << px << "," << py;
                        ASSERT_EQ(e.lw[1], to_fixed(4.f * hp)) << type; // W*L + E
                        ASSERT_EQ(e.e[0], to_fixed(1.f * hp)) << type;  // E's mean
                    } else if (e.w != 0) {
                        ASSERT_NE(hp, 0.f) << type;
                        ASSERT_EQ(e.w, to_fixed(0.25f * std::copysign(Tau, hp))) << type;
                        ASSERT_EQ(e.lw[1], to_fixed(4.f * std::copysign(Tau, hp))) << type;
                        ++kept[size_t(p)], ++kept_small;
                    }
                }
                ASSERT_EQ(counted, x.x >= 20.f && x.y >= 30.f ? 1u : 0u);
                ASSERT_TRUE(kept_small == int(std::floor(small_sum)) || kept_small == int(std::ceil(small_sum)))
                    << type << " kept " << kept_small << " of sum " << small_sum;
            }
            // Each small tap is kept with probability |h| / threshold (binomial, 5 standard deviations).
            for (int p = 0; p < 80; ++p)
                if (std::abs(h[size_t(p)]) < Tau) {
                    const double q = std::abs(h[size_t(p)]) / Tau;
                    EXPECT_NEAR(kept[size_t(p)] / double(Samples), q, 5.0 * std::sqrt(q * (1.0 - q) / Samples) + 1e-9)
                        << type << " pixel " << p;
                }
            if (x.x < 20.f) EXPECT_GT(*std::max_element(h.begin(), h.end()), 0.f) << type; // the margin reaches the window
        }
        EXPECT_EQ(negative_taps, filter->has_negative_lobes()) << type;
    }
}

TEST(SplatFilm, MeanWritesCountsTheEntriesAFootprintAddsTo) {
    // SplatFootprint::mean_writes, a part of the cost model of the splits' choice, is the mean
    // number of pixels a contribution at a uniform position in a pixel adds to (its taps of
    // weight TapThreshold or more, and the small ones Russian roulette keeps), away from the
    // crop window's edges.
    constexpr int Samples = 20000;
    for (const char *type : {"box", "tent", "gaussian", "mitchell", "lanczos"}) {
        auto filter = make_filter(type);
        MvPassFilm film({SplatFootprint::of(0, 0, 48, 48, *filter, Sampler::dimension_key(5))}, false);
        SplatCache cache(film);
        std::mt19937 rng(11);
        std::uniform_real_distribution<float> u(0.f, 1.f);
        double writes = 0.0, squares = 0.0;
        for (uint64_t sample = 0; sample < Samples; ++sample) {
            const Vec2f x(20.f + u(rng), 20.f + u(rng));
            ASSERT_TRUE(cache.add(0, 20 * 48 + 20, x, mix_bits(sample), Spectrum(1.f), 1.f));
            cache.flush();
            int n = 0;
            for (uint32_t k = 0; k < film.size(); ++k) n += film.take(k).w != 0;
            writes += n, squares += double(n) * n;
        }
        const double mean = writes / Samples, sd = std::sqrt(squares / Samples - mean * mean);
        const double expected = film.footprint(0).mean_writes();
        if (std::string(type) == "box") EXPECT_EQ(expected, 1.0);
        // Five standard errors, and 1/2 % for the grid of positions mean_writes averages over.
        EXPECT_NEAR(mean, expected, 5.0 * sd / std::sqrt(double(Samples)) + 0.005 * expected) << type;
    }
}

TEST(SplatFilm, FilterSamplesAreDistributedAndWeightedByTheFilter) {
    // sample() draws offsets with density |h| / ∫|h| per axis (h = eval_1d) and weights them by
    // h / p: a histogram of the offsets matches that density, and the weighted histogram
    // matches h itself (the other axis's weights average to ∫h = 1).
    for (const char *type : {"box", "tent", "gaussian", "mitchell", "catmullrom", "lanczos"}) {
        auto filter = make_filter(type);
        const float r = filter->radius(), abs_integral = filter->abs_integral_1d();
        constexpr int Bins = 40, N = 400000;
        std::vector<double> hist(Bins, 0.0), weighted(Bins, 0.0);
        std::mt19937 rng(3);
        std::uniform_real_distribution<float> u(0.f, 1.f);
        for (int i = 0; i < N; ++i) {
            float weight = 0.f;
            const Vec2f d = filter->sample(Vec2f(u(rng), u(rng)), weight);
            const float sign = filter->eval_1d(d.x) * filter->eval_1d(d.y) < 0.f ? -1.f : 1.f;
            ASSERT_EQ(weight, sign * abs_integral * abs_integral) << type << " offset " << d.x << "," << d.y;
            const int b = std::min(Bins - 1, int((d.x + r) / (2.f * r) * Bins));
            hist[size_t(b)] += 1.0;
            weighted[size_t(b)] += weight;
        }
        double peak = 0.0;
        for (int b = 0; b < Bins; ++b) {
            // h's mean over the bin, by a fine midpoint rule, and |h|'s.
            double mean = 0.0, abs_mean = 0.0;
            for (int k = 0; k < 100; ++k) {
                const float h = filter->eval_1d(-r + (float(b) + (k + 0.5f) / 100.f) * 2.f * r / Bins);
                mean += h / 100.0, abs_mean += std::abs(h) / 100.0;
            }
            const double width = 2.0 * r / Bins, expected = abs_mean / abs_integral * width * N;
            EXPECT_NEAR(hist[size_t(b)], expected, 5.0 * std::sqrt(expected) + 1.0) << type << " bin " << b;
            // Each weight is ±abs_integral^2: the weighted count's deviation is that times the count's.
            const double spread = abs_integral * abs_integral * (5.0 * std::sqrt(expected) + 1.0);
            EXPECT_NEAR(weighted[size_t(b)], mean * width * N, spread) << type << " bin " << b;
            peak = std::max(peak, abs_mean);
        }
        EXPECT_LE(peak, filter->peak_1d() * 1.0001) << type;
    }
}

TEST(SplatFilm, SignedFiltersFollowMitsubasDefinitions) {
    // Mitchell-Netravali (B = C = 1/3) integrates to 1: h(0) = 8/9, h(1) = 1/18, h(1.5) =
    // -5/144; Catmull-Rom (B = 0, C = 1/2): h(0) = 1, h(1.5) = -1/16; Lanczos of 3 lobes is
    // sinc(x) sinc(x / 3) over its integral. A table holds each bin's midpoint value: read
    // half a bin (1/256 or 3/1024 px) off, within that times the slope.
    auto at = [](const ReconstructionFilter &f, float d) { return f.eval_1d(d); };
    auto mitchell = make_filter("mitchell"), catmullrom = make_filter("catmullrom"), lanczos = make_filter("lanczos");
    EXPECT_NEAR(at(*mitchell, 0.f), 8.f / 9.f, 1e-3f);
    EXPECT_NEAR(at(*mitchell, 1.f), 1.f / 18.f, 1e-3f);
    EXPECT_NEAR(at(*mitchell, 1.5f), -5.f / 144.f, 1e-3f);
    EXPECT_NEAR(at(*catmullrom, 0.f), 1.f, 1e-3f);
    EXPECT_NEAR(at(*catmullrom, 1.5f), -1.f / 16.f, 1e-3f);
    EXPECT_FLOAT_EQ(mitchell->radius(), 2.f);
    EXPECT_FLOAT_EQ(lanczos->radius(), 3.f);
    auto sinc3 = [](double x) {
        const double a = 3.14159265358979 * std::abs(x);
        return a < 1e-9 ? 1.0 : std::sin(a) * std::sin(a / 3.0) / (a * a / 3.0);
    };
    double integral = 0.0;
    constexpr int Steps = 300000;
    for (int k = 0; k < Steps; ++k) integral += sinc3(-3.0 + (k + 0.5) * 6.0 / Steps) * 6.0 / Steps;
    for (float d : {0.f, 0.5f, 1.25f, 1.5f, 2.5f}) EXPECT_NEAR(at(*lanczos, d), sinc3(d) / integral, 2e-3) << d;
    EXPECT_LT(at(*lanczos, 1.5f), 0.f);
    for (auto *f : {mitchell.get(), catmullrom.get(), lanczos.get()}) EXPECT_TRUE(f->has_negative_lobes());
    for (const char *type : {"box", "tent", "gaussian"}) EXPECT_FALSE(make_filter(type)->has_negative_lobes()) << type;
}

TEST(SplatFilm, ManyViewsShareARegionWithoutDisplacing) {
    // 81 views of 64 x 64 pixels (a 9 x 9 light field): the native samples of a region of tiles
    // land in every view on a window of up to 32 x 32 pixels, offset by the view's disparity.
    // Each view owns a 32 x 32 block of the cache (entries_for(81)) with its pixels on it as on
    // a torus, so all those windows are held at once: adding the region's contributions three
    // times over displaces no entry before the flush.
    constexpr int Views = 81, Size = 64, Window = 32;
    const std::vector<SplatFootprint> views(Views, SplatFootprint::box(Size, Size));
    MvPassFilm film(views, false);
    SplatCache cache(film);
    EXPECT_EQ(SplatCache::entries_for(Views), size_t(1) << 17);
    for (int k = 0; k < 3; ++k)
        for (int v = 0; v < Views; ++v) {
            const int x0 = 10 + v % 9, y0 = 20 + v / 9; // the view's disparity
            for (int y = y0; y < y0 + Window; ++y)
                for (int x = x0; x < x0 + Window; ++x)
                    ASSERT_TRUE(cache.add(v, uint32_t(y * Size + x), Vec2f(float(x) + 0.5f, float(y) + 0.25f), 0,
                                          Spectrum(1.f), 1.f));
        }
    EXPECT_EQ(cache.displaced(), 0u);
    cache.flush();
    for (int v = 0; v < Views; ++v)
        EXPECT_EQ(film.take(film.offset(v) + uint32_t((20 + v / 9 + 5) * Size + 10 + v % 9 + 7)).count, 3u);
    // A window wider than a view's block wraps onto itself: entries are displaced (and the
    // sums stay exact, SplatFilm.IndependentOfCacheSizeAndThreads).
    SplatCache small(film);
    for (int k = 0; k < 2; ++k)
        for (int x = 0; x < 2 * Window; ++x) small.add(0, uint32_t(x), Vec2f(float(x) + 0.5f, 0.5f), 0, Spectrum(1.f), 1.f);
    EXPECT_EQ(small.displaced(), uint64_t(2 * 2 * Window - Window));
}
