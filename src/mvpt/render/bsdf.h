// BSDF interface. Directions are in the local shading frame (n = +z); `wi`
// points to the viewer / previous vertex, `wo` to the light / next vertex
// (Mitsuba's convention). `eval` includes the cosine foreshortening |cos wo|.
#pragma once

#include <optional>
#include <tuple>

#include "../core/math.h"
#include "../core/properties.h"
#include "interaction.h"

#include <utility>

namespace mvpt {

enum BsdfFlags : uint32_t {
    BsdfNone = 0,
    BsdfNull = 1u << 0,
    BsdfDiffuseReflection = 1u << 1,
    BsdfDiffuseTransmission = 1u << 2,
    BsdfGlossyReflection = 1u << 3,
    BsdfGlossyTransmission = 1u << 4,
    BsdfDeltaReflection = 1u << 5,
    BsdfDeltaTransmission = 1u << 6,

    BsdfReflection = BsdfDiffuseReflection | BsdfGlossyReflection | BsdfDeltaReflection,
    BsdfTransmission = BsdfNull | BsdfDiffuseTransmission | BsdfGlossyTransmission | BsdfDeltaTransmission,
    BsdfDiffuse = BsdfDiffuseReflection | BsdfDiffuseTransmission,
    BsdfGlossy = BsdfGlossyReflection | BsdfGlossyTransmission,
    BsdfSmooth = BsdfDiffuse | BsdfGlossy,
    BsdfDelta = BsdfNull | BsdfDeltaReflection | BsdfDeltaTransmission,
};

/// Radiance: paths from the camera (the default); Importance: from lights.
enum class TransportMode { Radiance, Importance };

struct BsdfContext {
    TransportMode mode = TransportMode::Radiance;
    /// The lobes `sample` may draw (BsdfFlags; Mitsuba's type_mask): BsdfDelta or BsdfSmooth draws
    /// only that kind, its density and weight conditioned on it (the lobe probabilities
    /// renormalised over the kind). Honoured by the BSDFs whose delta_probability has a value;
    /// eval and pdf ignore it.
    uint32_t type_mask = ~0u;
};

struct BsdfSample {
    Vec3f wo;
    /// Solid-angle density of `wo` (for a delta lobe: its discrete probability).
    float pdf = 0.f;
    /// Relative index of refraction along the sampled direction (1 for reflection).
    float eta = 1.f;
    /// The single lobe type (a BsdfFlags bit) that produced `wo`.
    uint32_t sampled_type = BsdfNone;
};

class Bsdf : public Object {
public:
    /// Either direction below the surface (local frame): a one-sided lobe is zero there, and a
    /// single call returns early rather than evaluate it.
    static bool below(Vec3f wi, Vec3f wo) { return wi.z <= 0.f || wo.z <= 0.f; }

    /// Sample `wo` given `wi`; returns the sample and its weight f*|cos wo|/pdf
    /// (zero weight when sampling failed).
    virtual std::pair<BsdfSample, Spectrum> sample(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi,
                                                   float u1, Vec2f u2) const = 0;
    /// f(wi, wo) |cos wo| for the non-delta lobes.
    virtual Spectrum eval(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const = 0;
    /// Solid-angle density with which `sample` produces `wo` (non-delta lobes).
    virtual float pdf(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const = 0;
    /// `eval` and `pdf` at once (BSDFs that share work between them override it).
    virtual std::pair<Spectrum, float> eval_pdf(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi,
                                                Vec3f wo) const {
        return {eval(ctx, si, wi, wo), pdf(ctx, si, wi, wo)};
    }
    /// `eval_pdf` for the incident directions wi[0..n) and one `wo`, into f[c] and pdf[c]
    /// (multi-view path tracing evaluates every sharing view's lobe at one direction).
    virtual void eval_pdf_views(const BsdfContext &ctx, const SurfaceInteraction &si, const Vec3f *wi, size_t n,
                                Vec3f wo, Spectrum *f, float *pdf) const {
        for (size_t c = 0; c < n; ++c) std::tie(f[c], pdf[c]) = eval_pdf(ctx, si, wi[c], wo);
    }

    /// Probability that `sample` draws a delta lobe (null included) for `wi`; a BSDF with both
    /// delta and smooth lobes has one only if its `sample` honours BsdfContext::type_mask.
    virtual std::optional<float> delta_probability(const SurfaceInteraction &, Vec3f) const {
        if (!(m_flags & BsdfDelta)) return 0.f;
        if (is_purely_delta()) return 1.f;
        return std::nullopt;
    }

    /// The fraction of light that passes straight through (the null lobe's weight, wo = -wi;
    /// Mitsuba's eval_null_transmission): what a shadow ray through media keeps here.
    virtual Spectrum null_transmission(const SurfaceInteraction &) const { return Spectrum(0.f); }

    uint32_t flags() const { return m_flags; }
    bool has_smooth() const { return (m_flags & BsdfSmooth) != 0; }
    bool is_purely_delta() const { return m_flags != 0 && (m_flags & BsdfSmooth) == 0; }
    /// Roughness at `si` for path-reuse heuristics: GGX-equivalent alpha, 1 for diffuse.
    virtual float roughness(const SurfaceInteraction &) const { return 1.f; }

protected:
    uint32_t m_flags = BsdfNone;
};

} // namespace mvpt
