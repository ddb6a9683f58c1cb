// The closed forms that some BSDFs amount to, found from their concrete types: a Lambertian
// reflectance, a rough conductor of constant parameters. Vector code that samples and
// evaluates many vertices at once (the wavefront path tracer's kernels) runs these forms; the
// Bsdf interface itself knows nothing of them.
#pragma once

#include "../../core/math.h"

#include <optional>
#include <utility>

namespace mvpt {

class Bsdf;
class Texture;

/// A Lambertian reflectance (diffuse, or twosided around one).
struct LambertInfo {
    /// The reflectance when it is constant (`texture` is null).
    Color3f reflectance;
    /// Reflects on both sides (twosided: the back side mirrors directions through the surface).
    bool two_sided = false;
    /// A varying reflectance: this texture at the hit (then `reflectance` is unused).
    const Texture *texture = nullptr;
};

/// A rough conductor of constant parameters (roughconductor with constant textures, one alpha,
/// visible-normal sampling; or twosided around one).
struct RoughConductorInfo {
    /// Beckmann, else GGX.
    bool beckmann = true;
    /// The roughness as MicrofacetDistribution holds it (at least 1e-4).
    float alpha = 0.1f;
    Color3f eta, k;
    /// The specular reflectance (1 when absent).
    Color3f specular{1.f};
    /// Reflects on both sides (twosided: the back side mirrors directions through the surface).
    bool two_sided = false;
};

/// What a BSDF amounts to: one of the forms above, or neither (then only its own code runs it).
struct BsdfForm {
    enum Kind : uint8_t { General, Lambert, RoughConductor };
    Kind kind = General;
    LambertInfo lambert;
    RoughConductorInfo conductor;
};

/// The form of `bsdf`: diffuse, roughconductor of constant parameters, or twosided around one
/// of them (the same on both sides).
BsdfForm bsdf_form(const Bsdf &bsdf);

// Each next to its type (the plugins' files):
/// A `diffuse` BSDF's reflectance (nothing for other types).
std::optional<LambertInfo> diffuse_form(const Bsdf &bsdf);
/// A `roughconductor` BSDF's constant parameters (nothing for other types or varying parameters).
std::optional<RoughConductorInfo> rough_conductor_form(const Bsdf &bsdf);
/// A `twosided` BSDF's front and back BRDFs (nothing for other types).
std::optional<std::pair<const Bsdf *, const Bsdf *>> twosided_sides(const Bsdf &bsdf);

} // namespace mvpt
