// Phase functions of participating media (Mitsuba 3's "phase"). Directions point away from
// the scattering point: `wi` towards the previous vertex, `wo` towards the next, so forward
// scattering is wo = -wi. Both functions here are sampled exactly: the density equals the
// value, and a sample's weight is 1.
#pragma once

#include "../core/math.h"
#include "../core/properties.h"

namespace mvpt {

class PhaseFunction : public Object {
public:
    /// p(wi, wo) per steradian, which is also the density of `sample`.
    virtual float eval(Vec3f wi, Vec3f wo) const = 0;
    /// A direction wo drawn with density eval(wi, wo).
    virtual Vec3f sample(Vec3f wi, Vec2f u) const = 0;
};

/// Henyey-Greenstein [1941] in the cosine between the directions of propagation, -wi and wo:
/// p = (1 - g^2) / (4 pi (1 + g^2 - 2 g cos)^(3/2)); g = 0 is isotropic.
float henyey_greenstein(float cos_propagation, float g);

} // namespace mvpt
