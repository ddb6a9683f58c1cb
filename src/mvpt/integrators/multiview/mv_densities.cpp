// The balance-heuristic densities D_k of §5 and the selection of §6 for the candidates of a
// shared vertex (a surface vertex or a medium vertex, docs/multiview-path-tracing.md).
#include "mv_densities.h"

#include "../../render/bsdf.h"

#include <algorithm>

namespace mvpt {

namespace {
/// Material similarity of candidates a and b, memoised in the |V| x |V| matrix `sm`.
float cached_similarity(const MvContext &ctx, MvScratch &sc, const Bsdf &bsdf, const SurfaceInteraction &si, size_t a,
                        size_t b) {
    if (a == b) return 1.f;
    size_t m = sc.cand.size;
    float &v = sc.sm[a * m + b];
    if (v < 0.f) v = sc.sm[b * m + a] = material_similarity(bsdf, si, sc.lobe[a], sc.lobe[b], ctx.cfg.tv, sc.alpha);
    return v;
}

/// Selection probability s_{j->k} of §6 between candidates j and k (the BSDF at y is read only
/// for the material similarity).
float selection(const MvContext &ctx, MvScratch &sc, const Bsdf *bsdf, const SurfaceInteraction *si, size_t j,
                size_t k) {
    if (j == k) return 1.f;
    float s = ctx.cfg.select_jacobian ? jacobian_similarity(sc.cand.g[j], sc.cand.g[k]) : 1.f;
    if (s > 0.f && sc.material) s *= cached_similarity(ctx, sc, *bsdf, *si, j, k);
    return s;
}

} // namespace

void mv_select(const MvContext &ctx, MvScratch &sc, Sampler &sampler, const Bsdf *bsdf, const SurfaceInteraction *si) {
    const MvCandidates &cand = sc.cand;
    // Without a selection term every candidate stays selected (s = 1): no draws.
    if (!sc.material && ctx.cfg.select_jacobian && sampler.kind() == SamplerKind::Independent)
        select_by_jacobian(cand, ctx.select_keys.data(), sampler.sample_hash(), true, sc.s_sel.data(),
                           sc.selected.data()); // the same draws, in one vector loop
    else if (sc.material || ctx.cfg.select_jacobian)
        for (size_t i = 1; i < cand.size; ++i) {
            sc.s_sel[i] = selection(ctx, sc, bsdf, si, 0, i);
            if (sc.s_sel[i] >= 1.f) continue; // selected whatever the draw (u < 1)
            sampler.set_dimension(DimSelectBase + ctx.views[cand.slot[i]].scene_index);
            sc.selected[i] = sampler.next_1d() < sc.s_sel[i];
        }
}

void mv_balance_sums(const MvContext &ctx, MvScratch &sc, const Bsdf *bsdf, const SurfaceInteraction *si,
                     const int *targets, size_t nt) {
    MvCandidates &c = sc.cand;
    const size_t m = c.size;
    //   D_k = sum_j n_j rho_{j->k},  rho_{j->k} = (dt_k/dt_j) (G_j/G_k) s_{j->k},  rho_{k->k} = 1,
    // over the strategies j whose shift to k is valid (visibility included).
    auto &valid_set = sc.valid_set;
    grow_scratch(valid_set, m);
    size_t n_valid = 0;
    for (size_t j = 0; j < m; ++j) { // branch-free compaction
        valid_set[n_valid] = uint32_t(j);
        n_valid += sc.visible[j];
    }
    grow_scratch(sc.d, (m + 7) / 8 * 8);
    const bool uniform_time = !ctx.scene_moves || ctx.all_time_compatible_equal_dt;
    if (!sc.material && uniform_time && ctx.all_time_compatible) {
        // No pairwise terms: the vector loop of balance_sums (j = k gives n_k).
        const size_t nv = n_valid, padded = (nt + 7) / 8 * 8;
        auto &g = sc.g_valid, &nn = sc.n_valid, &gt = sc.g_targets, &dt = sc.d_targets;
        const float *gp = c.g.data(), *np = c.n.data();
        if (nv < m) { // gather the valid strategies
            grow_scratch(g, nv), grow_scratch(nn, nv);
            for (size_t i = 0; i < nv; ++i) {
                g[i] = c.g[valid_set[i]];
                nn[i] = c.n[valid_set[i]];
            }
            gp = g.data(), np = nn.data();
        }
        if (nt == m) { // every candidate is a target (they are 0..m-1): no gather, no scatter
            balance_sums(gp, np, nv, sc.cand.g_padded(padded), padded, ctx.cfg.select_jacobian, sc.d.data());
            return;
        }
        grow_scratch(gt, padded), grow_scratch(dt, padded);
        for (size_t t = 0; t < nt; ++t) gt[t] = c.g[targets[t]];
        std::fill(gt.begin() + nt, gt.begin() + padded, 1.f); // padding: any positive G
        balance_sums(gp, np, nv, gt.data(), padded, ctx.cfg.select_jacobian, dt.data());
        for (size_t t = 0; t < nt; ++t) sc.d[targets[t]] = dt[t];
        return;
    }
    for (size_t t = 0; t < nt; ++t) {
        const int k = targets[t];
        const MvView &vk = ctx.views[c.slot[k]];
        const float inv_gk = 1.f / c.g[k];
        double sum = c.n[k];
        for (size_t v = 0; v < n_valid; ++v) {
            const uint32_t j = valid_set[v];
            if (int(j) == k) continue;
            const MvView &vj = ctx.views[c.slot[j]];
            // Validity of j -> k is that of l -> j and l -> k except for time, which is not transitive.
            if (!ctx.all_time_compatible && !time_compatible(vj, vk, ctx.scene_moves)) continue;
            float ratio = c.g[j] * inv_gk; // |T'_{k->j}| = G_j / G_k
            float s = ctx.cfg.select_jacobian ? std::min(1.f, ratio) : 1.f;
            if (sc.material && s > 0.f) s *= cached_similarity(ctx, sc, *bsdf, *si, j, size_t(k));
            float tau = time_density_ratio(vk, vj, ctx.scene_moves);
            sum += double(c.n[j]) * double(tau * ratio * s);
        }
        sc.d[k] = float(sum);
    }
}

} // namespace mvpt
