// Spectrum -> RGB conversion against values read back from Mitsuba 3.9.1 (`scalar_rgb`,
// mi.traverse of loaded scenes), and the checks of malformed spectra.
#include "mvpt/core/spectrum_rgb.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace mvpt;

namespace {

void expect_rgb(Color3f got, Color3f want) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], want[c], 1e-4f * std::max(1.f, std::abs(want[c]))) << "channel " << c;
}

SpectrumCurve curve(std::vector<double> w, std::vector<double> v) { return {std::move(w), std::move(v)}; }

} // namespace

TEST(SpectrumRgb, MatchesMitsubaForEachUse) {
    // Mitsuba cbox light (area `radiance`): emission, no D65, unclamped above.
    expect_rgb(spectrum_to_rgb(curve({400, 500, 600, 700}, {0, 8, 15.6, 18.4}), SpectrumUse::Emission),
               {20.7108f, 10.8546f, 2.77115f});
    // A diffuse `reflectance`: D65-weighted, clamped to [0, 1].
    expect_rgb(spectrum_to_rgb(curve({400, 404, 408, 412, 700}, {0.343, 0.445, 0.551, 0.624, 0.5}), SpectrumUse::Reflectance),
               {0.522126f, 0.567681f, 0.606915f});
    // Conductor `eta` / `k` (unbounded: D65-weighted, blue channel above 1 kept).
    expect_rgb(spectrum_to_rgb(curve({300, 400, 500, 600, 700, 800}, {1.8, 1.65, 0.9, 0.2, 0.16, 0.18}), SpectrumUse::Unbounded),
               {0.0452341f, 0.585709f, 1.33692f});
    expect_rgb(spectrum_to_rgb(curve({300, 400, 500, 600, 700, 800}, {1.92, 1.95, 1.95, 2.97, 3.8, 5.12}), SpectrumUse::Unbounded),
               {3.38869f, 2.34904f, 1.87516f});
    // The same eta as a reflectance clamps at 1.
    expect_rgb(spectrum_to_rgb(curve({300, 400, 500, 600, 700, 800}, {1.8, 1.65, 0.9, 0.2, 0.16, 0.18}), SpectrumUse::Reflectance),
               {0.0452341f, 0.585709f, 1.f});
    // Constants: themselves, except as emission (times xyz_to_srgb(1, 1, 1)).
    expect_rgb(spectrum_to_rgb(SpectrumCurve::uniform(0.3), SpectrumUse::Reflectance), Color3f(0.3f));
    expect_rgb(spectrum_to_rgb(SpectrumCurve::uniform(5), SpectrumUse::Emission), {6.02397f, 4.74146f, 4.54458f});
}

TEST(SpectrumRgb, FlatSpectraAreNearlyWhite) {
    // A flat unit reflectance over all of 360..830 nm is D65's colour: white up to the 5 nm tables.
    Color3f white = spectrum_to_rgb(curve({300, 900}, {1, 1}), SpectrumUse::Reflectance);
    expect_rgb(white, {0.998983f, 0.998872f, 0.998802f});
    // The luminance of a flat emission spectrum is its value (Mitsuba's Y normalisation).
    Color3f e = spectrum_to_rgb(curve({300, 900}, {2, 2}), SpectrumUse::Emission);
    EXPECT_NEAR(e.luminance(), 2.f, 2e-3f);
    // Zero outside the given range: a curve covering only 800..830 nm is almost black.
    EXPECT_LT(spectrum_to_rgb(curve({800, 830}, {1, 1}), SpectrumUse::Emission).max_value(), 1e-3f);
}

TEST(SpectrumRgb, MatchingFunctionsAndD65) {
    auto xyz = cie1931_xyz(600);
    EXPECT_NEAR(xyz[0], 1.0622, 1e-6);
    EXPECT_NEAR(xyz[1], 0.631, 1e-6);
    EXPECT_EQ(cie1931_xyz(359.9)[1], 0.0);
    EXPECT_NEAR(cie_d65(560) / 0.010101273599490354, 100.0, 1e-4);
}

TEST(SpectrumRgb, ValidateNamesTheProblem) {
    EXPECT_EQ(curve({400, 500}, {0.1, 0.2}).validate(), "");
    EXPECT_NE(curve({400}, {0.1}).validate().find("at least two"), std::string::npos);
    EXPECT_NE(curve({400, 400}, {0.1, 0.2}).validate().find("increase strictly (pair 2)"), std::string::npos);
    EXPECT_NE(curve({500, 400}, {0.1, 0.2}).validate().find("increase strictly"), std::string::npos);
    EXPECT_NE(curve({400, 500}, {0.1, NAN}).validate().find("not finite"), std::string::npos);
    EXPECT_NE(curve({400, 500}, {0.1}).validate().find("differ in number"), std::string::npos);
    EXPECT_NE(SpectrumCurve::uniform(INFINITY).validate().find("not finite"), std::string::npos);
}
