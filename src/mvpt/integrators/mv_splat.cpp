// The end of a tile's native samples (§7): their suffixes traced as one wavefront, their
// shared NEE's shadow rays as packets, and each sharing view's contribution W·L splatted.
#include "mv_sample.h"

#include "../core/multi_isa.h"
#include "../scene/scene.h"

#include <algorithm>

namespace mvpt {

namespace {

/// What one sample's entries have in common (MvPendingSamples::Sample, with its suffix known).
struct SampleTerms {
    float nee_weight[3], b_scale, suffix[3];
    bool nee, bounce, valid;
};

/// W·L of n entries (§7), per channel:
///   L = [nee] f_nee * nee_weight + [bounce] (f_bounce * b_scale) * suffix,  W·L = [valid] L * W,
/// the sums in the order of the scalar definition, so the bits do not depend on the CPU; and
/// whether W·L and W fit the splat buffers.
MVPT_MULTI_ISA void contribution_kernel(const Spectrum *__restrict f_nee, const Spectrum *__restrict f_bounce,
                                        const float *__restrict w, size_t n, const SampleTerms &t,
                                        float *__restrict o0, float *__restrict o1, float *__restrict o2,
                                        uint32_t *__restrict ok) {
    const bool nee = t.nee, bounce = t.bounce, valid = t.valid;
    const float nw0 = t.nee_weight[0], nw1 = t.nee_weight[1], nw2 = t.nee_weight[2], bs = t.b_scale;
    const float s0 = t.suffix[0], s1 = t.suffix[1], s2 = t.suffix[2];
    for (size_t i = 0; i < n; ++i) {
        const Spectrum fn = f_nee[i], fb = f_bounce[i];
        const float l0 = select(nee, fn.r * nw0, 0.f) + select(bounce, fb.r * bs * s0, 0.f);
        const float l1 = select(nee, fn.g * nw1, 0.f) + select(bounce, fb.g * bs * s1, 0.f);
        const float l2 = select(nee, fn.b * nw2, 0.f) + select(bounce, fb.b * bs * s2, 0.f);
        const float v0 = select(valid, l0 * w[i], 0.f), v1 = select(valid, l1 * w[i], 0.f), v2 = select(valid, l2 * w[i], 0.f);
        o0[i] = v0, o1[i] = v1, o2[i] = v2;
        ok[i] = uint32_t(SplatBuffer::fits(v0)) & uint32_t(SplatBuffer::fits(v1)) & uint32_t(SplatBuffer::fits(v2)) &
                uint32_t(SplatBuffer::fits(w[i]));
    }
}

} // namespace

void mv_finish_samples(const MvContext &ctx, int slot, MvPendingSamples &pending, MvSplatSink &sink,
                       RayCounters &counters, MvViewStats *stats) {
    const size_t n_suffix = pending.rays.size();
    pending.radiance.resize(n_suffix);
    pending.valid.resize(n_suffix);
    const uint64_t rays_before = counters.rays + counters.shadow_rays;
    if (n_suffix > 0)
        ctx.path->trace_batch(*ctx.scene, pending.rays.data(), pending.states.data(), pending.samplers.data(),
                              pending.radiance.data(), pending.valid.data(), n_suffix, counters);
    stats[slot].rays += counters.rays + counters.shadow_rays - rays_before;
    // The shared NEE's shadow rays as packets (counted when queued).
    pending.shadow_blocked.resize(pending.shadow_rays.size());
    if (!pending.shadow_rays.empty())
        ctx.scene->occluded(pending.shadow_rays.data(), pending.shadow_rays.size(), pending.shadow_blocked.data());

    uint32_t most = 0;
    for (const MvPendingSamples::Sample &rec : pending.samples) most = std::max(most, rec.count);
    for (int c = 0; c < 3; ++c) pending.lw[c].resize(most);
    pending.ok.resize(most);
    float *const lw[3] = {pending.lw[0].data(), pending.lw[1].data(), pending.lw[2].data()};
    SplatBuffer &buffer = sink.buffer;
    for (const MvPendingSamples::Sample &rec : pending.samples) {
        const Spectrum suffix = rec.suffix >= 0 ? pending.radiance[rec.suffix] : Spectrum(0.f);
        const bool bounce = !suffix.is_black();
        SampleTerms t;
        for (int c = 0; c < 3; ++c) t.nee_weight[c] = rec.nee_weight[c], t.suffix[c] = suffix[c];
        t.b_scale = rec.b_scale;
        t.nee = rec.nee && rec.shadow >= 0 && !pending.shadow_blocked[rec.shadow];
        t.bounce = bounce && rec.delta_view < 0;
        t.valid = rec.suffix >= 0 ? pending.valid[rec.suffix] != 0 : rec.valid;
        const uint32_t first = rec.first, n = rec.count;
        const Spectrum *f_nee = pending.f_nee.data() + first, *f_bounce = pending.f_bounce.data() + first;
        const float *w = pending.w.data() + first;
        contribution_kernel(f_nee, f_bounce, w, n, t, lw[0], lw[1], lw[2], pending.ok.data());
        if (bounce && rec.delta_view >= 0) { // a delta lobe's direction serves its view only
            const uint32_t i = uint32_t(rec.delta_view);
            Spectrum L = t.nee ? f_nee[i] * rec.nee_weight : Spectrum(0.f);
            L += rec.delta_bounce * suffix;
            const Spectrum v = t.valid ? L * w[i] : Spectrum(0.f);
            for (int c = 0; c < 3; ++c) lw[c][i] = v[c];
            pending.ok[i] = SplatBuffer::fits(v) & SplatBuffer::fits(w[i]);
        }
        const int *slots = pending.slot.data() + first;
        const uint32_t *pixels = pending.pixel.data() + first;
        // The native view's entry (i = 0) also carries E.
        pending.ok[0] &= uint32_t(SplatBuffer::fits(rec.e));
        for (uint32_t i = 0; i < n; ++i) {
            if (!pending.ok[i]) {
                ++sink.dropped[slots[i]];
                continue;
            }
            buffer.add_fitting(slots[i], pixels[i], lw[0][i], lw[1][i], lw[2][i], w[i]);
        }
        if (pending.ok[0]) buffer.add_native(slots[0], pixels[0], rec.e);
    }
    pending.clear();
}

} // namespace mvpt
