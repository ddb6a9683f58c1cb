// The polynomial exp, log, erf, erfinv and atan2 of core/poly_math.h against double-precision libm
// over their domains, at the accuracy the header states.
#include "mvpt/core/poly_math.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace mvpt;

TEST(PolyMath, ExpRelativeError) {
    double worst = 0.0;
    for (int i = 0; i <= 400000; ++i) {
        float x = -87.f + 175.f * float(i) / 400000.f;
        double ref = std::exp(double(x));
        worst = std::max(worst, std::abs(double(exp_poly(x)) - ref) / ref);
    }
    EXPECT_LT(worst, 1.5e-7);
    EXPECT_EQ(exp_poly(0.f), 1.f);
    EXPECT_EQ(exp_poly(-100.f), 0.f);
    EXPECT_EQ(exp_poly(-Infinity), 0.f);
}

TEST(PolyMath, LogError) {
    double worst = 0.0;
    for (int i = 0; i <= 400000; ++i) {
        float x = std::exp(-85.f + 170.f * float(i) / 400000.f);
        double ref = std::log(double(x));
        // Relative error, absolute near x = 1 where log(x) vanishes.
        worst = std::max(worst, std::abs(double(log_poly(x)) - ref) / std::max(std::abs(ref), 1.0));
    }
    EXPECT_LT(worst, 1.5e-7);
    EXPECT_EQ(log_poly(1.f), 0.f);
}

TEST(PolyMath, ErfAbsoluteError) {
    double worst = 0.0;
    for (int i = 0; i <= 400000; ++i) {
        float x = -8.f + 16.f * float(i) / 400000.f;
        worst = std::max(worst, std::abs(double(erf_poly(x)) - std::erf(double(x))));
    }
    EXPECT_LT(worst, 2e-7);
    EXPECT_EQ(erf_poly(0.f), 0.f);
    EXPECT_EQ(erf_poly(Infinity), 1.f);
    EXPECT_EQ(erf_poly(-Infinity), -1.f);
}

TEST(PolyMath, ErfinvInvertsErf) {
    // Residual erf(erfinv(x)) - x in double precision, scaled by erf's slope at the result
    // (the error in erfinv itself), relative to max(|erfinv(x)|, 0.1).
    double worst = 0.0;
    for (int i = 1; i < 200000; ++i) {
        float x = -1.f + 2.f * float(i) / 200000.f;
        double y = erfinv_poly(x);
        double slope = 2.0 / std::sqrt(3.14159265358979) * std::exp(-y * y);
        worst = std::max(worst, std::abs(std::erf(y) - double(x)) / slope / std::max(std::abs(y), 0.1));
    }
    EXPECT_LT(worst, 1e-5);
    EXPECT_EQ(erfinv_poly(0.f), 0.f);
}

TEST(PolyMath, Atan2AbsoluteError) {
    // Directions all around the circle, at several radii (the result depends on y/x only),
    // and the axes and zeros with std::atan2's signs.
    double worst = 0.0;
    for (int i = 0; i < 400000; ++i) {
        double a = -3.14159265358979 + 6.28318530717959 * (double(i) + 0.5) / 400000.0;
        for (float radius : {1e-3f, 1.f, 7.5f, 1e4f}) {
            float x = float(radius * std::cos(a)), y = float(radius * std::sin(a));
            worst = std::max(worst, std::abs(double(atan2_poly(y, x)) - std::atan2(double(y), double(x))));
        }
    }
    EXPECT_LT(worst, 3e-7);
    for (float y : {0.f, -0.f, 1.f, -1.f, 3e-30f})
        for (float x : {0.f, -0.f, 1.f, -1.f, 2e-30f})
            EXPECT_NEAR(atan2_poly(y, x), std::atan2(y, x), 3e-7f) << y << ", " << x;
    EXPECT_EQ(std::signbit(atan2_poly(-0.f, 1.f)), true);
    EXPECT_EQ(atan2_poly(0.f, -0.f), Pi);
    EXPECT_EQ(atan2_poly(-0.f, -1.f), -Pi);
}
