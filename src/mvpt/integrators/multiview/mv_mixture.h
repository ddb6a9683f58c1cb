// The bounce of a shared vertex (docs/multiview-path-tracing.md §7): one direction drawn
// from the uniform mixture of the sharing views' BSDF lobes.
#pragma once

#include "../../render/bsdf.h"

#include <cstddef>

namespace mvpt {

struct MixtureSample {
    BsdfSample bs;        ///< the direction and the sampled lobe of view `view`
    Spectrum weight;      ///< f*|cos|/pdf of view `view`'s own lobe (as Bsdf::sample returns it)
    size_t view = 0;      ///< index (into the lobes) of the view whose lobe was sampled
    /// Density of the mixture: (1/|S|) sum_c p_c(wo | wi_c) for a smooth direction; for a delta
    /// lobe the discrete probability P_view / |S| (the direction serves that view only).
    float pdf = 0.f;
    bool delta = false;
};

/// Sum of n per-view values in 8 independent lanes, the lanes then added in a fixed order:
/// no serial dependency chain over the views, and the same bits on every run.
float sum_over_views(const float *v, size_t n);
/// Largest channel of n per-view spectra, 0 for none (no serial dependency chain either).
float max_over_views(const Spectrum *f, size_t n);

/// Mixture density (1/n) sum_c p_c(wo | wi[c]) of the non-delta lobes; divided by n, not by
/// the number of non-zero terms.
float lobe_mixture_pdf(const Bsdf &bsdf, const SurfaceInteraction &si, const Vec3f *wi, size_t n, Vec3f wo);

/// Pick a view with `u_view`, sample its lobe with (u_lobe, u_dir). Zero weight: no direction.
/// With `f` and `pdf_buf` (n entries each), a smooth direction also gets every view's
/// f(wi[c], wo)|cos| and lobe density there, from the same BSDF evaluations as the mixture density.
MixtureSample sample_lobe_mixture(const Bsdf &bsdf, const SurfaceInteraction &si, const Vec3f *wi, size_t n,
                                  float u_view, float u_lobe, Vec2f u_dir, Spectrum *f = nullptr,
                                  float *pdf_buf = nullptr);

} // namespace mvpt
