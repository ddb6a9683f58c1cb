// Indices of refraction given by name, as Mitsuba 3 accepts them for
// int_ior / ext_ior (values from Hecht, Optics, 4th ed.: 0-20 C, ~589 nm).
#pragma once

#include "../core/properties.h"

#include <cctype>
#include <string>

namespace mvpt {

/// One named dielectric and its IOR.
struct NamedIor {
    const char *name;
    float value;
};

/// Mitsuba 3's table of named IORs (mitsuba/render/ior.h), lower-case names.
inline constexpr NamedIor kNamedIors[] = {
    {"vacuum", 1.0f},           {"helium", 1.000036f},     {"hydrogen", 1.000132f},
    {"air", 1.000277f},         {"carbon dioxide", 1.00045f},
    {"water", 1.3330f},         {"acetone", 1.36f},        {"ethanol", 1.361f},
    {"carbon tetrachloride", 1.461f}, {"glycerol", 1.4729f}, {"benzene", 1.501f},
    {"silicone oil", 1.52045f}, {"bromine", 1.661f},
    {"water ice", 1.31f},       {"fused quartz", 1.458f},  {"pyrex", 1.470f},
    {"acrylic glass", 1.49f},   {"polypropylene", 1.49f},  {"bk7", 1.5046f},
    {"sodium chloride", 1.544f}, {"amber", 1.55f},         {"pet", 1.5750f},
    {"diamond", 2.419f},
};

/// IOR of a named material (case-insensitive, as Mitsuba); false if unknown.
inline bool lookup_named_ior(std::string name, float &value) {
    for (auto &c : name) c = char(std::tolower(static_cast<unsigned char>(c)));
    for (const auto &e : kNamedIors)
        if (name == e.name) {
            value = e.value;
            return true;
        }
    return false;
}

/// Read an IOR parameter given either as a <float> or as a <string> naming a
/// material; `def` is the material name used when the parameter is absent.
inline float read_ior(const Properties &props, const std::string &param, const std::string &def) {
    std::string name = def;
    if (props.has(param)) {
        if (!props.is_string(param)) {
            float v = props.get_float(param);
            if (!(v > 0.f)) props.fail(param, "'" + param + "' must be a positive index of refraction");
            return v;
        }
        name = props.get_string(param);
    }
    float v = 0.f;
    if (!lookup_named_ior(name, v)) {
        std::string valid;
        for (const auto &e : kNamedIors) valid += (valid.empty() ? "" : ", ") + std::string(e.name);
        props.fail(param, "unknown IOR name \"" + name + "\" for '" + param + "'; valid names: " + valid);
    }
    return v;
}

} // namespace mvpt
