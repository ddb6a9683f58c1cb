#include "mv_media.h"

#include "../path/volpath.h"

#include "../../render/camera.h"
#include "../../render/shape.h"
#include "../../accel/scene.h"

#include <algorithm>

namespace mvpt {

MvMediaVertex mv_media_first_vertex(const MvContext &ctx, int slot, const Ray &ray, Sampler &sampler,
                                    RayCounters &counters) {
    const MvView &v = ctx.views[slot];
    sampler.set_dimension(DimCameraSegmentBase + v.scene_index);
    RandomStream rs = sampler.next_stream();
    // From the near plane, as the volumetric path tracer's camera rays.
    Ray r{ray.at(ray.tmin), ray.d, 0.f, ray.tmax - ray.tmin, ray.time};
    return {walk_segment(*ctx.scene, r, v.camera->medium.get(), NullRule::PureNull, rs, counters), r};
}

Spectrum mv_in_scattering(const MvContext &ctx, int slot, const Ray &ray, const MvMediaVertex &y, Sampler &sampler,
                          RayCounters &counters) {
    const SegmentWalk &w = y.walk;
    if (w.medium_pieces == 0 && !w.crossed_emitter) return Spectrum(0.f); // nothing on the segment
    // More estimates where the segment is more opaque: the in-scattering, the native view's own,
    // is then more of its variance (docs/performance.md: 1 + 8 (1 - T), measured on two fog scenes).
    const float opacity = 1.f - (w.tr[0] + w.tr[1] + w.tr[2]) * (1.f / 3.f);
    const int estimates = std::clamp(1 + int(InScatterPerOpacity * opacity + 0.5f), 1, MaxInScatterEstimates);
    // One piece in a medium, vacuum and null surfaces elsewhere: the piece's start is reached.
    const bool one_piece = w.medium_pieces == 1 && !w.crossed_emitter;
    const Ray piece{y.near.at(w.piece_t0), y.near.d, 0.f, w.piece_t1 - w.piece_t0, y.near.time};
    Spectrum sum(0.f);
    for (int j = 0; j < estimates; ++j) {
        const uint32_t dims = DimInScatter + uint32_t(j) * DimInScatterStride;
        if (one_piece) {
            bool drawn = false;
            Spectrum L = ctx.volpath->in_scattering(*ctx.scene, piece, *w.piece_medium, sampler, counters, drawn, dims);
            if (drawn) { sum += L; continue; }
        }
        sum += ctx.volpath->li_in(*ctx.scene, ray, ctx.views[slot].camera->medium.get(), sampler, counters,
                                  VolPathPart::ScatteredInMedium, dims);
    }
    return sum * (1.f / float(estimates));
}

void mv_media_visibility(const MvContext &ctx, MvScratch &sc, Point3f p, float time, Spectrum tr_native,
                         bool selected_only, Sampler *sampler, RayCounters &counters, MvViewStats *st_l) {
    const MvCandidates &c = sc.cand;
    const size_t m = c.size;
    sc.tr.resize(std::max<size_t>(m, 1));
    sc.tr[0] = tr_native;
    // Each candidate's segment from k's near plane (vis from p towards its lens point) to just
    // before p, walked as one batch; candidates without a segment see p.
    MvMediaWalks &mw = sc.walks;
    mw.clear();
    for (size_t i = 1; i < m; ++i) {
        sc.tr[i] = Spectrum(1.f);
        sc.visible[i] = 1;
        if (selected_only && !sc.selected[i]) continue;
        const MvView &v = ctx.views[c.slot[i]];
        const Vec3f to_lens = c.lens_point(i) - p;
        const float dist = norm(to_lens), vis = c.vis[i];
        RandomStream rs(0);
        if (sampler) {
            sampler->set_dimension(DimCameraSegmentBase + v.scene_index);
            rs = sampler->next_stream();
        }
        if (!(vis > 0.f && dist > 0.f && std::isfinite(dist))) continue;
        const Vec3f d = to_lens / dist;
        mw.candidate.push_back(uint32_t(i));
        mw.rays.push_back(Ray{p + d * vis, -d, 0.f, vis * (1.f - ShadowEpsilon), time});
        mw.media.push_back(v.camera->medium.get());
        mw.streams.push_back(rs);
    }
    mw.walks.resize(mw.rays.size());
    walk_segments(*ctx.scene, mw.rays.data(), mw.media.data(), mw.rays.size(), NullRule::PureNull, mw.streams.data(),
                  counters, mw.walks.data(), mw.buffers);
    for (size_t j = 0; j < mw.walks.size(); ++j) {
        const size_t i = mw.candidate[j];
        sc.visible[i] = !mw.walks[j].stopped;
        sc.tr[i] = mw.walks[j].tr;
    }
    for (size_t i = 1; i < m; ++i) {
        if (selected_only && !sc.selected[i]) {
            sc.visible[i] = 0;
            if (st_l) ++st_l->rejected[int(ShiftTest::Selection)];
            continue;
        }
        if (!st_l) continue;
        if (!sc.visible[i]) ++st_l->rejected[int(ShiftTest::Visibility)];
        else if (!selected_only && !sc.selected[i]) ++st_l->rejected[int(ShiftTest::Selection)];
    }
}

const Medium *mv_medium_towards(const SurfaceInteraction &si, Vec3f d, const Medium *arrival) {
    return si.shape->is_medium_transition() ? si.shape->target_medium(d, si.n) : arrival;
}

} // namespace mvpt
