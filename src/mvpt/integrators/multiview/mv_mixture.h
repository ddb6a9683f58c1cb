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
    /// Density of the mixture: smooth_mixture_pdf for a smooth direction; for a delta lobe the
    /// discrete probability of the view and its lobe (the direction serves that view only), and
    /// `weight` f/(that probability) over |S|.
    float pdf = 0.f;
    bool delta = false;
};

/// Sum of n per-view values in 8 independent lanes, the lanes then added in a fixed order:
/// no serial dependency chain over the views, and the same bits on every run.
float sum_over_views(const float *v, size_t n);
/// Largest channel of n per-view spectra, 0 for none (no serial dependency chain either).
float max_over_views(const Spectrum *f, size_t n);

/// How the bounce of a shared vertex divides its directions between the views' delta lobes and
/// their smooth lobes (§7, "Delta lobes"). A smooth direction serves every sharing view, a delta
/// one only the view it was drawn for; so at a BSDF with both kinds (smooth plastic, a mask) a
/// delta event is drawn with probability q, q / (1 - q) = n^(3/8) P / (1 - P) for n views whose
/// own sampling picks a delta lobe with mean probability P, else a smooth one from the mixture of
/// the views' smooth lobes, each conditioned on its kind. Without `split` (a BSDF of one kind,
/// one view, or one that cannot draw its kinds apart) each view's lobe is chosen as its own
/// sampling chooses it.
struct LobeClasses {
    bool split = false;
    float q = 0.f;                      ///< probability of a delta event
    const float *p_delta = nullptr;     ///< per view, the probability its own sampling draws a delta lobe
    const float *smooth_scale = nullptr; ///< per view, (1 - q) / (n (1 - p_delta)), 0 if p_delta = 1
};

/// The classes of the views wi[0..n) at si (p_delta and smooth_scale: n entries of storage).
LobeClasses lobe_classes(const Bsdf &bsdf, const SurfaceInteraction &si, const Vec3f *wi, size_t n, float *p_delta,
                         float *smooth_scale);

/// Density of the smooth directions of the mixture at a direction where view c's lobe density is
/// pdf[c]: (1/n) sum_c pdf[c], or with split classes (1 - q)/n sum_c pdf[c] / (1 - p_delta[c]).
/// Divided by n, not by the number of non-zero terms.
float smooth_mixture_pdf(const LobeClasses &classes, const float *pdf, size_t n);

/// Mixture density of the smooth directions at wo (as smooth_mixture_pdf, the BSDF evaluated).
float lobe_mixture_pdf(const Bsdf &bsdf, const SurfaceInteraction &si, const Vec3f *wi, size_t n,
                       const LobeClasses &classes, Vec3f wo);

/// Pick a view with `u_view` (with split classes, the kind and then the view), sample its lobe
/// with (u_lobe, u_dir). Zero weight: no direction. With `f` and `pdf_buf` (n entries each), a
/// smooth direction also gets every view's f(wi[c], wo)|cos| and lobe density there, from the
/// same BSDF evaluations as the mixture density.
MixtureSample sample_lobe_mixture(const Bsdf &bsdf, const SurfaceInteraction &si, const Vec3f *wi, size_t n,
                                  const LobeClasses &classes, float u_view, float u_lobe, Vec2f u_dir,
                                  Spectrum *f = nullptr, float *pdf_buf = nullptr);

} // namespace mvpt
