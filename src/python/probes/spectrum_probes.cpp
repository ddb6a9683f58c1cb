// `mvpt._core.spectrum_to_rgb`: the loader's spectrum -> RGB conversion, for tests
// against Mitsuba's RGB variants.
#include "mvpt/core/spectrum_rgb.h"

#include <nanobind/nanobind.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include <stdexcept>
#include <tuple>

namespace nb = nanobind;
using namespace nb::literals;
using namespace mvpt;

void bind_spectrum(nb::module_ &m) {
    m.def("spectrum_to_rgb", [](std::vector<double> wavelengths, std::vector<double> values, const std::string &use) {
        SpectrumUse u;
        if (use == "reflectance") u = SpectrumUse::Reflectance;
        else if (use == "unbounded") u = SpectrumUse::Unbounded;
        else if (use == "emission") u = SpectrumUse::Emission;
        else throw std::invalid_argument("use must be 'reflectance', 'unbounded' or 'emission', got '" + use + "'");
        SpectrumCurve s{std::move(wavelengths), std::move(values)};
        std::string problem = s.validate();
        if (!problem.empty()) throw std::invalid_argument("spectrum: " + problem);
        Color3f c = spectrum_to_rgb(s, u);
        return std::make_tuple(c.r, c.g, c.b);
    }, "wavelengths"_a, "values"_a, "use"_a = "reflectance",
       "RGB of a spectrum (wavelengths empty: one constant value) as Mitsuba 3's RGB variants convert it.");
}
