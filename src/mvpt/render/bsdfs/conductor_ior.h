// Complex IOR of the conductor BSDFs: `material` preset or explicit `eta`/`k`
// (Mitsuba 3's rules; default material "none": eta = 0, k = 1, a perfect mirror).
#pragma once

#include "../../core/properties.h"
#include "../texture.h"
#include "conductor_presets.h"

#include <memory>

namespace mvpt {

/// Real and imaginary IOR textures of a conductor.
struct ConductorIor {
    std::shared_ptr<Texture> eta, k;
};

/// Read `material` or `eta`/`k`; giving both a material and eta is an error.
inline ConductorIor read_conductor_ior(const Properties &props) {
    ConductorIor r;
    std::string material = props.get_string("material", "none");
    if (props.has_texture("eta") || material == "none") {
        if (material != "none") props.fail("material", "specify either (eta, k) or material, not both");
        r.eta = get_texture(props, "eta", 0.f, SpectrumUse::Unbounded);
        r.k = get_texture(props, "k", 1.f, SpectrumUse::Unbounded);
        return r;
    }
    const ConductorPreset *p = find_conductor_preset(material);
    if (!p) {
        std::string valid = "none";
        for (const auto &e : kConductorPresets) valid += std::string(", ") + e.name;
        props.fail("material", "unknown conductor material \"" + material + "\"; valid presets: " + valid);
    }
    r.eta = std::make_shared<ConstantTexture>(p->eta);
    r.k = std::make_shared<ConstantTexture>(p->k);
    return r;
}

} // namespace mvpt
