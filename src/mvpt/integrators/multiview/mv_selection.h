// Selection of the views that share a native sample (docs/multiview-path-tracing.md §6):
// s = s_J * s_M, Jacobian similarity times material similarity.
#pragma once

#include "../../render/bsdf.h"
#include "mvpath.h"

namespace mvpt {

/// s_J for the shift j -> k: min(1, 1/|T'_{j->k}|) with |T'_{j->k}| = G_k / G_j (§4, §6).
inline float jacobian_similarity(float g_from, float g_to) { return g_to > 0.f ? std::min(1.f, g_from / g_to) : 0.f; }

/// One view's BSDF lobe at the shared vertex: its viewing direction (local frame), the lobe's
/// mirror (peak) direction and the lobe's sampling density there.
struct ViewLobe {
    Vec3f wi;
    Vec3f mirror;
    float peak = 0.f;
};

/// The lobe of `bsdf` at `si` seen from local direction `wi`.
ViewLobe view_lobe(const Bsdf &bsdf, const SurfaceInteraction &si, Vec3f wi);

/// Material similarity s_M = (1 - TV(rho_a, rho_b))^(1/alpha) of two views' lobes at `si`
/// (§6); 1 for BSDFs without glossy lobes, 0 (never NaN) when the estimate underflows.
/// Symmetric in (a, b), and a deterministic function of the lobes, so the selection
/// probability that enters the MIS sums D (§5) is the one used to select.
float material_similarity(const Bsdf &bsdf, const SurfaceInteraction &si, const ViewLobe &a, const ViewLobe &b,
                          MvTotalVariation tv);
/// The same with the roughness alpha at `si` given (it is the same for every pair of views).
float material_similarity(const Bsdf &bsdf, const SurfaceInteraction &si, const ViewLobe &a, const ViewLobe &b,
                          MvTotalVariation tv, float alpha);

/// Total variation distance 1/2 int |rho_a - rho_b| of two lobes, estimated with a fixed
/// quasi-random point set from both sides and averaged (the Monte Carlo switch of §6).
float total_variation_mc(const Bsdf &bsdf, const SurfaceInteraction &si, Vec3f wi_a, Vec3f wi_b);

/// Peak-ratio estimate of the total variation: 1 - min(q_a, q_b), q_c the ratio of the
/// two densities at lobe c's mirror direction (§6).
float total_variation_peak(const Bsdf &bsdf, const SurfaceInteraction &si, const ViewLobe &a, const ViewLobe &b);

} // namespace mvpt
