// The balance-heuristic densities D_k (§5) and the selection (§6) of the views that can share
// a vertex (docs/multiview-path-tracing.md), for surface and medium vertices alike.
#pragma once

#include "mv_sample.h"

namespace mvpt {

/// The selection draws of §6 for the candidates in sc.cand (sc.s_sel, sc.selected set to 1 by
/// the caller); `bsdf` and `si` (the shared surface vertex) are read for the material
/// similarity only (sc.material).
void mv_select(const MvContext &ctx, MvScratch &sc, Sampler &sampler, const Bsdf *bsdf, const SurfaceInteraction *si);

/// D_k of §5 for the candidates `targets` (indices into sc.cand), into sc.d, summed over the
/// visible candidates (sc.visible); `bsdf` and `si` as for mv_select.
void mv_balance_sums(const MvContext &ctx, MvScratch &sc, const Bsdf *bsdf, const SurfaceInteraction *si,
                     const int *targets, size_t nt);

} // namespace mvpt
