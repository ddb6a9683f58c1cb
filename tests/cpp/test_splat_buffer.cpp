// The fixed-point splat buffers of multi-view path tracing (mv_film.h): exact integer sums,
// and contributions that are not finite or too large rejected whole, whichever channel
// holds the bad value.
#include "mvpt/mv_film.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using namespace mvpt;

namespace {
/// Channel c of pixel p of view 0 (0 while nothing was splatted: the buffer is allocated on use).
int64_t value_at(SplatBuffer &b, size_t p, int c) { return b.view(0).empty() ? 0 : b.view(0).channel(p, c); }
} // namespace

TEST(SplatBuffer, SumsAreExactAndOrderFree) {
    SplatBuffer a({4}), b({4});
    const float v[3] = {0.1f, 1e-7f, 3.5f};
    for (int i = 0; i < 3; ++i) a.add(0, 2, Spectrum(v[i], 2 * v[i], 0.f), v[i]);
    for (int i = 2; i >= 0; --i) b.add(0, 2, Spectrum(v[i], 2 * v[i], 0.f), v[i]);
    for (int c = 0; c < SplatChannels; ++c) EXPECT_EQ(a.view(0).channel(2, c), b.view(0).channel(2, c)) << "channel " << c;
    EXPECT_EQ(a.view(0).channel(2, 7), 3);
    EXPECT_EQ(a.view(0).channel(2, 6), to_fixed(0.1f) + to_fixed(1e-7f) + to_fixed(3.5f));
    EXPECT_EQ(a.view(0).channel(1, 0), 0); // other pixels untouched
}

TEST(SplatBuffer, RejectsWholeContributionsThatDoNotFit) {
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = INFINITY, big = float(SplatMax);
    for (int channel = 0; channel < 4; ++channel)
        for (float bad : {nan, inf, -inf, big, -big}) {
            SplatBuffer buf({1});
            float x[4] = {1.f, 1.f, 1.f, 1.f};
            x[channel] = bad;
            EXPECT_FALSE(buf.add(0, 0, Spectrum(x[0], x[1], x[2]), x[3])) << "channel " << channel << " value " << bad;
            for (int c = 0; c < SplatChannels; ++c) EXPECT_EQ(value_at(buf, 0, c), 0) << "channel " << c;
            // The native view's radiance E is checked too, before anything is added.
            Spectrum e(1.f);
            if (channel < 3) e[channel] = bad;
            else continue;
            EXPECT_FALSE(buf.add(0, 0, Spectrum(1.f), 1.f, e));
            for (int c = 0; c < SplatChannels; ++c) EXPECT_EQ(value_at(buf, 0, c), 0) << "E, channel " << c;
        }
    SplatBuffer ok({1});
    EXPECT_TRUE(ok.add(0, 0, Spectrum(std::nextafter(big, 0.f)), 1.f, Spectrum(-1.f)));
    EXPECT_EQ(ok.view(0).channel(0, 3), to_fixed(-1.f));
}
