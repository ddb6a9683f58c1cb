// The end of a batch of a tile's native samples (§7): their suffixes traced as one wavefront,
// their shared NEE's shadow rays as packets, and each sharing view's contribution W·L splatted.
#include "mv_splat.h"
#include "mv_split_choice.h"
#include "../path/path.h"
#include "../path/volpath.h"

#include "../../core/simd.h"
#include "../../accel/scene.h"

#include <algorithm>

namespace mvpt {

void MvPendingSamples::clear() {
    samples.clear();
    entries = 0;
    rays.clear(), states.clear(), samplers.clear(), media.clear(), dims.clear();
    shadow_rays.clear();
}

size_t MvPendingSamples::add_entries(size_t n) {
    const size_t first = entries;
    entries += n;
    if (entries > slot.size()) { // grow geometrically: no per-sample resizing (and zero fills)
        const size_t size = std::max(entries, 2 * slot.size());
        slot.resize(size), pixel.resize(size), film.resize(size), w.resize(size);
        f_nee.resize(size + 1), f_bounce.resize(size + 1); // + 1: mv_splat.cpp reads 16 bytes per entry
    }
    return first;
}

Spectrum mv_entry_value(const MvSplatTerms &t, const Spectrum &f_nee, const Spectrum &f_bounce, float w) {
    Spectrum L = t.nee ? f_nee * t.nee_weight : Spectrum(0.f);
    if (t.bounce) L += f_bounce * t.b_scale * t.suffix;
    return t.valid ? L * w : Spectrum(0.f);
}

// Per entry, L (RGB) in the lanes of one vector, masked as mv_entry_value selects.
MVPT_MULTI_ISA void mv_sum_entries(const MvSplatTerms &t, const Spectrum *__restrict f_nee,
                                   const Spectrum *__restrict f_bounce, size_t n, MvEntryRadiance *__restrict sum) {
    using namespace simd;
    static_assert(sizeof(Spectrum) == 12, "entries are read as 16 bytes from each Spectrum");
    if (!t.valid) return;
    const i32x4 rgb = {-1, -1, -1, 0}, none = {};
    const i32x4 nee_mask = t.nee ? rgb : none, bounce_mask = t.bounce ? rgb : none;
    const f32x4 nw = {t.nee_weight[0], t.nee_weight[1], t.nee_weight[2], 0.f};
    const f32x4 sfx = {t.suffix[0], t.suffix[1], t.suffix[2], 0.f};
    auto masked = [](f32x4 v, i32x4 mask) { return bit_cast<f32x4>(bit_cast<i32x4>(v) & mask); };
    for (size_t i = 0; i < n; ++i) {
        const f32x4 L = masked(load<f32x4>(&f_nee[i].r) * nw, nee_mask) +
                        masked(load<f32x4>(&f_bounce[i].r) * t.b_scale * sfx, bounce_mask);
        store(sum[i].v, load<f32x4>(sum[i].v) + L);
    }
}

// Per entry, the four values W*L (RGB) and W in the lanes of one vector, added in fixed point
// by add_fixed (one vector where they are below 2^21).
MVPT_MULTI_ISA size_t mv_splat_entries(SplatCache &cache, const MvEntryRadiance *__restrict sum,
                                       const float *__restrict w, float l_scale, const int *__restrict slots,
                                       const uint32_t *__restrict pixels, const Vec2f *__restrict films,
                                       uint64_t sample, size_t begin, size_t end, uint64_t *__restrict dropped) {
    using namespace simd;
    const f32x4 fits = f32x4{} + float(SplatMax);
    auto all = [](i32x4 m) { return (m[0] & m[1] & m[2] & m[3]) != 0; };
    size_t lost = 0;
    // In a large cache, the entries of the next few views are loaded while this one's is summed.
    const size_t ahead = cache.large() ? 8 : 0;
    for (size_t i = begin; i < std::min(end, begin + ahead); ++i) cache.prefetch(slots[i], films[i]);
    for (size_t i = begin; i < end; ++i) {
        if (ahead && i + ahead < end) cache.prefetch(slots[i + ahead], films[i + ahead]);
        f32x4 v = load<f32x4>(sum[i].v) * (w[i] * l_scale); // W*L, W
        v[3] = w[i];
        if (!cache.is_box(slots[i])) { // spread over the pixels the view's filter covers
            if (!cache.add(slots[i], pixels[i], films[i], sample, Spectrum(v[0], v[1], v[2]), v[3]))
                ++dropped[slots[i]], ++lost;
            continue;
        }
        const f32x4 mag = bit_cast<f32x4>(bit_cast<i32x4>(v) & 0x7fffffff);
        if (!all(mag < fits)) { // also NaN
            ++dropped[slots[i]], ++lost;
            continue;
        }
        SplatEntry &p = cache.at(slots[i], pixels[i], films[i]);
        add_fixed(p.lw, v);
        ++p.count;
    }
    return lost;
}

namespace {

/// The terms one split's entries have in common once its suffix and shadow ray are traced.
MvSplatTerms split_terms(const MvPendingSamples &pending, const MvPendingSamples::Sample &rec) {
    const Spectrum suffix = rec.suffix >= 0 ? pending.radiance[rec.suffix] : Spectrum(0.f);
    return {rec.nee_weight, suffix, rec.b_scale, rec.nee && (rec.shadow < 0 || !pending.shadow_blocked[rec.shadow]),
            !suffix.is_black(), rec.suffix >= 0 ? pending.valid[rec.suffix] != 0 : rec.valid};
}

/// The terms of one split of a shared vertex: a delta lobe's bounce serves its view only, so it
/// is left out of t.bounce and *delta says so. A view's null event whose path stays invalid
/// (§7, "Validity") leaves the split valid for the other views; *void_scale is then the factor
/// to take off that view's light sample (0 otherwise).
MvSplatTerms shared_split_terms(const MvPendingSamples &pending, const MvPendingSamples::Sample &rec, bool *delta,
                                float *void_scale) {
    MvSplatTerms t = split_terms(pending, rec);
    *delta = t.bounce && rec.delta_view >= 0;
    t.bounce = t.bounce && !*delta;
    *void_scale = 0.f;
    if (!t.valid && rec.null_scale > 0.f) {
        t.valid = true;
        *void_scale = t.nee ? rec.null_scale : 0.f;
    }
    return t;
}

/// The light sample of entry i, times `scale`, taken off `sum`.
void take_light_sample(const MvPendingSamples &pending, const MvSplatTerms &t, uint32_t i, float scale, float *sum) {
    const Spectrum l = pending.f_nee[i] * t.nee_weight * scale;
    for (int c = 0; c < 3; ++c) sum[c] -= l[c];
}

double luminance(const Spectrum &s) { return (double(s[0]) + double(s[1]) + double(s[2])) / 3.0; }

/// A medium vertex's contributions: native-only radiance of each view (W = 0).
void splat_medium_vertex(const MvPendingSamples &pending, const MvPendingSamples::Sample &rec, MvSplatSink &sink) {
    const MvSplatTerms t = split_terms(pending, rec);
    if (pending.probe) { // the native view's entry (the first)
        const uint32_t i = rec.first;
        const Spectrum lw = mv_entry_value(t, pending.f_nee[i], pending.f_bounce[i], pending.w[i]);
        mv_probe_native(*pending.probe, rec.key, lw);
        return;
    }
    size_t lost = 0;
    for (uint32_t i = rec.first; i < rec.first + rec.count; ++i)
        lost += !sink.native(pending.slot[i], pending.pixel[i], pending.film[i], rec.hash, Spectrum(0.f), 0.f,
                             mv_entry_value(t, pending.f_nee[i], pending.f_bounce[i], pending.w[i]));
    if (lost) sink.lost(rec.key);
}

/// The pilot's record of the group of splits starting at `group`: E and each split's W L of the
/// native view's entry (the first).
void probe_shared_vertex(const MvPendingSamples &pending, const MvPendingSamples::Sample *group) {
    MvPilotSample x;
    x.key = group[0].key;
    x.e = luminance(group[0].e);
    x.sharing = group[0].count;
    const uint32_t i = group[0].first;
    for (uint32_t b = 0; b < std::min(group[0].splits, uint32_t(PilotSplits)); ++b) {
        const MvPendingSamples::Sample &rec = group[b];
        bool delta;
        float void_scale;
        const MvSplatTerms t = shared_split_terms(pending, rec, &delta, &void_scale);
        Spectrum lw = mv_entry_value(t, pending.f_nee[rec.first], pending.f_bounce[rec.first], pending.w[i]);
        if (delta && t.valid && rec.delta_view == 0) lw += rec.delta_bounce * t.suffix * pending.w[i];
        if (void_scale > 0.f && rec.delta_view == 0)
            lw += pending.f_nee[rec.first] * t.nee_weight * (-void_scale * pending.w[i]);
        x.split[b] = luminance(lw);
    }
    pending.probe->samples.push_back(x);
}

/// The group of splits starting at `group` (§7): each entry's L summed over them, then W times
/// their mean, and W, splatted; the native view's entry (i = 0) with E.
void splat_shared_vertex(MvPendingSamples &pending, const MvPendingSamples::Sample *group, MvSplatSink &sink) {
    if (pending.probe) return probe_shared_vertex(pending, group);
    const uint32_t first = group[0].first, n = group[0].count;
    if (pending.radiance_sum.size() < n) pending.radiance_sum.resize(n);
    MvEntryRadiance *sum = pending.radiance_sum.data();
    std::fill_n(sum, n, MvEntryRadiance{});
    for (uint32_t b = 0; b < group[0].splits; ++b) {
        const MvPendingSamples::Sample &rec = group[b];
        bool delta;
        float void_scale;
        const MvSplatTerms t = shared_split_terms(pending, rec, &delta, &void_scale);
        mv_sum_entries(t, pending.f_nee.data() + rec.first, pending.f_bounce.data() + rec.first, n, sum);
        if (delta && t.valid)
            for (int c = 0; c < 3; ++c) sum[rec.delta_view].v[c] += rec.delta_bounce[c] * t.suffix[c];
        if (void_scale > 0.f)
            take_light_sample(pending, t, rec.first + uint32_t(rec.delta_view), void_scale, sum[rec.delta_view].v);
    }
    const float *w = pending.w.data() + first;
    const int *slots = pending.slot.data() + first;
    const uint32_t *pixels = pending.pixel.data() + first;
    const Vec2f *films = pending.film.data() + first;
    const float mean = 1.f / float(group[0].splits), w0 = w[0] * mean;
    const Spectrum lw0(sum[0].v[0] * w0, sum[0].v[1] * w0, sum[0].v[2] * w0);
    size_t lost = !sink.native(slots[0], pixels[0], films[0], group[0].hash, lw0, w[0], group[0].e);
    lost += mv_splat_entries(sink.cache, sum, w, mean, slots, pixels, films, group[0].hash, 1, n, sink.dropped);
    if (lost) sink.lost(group[0].key);
}

} // namespace

void mv_probe_delta(MvSplitProbe &probe, const SampleKey &key, const Spectrum *paths, float scale) {
    MvPilotSample x;
    x.key = key;
    x.delta = true;
    for (int k = 0; k < PilotSplits; ++k) x.split[k] = luminance(paths[k] * scale);
    probe.samples.push_back(x);
}

void mv_probe_native(MvSplitProbe &probe, const SampleKey &key, const Spectrum &e) {
    MvPilotSample x;
    x.key = key;
    x.e = luminance(e);
    probe.samples.push_back(x);
}

void mv_finish_samples(const MvContext &ctx, int slot, MvPendingSamples &pending, MvSplatSink &sink,
                       RayCounters &counters, MvViewStats *stats) {
    const size_t n_suffix = pending.rays.size();
    pending.radiance.resize(n_suffix);
    pending.valid.resize(n_suffix);
    const uint64_t rays_before = counters.rays + counters.shadow_rays;
    if (ctx.volpath) // through media: one path at a time
        for (size_t i = 0; i < n_suffix; ++i) {
            pending.radiance[i] = ctx.volpath->trace(*ctx.scene, pending.rays[i], pending.media[i], pending.states[i],
                                                     pending.samplers[i], counters, VolPathPart::All, pending.dims[i]);
            pending.valid[i] = 1;
        }
    else if (n_suffix > 0)
        ctx.path->trace_batch(*ctx.scene, pending.rays.data(), pending.states.data(), pending.samplers.data(),
                              pending.radiance.data(), pending.valid.data(), n_suffix, counters);
    stats[slot].rays += counters.rays + counters.shadow_rays - rays_before;
    // The shared NEE's shadow rays as packets (counted when queued).
    pending.shadow_blocked.resize(pending.shadow_rays.size());
    if (!pending.shadow_rays.empty())
        ctx.scene->occluded(pending.shadow_rays.data(), pending.shadow_rays.size(), pending.shadow_blocked.data());

    for (size_t r = 0; r < pending.samples.size(); r += std::max(pending.samples[r].splits, 1u)) {
        if (pending.samples[r].medium) splat_medium_vertex(pending, pending.samples[r], sink);
        else splat_shared_vertex(pending, &pending.samples[r], sink);
    }
    pending.clear();
}

} // namespace mvpt
