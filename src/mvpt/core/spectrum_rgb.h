// Spectra given as wavelength:value pairs (Mitsuba's `<spectrum>`), and their
// conversion to linear sRGB exactly as Mitsuba 3's RGB variants do it.
#pragma once

#include "math.h"

#include <array>
#include <string>
#include <vector>

namespace mvpt {

/// A `<spectrum>` value: one constant (no wavelengths), or a piecewise-linear curve
/// through (wavelength in nm, value) pairs with strictly increasing wavelengths.
struct SpectrumCurve {
    std::vector<double> wavelengths, values;

    /// A constant spectrum.
    static SpectrumCurve uniform(double value) { return {{}, {value}}; }
    bool is_uniform() const { return wavelengths.empty(); }
    /// Empty when well formed, else what is wrong (size mismatch, < 2 pairs, not increasing, not finite).
    std::string validate() const;
};

/// What a spectrum parameter means; it selects the RGB conversion (Mitsuba's
/// Properties::get_texture / get_unbounded_texture / get_emissive_texture).
enum class SpectrumUse {
    Reflectance, ///< albedo-like: weighted by D65, clamped to [0, 1]
    Unbounded,   ///< e.g. IOR, roughness: weighted by D65, clamped to >= 0
    Emission,    ///< radiance / intensity: not weighted by D65, clamped to >= 0
};

/// The RGB value Mitsuba 3's RGB variants give a spectrum used as `use`: a constant
/// is itself, except for emission, where it is c * xyz_to_srgb(1, 1, 1); a curve is
/// integrated by spectrum_list_to_srgb(bounded = Reflectance, d65 = not Emission).
Color3f spectrum_to_rgb(const SpectrumCurve &s, SpectrumUse use);

/// Mitsuba's `spectrum_list_to_srgb`: the curve (zero outside its wavelength range)
/// times the CIE 1931 matching functions (times normalised D65 when `d65`), summed
/// at 1000 equidistant wavelengths over [360, 830] nm and scaled to luminance units,
/// then XYZ -> linear sRGB, clamped to [0, 1] when `bounded`, else to >= 0.
std::array<double, 3> spectrum_list_to_srgb(const std::vector<double> &wavelengths,
                                            const std::vector<double> &values, bool bounded, bool d65);

/// CIE 1931 x-bar, y-bar, z-bar at `lambda` nm (Mitsuba's 5 nm table, linear interpolation; 0 outside).
std::array<double, 3> cie1931_xyz(double lambda);
/// CIE D65 at `lambda` nm, normalised to unit luminance (Mitsuba's `cie_d65`; 0 outside).
double cie_d65(double lambda);
/// CIE XYZ -> linear sRGB (Rec. 709 primaries, D65 white), Mitsuba's matrix.
std::array<double, 3> xyz_to_srgb(const std::array<double, 3> &xyz);

} // namespace mvpt
