#include "mvpt/core/sampler.h"

#include <gtest/gtest.h>

#include <set>

using namespace mvpt;

TEST(Sampler, DependsOnlyOnSampleCoordinates) {
    for (SamplerKind kind : {SamplerKind::Independent, SamplerKind::Sobol}) {
        Sampler a(kind, 7), b(kind, 7);
        a.start(3, 10, 20, 5);
        float x1 = a.next_1d();
        Vec2f x2 = a.next_2d();
        b.start(9, 1, 1, 1); // unrelated use first
        b.next_2d();
        b.start(3, 10, 20, 5);
        EXPECT_EQ(x1, b.next_1d());
        Vec2f y2 = b.next_2d();
        EXPECT_EQ(x2.x, y2.x);
        EXPECT_EQ(x2.y, y2.y);
    }
}

TEST(Sampler, SobolPrefixIsStratified) {
    // Every power-of-two prefix of an Owen-scrambled (0,2)-sequence puts one
    // point in each of the 2^m elementary intervals of any shape.
    Sampler s(SamplerKind::Sobol, 1);
    const int n = 64;
    for (int shape = 0; shape <= 6; ++shape) {
        int nx = 1 << shape, ny = n / nx;
        std::set<int> cells;
        for (int i = 0; i < n; ++i) {
            s.start(0, 4, 2, uint32_t(i), 5);
            Vec2f p = s.next_2d();
            ASSERT_GE(p.x, 0.f);
            ASSERT_LT(p.x, 1.f);
            cells.insert(int(p.x * nx) * ny + int(p.y * ny));
        }
        EXPECT_EQ(int(cells.size()), n) << "elementary intervals " << nx << "x" << ny;
    }
}
