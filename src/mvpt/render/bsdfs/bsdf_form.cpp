#include "bsdf_form.h"

#include <cstring>

namespace mvpt {

namespace {
/// Bitwise-equal values.
template <typename T> bool same_bits(const T &a, const T &b) { return std::memcmp(&a, &b, sizeof(T)) == 0; }

/// The form of a one-sided BSDF.
BsdfForm one_sided_form(const Bsdf &bsdf) {
    BsdfForm form;
    if (std::optional<LambertInfo> lam = diffuse_form(bsdf)) {
        form.kind = BsdfForm::Lambert;
        form.lambert = *lam;
    } else if (std::optional<RoughConductorInfo> cond = rough_conductor_form(bsdf)) {
        form.kind = BsdfForm::RoughConductor;
        form.conductor = *cond;
    }
    return form;
}
} // namespace

BsdfForm bsdf_form(const Bsdf &bsdf) {
    const auto sides = twosided_sides(bsdf);
    if (!sides) return one_sided_form(bsdf);
    // Both sides one form with the same parameters (the same constant or texture): that form on both sides.
    const BsdfForm front = one_sided_form(*sides->first), back = one_sided_form(*sides->second);
    BsdfForm form;
    if (front.kind == BsdfForm::Lambert && back.kind == BsdfForm::Lambert &&
        front.lambert.texture == back.lambert.texture && same_bits(front.lambert.reflectance, back.lambert.reflectance)) {
        form = front;
        form.lambert.two_sided = true;
    }
    const RoughConductorInfo &a = front.conductor, &b = back.conductor;
    if (front.kind == BsdfForm::RoughConductor && back.kind == BsdfForm::RoughConductor && a.beckmann == b.beckmann &&
        same_bits(a.alpha, b.alpha) && same_bits(a.eta, b.eta) && same_bits(a.k, b.k) && same_bits(a.specular, b.specular)) {
        form = front;
        form.conductor.two_sided = true;
    }
    return form;
}

} // namespace mvpt
