// mv_sum_entries + mv_splat_entries (one vector per entry, rounded by adding 1.5 * 2^52) against
// mv_entry_value + SplatCache::add (llrint per channel): the same integers in every channel,
// the same contributions dropped, for values that take each of its three paths; and the sum of
// two splits at half weight against its scalar value.
#include "mvpt/integrators/multiview/mv_sample.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

using namespace mvpt;

TEST(MvSplat, EntryKernelEqualsScalarAdds) {
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    // Mostly ordinary values; some beyond 2^21 (to_fixed per channel), beyond SplatMax or not
    // finite (dropped), negative, zero.
    auto value = [&]() -> float {
        float r = u(rng);
        if (r < 0.70f) return 4.f * u(rng);
        if (r < 0.80f) return -4.f * u(rng);
        if (r < 0.88f) return std::ldexp(1.f + u(rng), 21 + int(rng() % 8)); // [2^21, 2^29): fits
        if (r < 0.91f) return std::ldexp(1.f + u(rng), 32);                  // >= SplatMax
        if (r < 0.93f) return (rng() & 1) ? INFINITY : nan;
        return 0.f;
    };
    const std::vector<size_t> pixels_per_view = {5, 9, 3};
    int paths[3] = {}; // vector, per channel, dropped (by the values the reference adds)
    for (int trial = 0; trial < 1000; ++trial) {
        const size_t n = 1 + rng() % 40, begin = rng() % n, end = begin + rng() % (n - begin + 1);
        std::vector<Spectrum> f_nee(n + 1), f_bounce(n + 1); // + 1: read 16 bytes per entry
        std::vector<float> w(n);
        std::vector<int> slots(n);
        std::vector<uint32_t> pixels(n);
        std::vector<Vec2f> films(n);
        for (size_t i = 0; i <= n; ++i) {
            f_nee[i] = Spectrum(value(), value(), value());
            f_bounce[i] = Spectrum(value(), value(), value());
        }
        for (size_t i = 0; i < n; ++i) {
            w[i] = u(rng) < 0.9f ? u(rng) : value();
            slots[i] = int(rng() % pixels_per_view.size());
            pixels[i] = uint32_t(rng() % pixels_per_view[size_t(slots[i])]);
            films[i] = Vec2f(float(pixels[i]) + u(rng), u(rng));
        }
        MvSplatTerms t{Spectrum(u(rng), 2.f * u(rng), u(rng)), Spectrum(value(), u(rng), u(rng)), 0.5f + u(rng),
                       (rng() % 4) != 0, (rng() % 4) != 0, (rng() % 8) != 0};
        std::vector<SplatFootprint> views;
        for (size_t n : pixels_per_view) views.push_back(SplatFootprint::box(int(n), 1));
        MvPassFilm ref_film(views, false), got_film(views, false);
        SplatCache ref(ref_film), got(got_film, 4); // a small cache: entries are displaced mid-sample
        std::vector<uint64_t> ref_dropped(pixels_per_view.size()), got_dropped(pixels_per_view.size());
        for (size_t i = begin; i < end; ++i) {
            const Spectrum v = mv_entry_value(t, f_nee[i], f_bounce[i], w[i]);
            const bool added = ref.add(slots[i], pixels[i], films[i], 7, v, w[i]);
            ref_dropped[size_t(slots[i])] += !added;
            const bool exact = std::abs(v[0]) < 0x1p21f && std::abs(v[1]) < 0x1p21f && std::abs(v[2]) < 0x1p21f &&
                               std::abs(w[i]) < 0x1p21f;
            ++paths[!added ? 2 : exact ? 0 : 1];
        }
        std::vector<MvEntryRadiance> sum(n);
        mv_sum_entries(t, f_nee.data(), f_bounce.data(), n, sum.data());
        mv_splat_entries(got, sum.data(), w.data(), 1.f, slots.data(), pixels.data(), films.data(), 7, begin, end,
                         got_dropped.data());
        ref.flush(), got.flush();
        for (size_t s = 0; s < pixels_per_view.size(); ++s)
            ASSERT_EQ(got_dropped[s], ref_dropped[s]) << "trial " << trial << ", view " << s;
        for (uint32_t k = 0; k < ref_film.size(); ++k) {
            const SplatEntry g = got_film.take(k), r = ref_film.take(k);
            for (int c = 0; c < 3; ++c) ASSERT_EQ(g.lw[c], r.lw[c]) << "trial " << trial << ", pixel " << k << ", channel " << c;
            ASSERT_EQ(g.w, r.w) << "trial " << trial << ", pixel " << k;
            ASSERT_EQ(g.count, r.count) << "trial " << trial << ", pixel " << k;
        }
    }
    EXPECT_GT(paths[0], 3000);
    EXPECT_GT(paths[1], 1000);
    EXPECT_GT(paths[2], 500);
}

TEST(MvSplat, SplitsAreSummedAndWeighted) {
    // Two splits of one entry: L = L_0 + L_1 (each as mv_entry_value selects), splatted as
    // (L w / 2, w): W times the splits' mean, and W; a split that is not valid adds nothing.
    const Spectrum f_nee[2] = {Spectrum(0.5f, 0.25f, 1.f), Spectrum(0.f)}, f_bounce[2] = {Spectrum(2.f, 1.f, 0.5f), Spectrum(0.f)};
    const MvSplatTerms a{Spectrum(1.f, 2.f, 4.f), Spectrum(0.5f, 0.5f, 1.f), 2.f, true, true, true};
    MvSplatTerms b = a;
    b.nee = false;
    MvSplatTerms invalid = a;
    invalid.valid = false;
    std::vector<MvEntryRadiance> sum(1);
    for (const MvSplatTerms &t : {a, b, invalid}) mv_sum_entries(t, f_nee, f_bounce, 1, sum.data());
    const Spectrum want = mv_entry_value(a, f_nee[0], f_bounce[0], 1.f) + mv_entry_value(b, f_nee[0], f_bounce[0], 1.f);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(sum[0].v[c], want[c]);
    EXPECT_EQ(sum[0].v[3], 0.f);
    const std::vector<SplatFootprint> views = {SplatFootprint::box(1, 1)};
    MvPassFilm film(views, false);
    SplatCache cache(film);
    const float w = 0.75f;
    const int slot = 0;
    const uint32_t pixel = 0;
    const Vec2f at(0.5f, 0.5f);
    uint64_t dropped = 0;
    EXPECT_EQ(mv_splat_entries(cache, sum.data(), &w, 0.5f, &slot, &pixel, &at, 7, 0, 1, &dropped), 0u);
    cache.flush();
    const SplatEntry e = film.take(0);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(e.lw[c], to_fixed(want[c] * (w * 0.5f)));
    EXPECT_EQ(e.w, to_fixed(w));
}
