#include "mvpt/core/bilinear_distribution.h"
#include "mvpt/core/sampler.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace mvpt;

namespace {
BilinearDistribution2D make(int w, int h, std::vector<float> *values = nullptr) {
    std::vector<float> v(size_t(w) * h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) v[size_t(y) * w + x] = float((x * 7 + y * 3) % 5) + (x == 2 && y == 1 ? 20.f : 0.f);
    v[0] = 0.f; // a zero corner: linear ramps down to zero must still sample correctly
    if (values) *values = v;
    return BilinearDistribution2D(v, w, h);
}
} // namespace

TEST(BilinearDistribution2D, DensityIntegratesToOne) {
    auto d = make(6, 4);
    const int n = 600;
    double sum = 0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) sum += d.pdf({(i + 0.5f) / n, (j + 0.5f) / n});
    EXPECT_NEAR(sum / (double(n) * n), 1.0, 1e-4);
}

TEST(BilinearDistribution2D, SampleReturnsItsDensity) {
    auto d = make(6, 4);
    Sampler s(SamplerKind::Independent, 3);
    for (uint32_t i = 0; i < 5000; ++i) {
        s.start(0, 0, 0, i);
        float pdf;
        Vec2f p = d.sample(s.next_2d(), &pdf);
        ASSERT_GE(p.x, 0.f); ASSERT_LT(p.x, 1.f);
        ASSERT_GE(p.y, 0.f); ASSERT_LT(p.y, 1.f);
        EXPECT_NEAR(pdf, d.pdf(p), 1e-4f * std::max(1.f, pdf));
    }
}

TEST(BilinearDistribution2D, HistogramFollowsDensity) {
    // 4x4 sub-cells per patch: counts against the integrated density (5 sigma each).
    const int w = 6, h = 4, sub = 4, nx = (w - 1) * sub, ny = (h - 1) * sub;
    auto d = make(w, h);
    std::vector<double> counts(size_t(nx) * ny, 0.0);
    const uint32_t n = 400000;
    Sampler s(SamplerKind::Independent, 9);
    for (uint32_t i = 0; i < n; ++i) {
        s.start(0, 0, 0, i);
        float pdf;
        Vec2f p = d.sample(s.next_2d(), &pdf);
        counts[size_t(std::min(int(p.y * ny), ny - 1)) * nx + std::min(int(p.x * nx), nx - 1)] += 1;
    }
    for (int cy = 0; cy < ny; ++cy)
        for (int cx = 0; cx < nx; ++cx) {
            // The density is bilinear inside a cell: the midpoint rule is exact.
            double expected = d.pdf({(cx + 0.5f) / nx, (cy + 0.5f) / ny}) / (double(nx) * ny) * n;
            EXPECT_NEAR(counts[size_t(cy) * nx + cx], expected, 5 * std::sqrt(expected) + 1) << cx << "," << cy;
        }
}

TEST(BilinearDistribution2D, SampleLinearInvertsTheCdf) {
    for (float a : {0.f, 0.3f, 1.f, 4.f})
        for (float b : {0.f, 0.5f, 1.f, 7.f}) {
            if (a + b == 0.f) continue;
            for (float u : {0.f, 0.1f, 0.5f, 0.9f}) {
                float t = sample_linear(u, a, b);
                float cdf = (a * t + 0.5f * (b - a) * t * t) / (0.5f * (a + b));
                EXPECT_NEAR(cdf, u, 1e-5f) << a << " " << b << " " << u;
            }
        }
}

TEST(BilinearDistribution2D, NeverSamplesZeroPatches) {
    // A zero row of patches and a zero column of patches (their vertices all zero) between
    // positive ones: the alias tables must never pick them.
    const int w = 7, h = 6;
    std::vector<float> v(size_t(w) * h, 1.f);
    for (int x = 0; x < w; ++x) v[size_t(2) * w + x] = v[size_t(3) * w + x] = 0.f; // patch row 2
    for (int y = 0; y < h; ++y) v[size_t(y) * w + 4] = v[size_t(y) * w + 5] = 0.f;  // patch column 4
    BilinearDistribution2D d(v, w, h);
    Sampler s(SamplerKind::Independent, 4);
    for (uint32_t i = 0; i < 100000; ++i) {
        s.start(0, 0, 0, i);
        float pdf;
        Vec2f p = d.sample(s.next_2d(), &pdf);
        ASSERT_GT(pdf, 0.f) << p.x << ", " << p.y;
        ASSERT_NE(int(p.y * (h - 1)), 2);
        ASSERT_NE(int(p.x * (w - 1)), 4);
    }
    // The batch gives the same points.
    Vec2f u[3] = {{0.f, 0.f}, {0.5f, 0.41f}, {OneMinusEpsilon, OneMinusEpsilon}}, p[3];
    float pdf[3];
    d.sample_batch(3, u, p, pdf, [](size_t, int, int) {});
    for (int i = 0; i < 3; ++i) {
        float ref_pdf;
        Vec2f ref = d.sample(u[i], &ref_pdf);
        EXPECT_EQ(p[i].x, ref.x);
        EXPECT_EQ(p[i].y, ref.y);
        EXPECT_EQ(pdf[i], ref_pdf);
    }
}

TEST(BilinearDistribution2D, BlackMapSamplesDensityZero) {
    BilinearDistribution2D d(std::vector<float>(12, 0.f), 4, 3);
    EXPECT_TRUE(d.empty());
    float pdf = 1.f;
    Vec2f p = d.sample({0.3f, 0.7f}, &pdf);
    EXPECT_EQ(pdf, 0.f);
    EXPECT_TRUE(p.x >= 0.f && p.x < 1.f && p.y >= 0.f && p.y < 1.f);
}
