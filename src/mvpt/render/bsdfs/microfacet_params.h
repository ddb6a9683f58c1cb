// Shared parameter reading for the microfacet BSDFs (distribution, alpha or
// alpha_u/alpha_v as textures, sample_visible), with Mitsuba 3's defaults and
// error cases.
#pragma once

#include "../../core/properties.h"
#include "../interaction.h"
#include "../microfacet.h"
#include "../texture.h"

#include <memory>

namespace mvpt {

/// Roughness description of a microfacet BSDF; `at(si)` builds the distribution at a hit.
struct MicrofacetParams {
    MicrofacetType type = MicrofacetType::Beckmann;
    std::shared_ptr<Texture> alpha_u, alpha_v;
    bool sample_visible = true;

    /// Anisotropic when alpha_u and alpha_v are distinct textures (Mitsuba's criterion).
    bool anisotropic() const { return alpha_u != alpha_v; }
    MicrofacetDistribution at(const SurfaceInteraction &si) const {
        return MicrofacetDistribution(type, alpha_u->eval_1(si), alpha_v->eval_1(si), sample_visible);
    }
    /// Mean of the two roughnesses at `si` (the value reported by Bsdf::roughness).
    float mean_alpha(const SurfaceInteraction &si) const {
        return 0.5f * (alpha_u->eval_1(si) + alpha_v->eval_1(si));
    }
};

/// Read `distribution` (default beckmann), `alpha` (default 0.1) or both
/// `alpha_u` and `alpha_v`, and `sample_visible` (default true).
inline MicrofacetParams read_microfacet_params(const Properties &props) {
    MicrofacetParams p;
    if (props.has("distribution")) {
        std::string d = props.get_string("distribution");
        if (!parse_microfacet_type(d, p.type))
            props.fail("distribution", "invalid distribution \"" + d + "\", must be \"beckmann\" or \"ggx\"");
    }
    p.sample_visible = props.get_bool("sample_visible", true);
    bool has_u = props.has_texture("alpha_u"), has_v = props.has_texture("alpha_v");
    if (has_u || has_v) {
        if (!has_u || !has_v)
            props.fail(has_u ? "alpha_u" : "alpha_v", "both 'alpha_u' and 'alpha_v' must be specified");
        if (props.has_texture("alpha"))
            props.fail("alpha", "specify either 'alpha' or 'alpha_u'/'alpha_v', not both");
        p.alpha_u = get_texture(props, "alpha_u", 0.1f, SpectrumUse::Unbounded);
        p.alpha_v = get_texture(props, "alpha_v", 0.1f, SpectrumUse::Unbounded);
    } else {
        p.alpha_u = p.alpha_v = get_texture(props, "alpha", 0.1f, SpectrumUse::Unbounded);
    }
    return p;
}

} // namespace mvpt
