#include "spectrum_rgb.h"

#include "cie_tables.h"

#include <algorithm>
#include <cmath>

namespace mvpt {

namespace {

/// Linear interpolation in a 5 nm table over [360, 830] nm (Mitsuba's lookup: t
/// scaled by 94/470, lower node clamped to [0, 93]); 0 outside the range.
double lookup(const float *table, double lambda) {
    if (!(lambda >= cie::kMinWavelength && lambda <= cie::kMaxWavelength)) return 0.0;
    double t = (lambda - cie::kMinWavelength) * ((cie::kSamples - 1) / (cie::kMaxWavelength - cie::kMinWavelength));
    int i0 = std::clamp(int(t), 0, cie::kSamples - 2);
    double w1 = t - i0, w0 = 1.0 - w1;
    return w0 * double(table[i0]) + w1 * double(table[i0 + 1]);
}

} // namespace

std::string SpectrumCurve::validate() const {
    if (is_uniform()) {
        if (values.size() != 1) return "a constant spectrum needs exactly one value";
        if (!std::isfinite(values[0])) return "the value is not finite";
        return {};
    }
    if (wavelengths.size() != values.size()) return "wavelengths and values differ in number";
    if (wavelengths.size() < 2) return "needs at least two wavelength:value pairs";
    for (size_t i = 0; i < wavelengths.size(); ++i) {
        if (!std::isfinite(wavelengths[i]) || !std::isfinite(values[i]))
            return "pair " + std::to_string(i + 1) + " is not finite";
        if (i > 0 && !(wavelengths[i] > wavelengths[i - 1]))
            return "wavelengths must increase strictly (pair " + std::to_string(i + 1) + ")";
    }
    return {};
}

std::array<double, 3> cie1931_xyz(double lambda) {
    return {lookup(cie::kX, lambda), lookup(cie::kY, lambda), lookup(cie::kZ, lambda)};
}

double cie_d65(double lambda) { return lookup(cie::kD65, lambda) * cie::kD65Normalization; }

std::array<double, 3> xyz_to_srgb(const std::array<double, 3> &xyz) {
    // Mitsuba's single-precision coefficients (core/spectrum.h, xyz_to_srgb).
    static const float M[3][3] = {{3.240479f, -1.537150f, -0.498535f},
                                  {-0.969256f, 1.875991f, 0.041556f},
                                  {0.055648f, -0.204043f, 1.057311f}};
    std::array<double, 3> rgb{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) rgb[i] += double(M[i][j]) * xyz[j];
    return rgb;
}

std::array<double, 3> spectrum_list_to_srgb(const std::vector<double> &wavelengths,
                                            const std::vector<double> &values, bool bounded, bool d65) {
    // Riemann sum over 1000 wavelengths spanning [360, 830] nm (Mitsuba, core/spectrum.cpp).
    constexpr int steps = 1000;
    const double lo = cie::kMinWavelength, hi = cie::kMaxWavelength;
    std::array<double, 3> xyz{};
    for (int i = 0; i < steps; ++i) {
        double w = lo + (i / double(steps - 1)) * (hi - lo);
        if (w < wavelengths.front() || w > wavelengths.back()) continue;
        // Interval [w0, w1] containing w; the last one also takes w == back().
        size_t k = size_t(std::upper_bound(wavelengths.begin(), wavelengths.end(), w) - wavelengths.begin());
        k = std::clamp<size_t>(k, 1, wavelengths.size() - 1) - 1;
        double w0 = wavelengths[k], w1 = wavelengths[k + 1], v0 = values[k], v1 = values[k + 1];
        double v = ((w - w1) * v0 + (w0 - w) * v1) / (w0 - w1);
        double weight = v * cie::kYNormalization * (d65 ? cie_d65(w) : 1.0);
        std::array<double, 3> cmf = cie1931_xyz(w);
        for (int c = 0; c < 3; ++c) xyz[c] += cmf[c] * weight;
    }
    for (double &c : xyz) c *= (hi - lo) / steps;
    std::array<double, 3> rgb = xyz_to_srgb(xyz);
    for (double &c : rgb) c = bounded ? std::clamp(c, 0.0, 1.0) : std::max(c, 0.0);
    return rgb;
}

Color3f spectrum_to_rgb(const SpectrumCurve &s, SpectrumUse use) {
    if (s.is_uniform()) {
        if (use != SpectrumUse::Emission) return Color3f(float(s.values[0]));
        // A flat emission spectrum is not white in sRGB (whose white is D65): Mitsuba
        // scales xyz_to_srgb(1, 1, 1) so that RGB renders match spectral ones.
        std::array<double, 3> rgb = xyz_to_srgb({1.0, 1.0, 1.0});
        return {float(s.values[0] * rgb[0]), float(s.values[0] * rgb[1]), float(s.values[0] * rgb[2])};
    }
    std::array<double, 3> rgb = spectrum_list_to_srgb(s.wavelengths, s.values, use == SpectrumUse::Reflectance,
                                                      use != SpectrumUse::Emission);
    return {float(rgb[0]), float(rgb[1]), float(rgb[2])};
}

} // namespace mvpt
