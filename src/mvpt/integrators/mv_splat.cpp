// The end of a tile's native samples (§7): their suffixes traced as one wavefront, their
// shared NEE's shadow rays as packets, and each sharing view's contribution W·L splatted.
#include "mv_sample.h"
#include "volpath.h"

#include "../core/multi_isa.h"
#include "../scene/scene.h"

#include <algorithm>

#if defined(__SSE2__)
#include <emmintrin.h>
#include <xmmintrin.h>
#endif

namespace mvpt {

Spectrum mv_entry_value(const MvSplatTerms &t, const Spectrum &f_nee, const Spectrum &f_bounce, float w) {
    Spectrum L = t.nee ? f_nee * t.nee_weight : Spectrum(0.f);
    if (t.bounce) L += f_bounce * t.b_scale * t.suffix;
    return t.valid ? L * w : Spectrum(0.f);
}

// Per entry, the four values in the lanes of one vector, masked as mv_entry_value selects,
// then x = v 2^30 + 1.5 2^52, which holds v 2^30 rounded to an integer (to nearest even) in its
// low bits: exactly to_fixed's llrint when |v| < 2^21. Other values that fit take to_fixed per
// channel.
MVPT_MULTI_ISA size_t mv_splat_entries(SplatCache &cache, const MvSplatTerms &t, const Spectrum *__restrict f_nee,
                                     const Spectrum *__restrict f_bounce, const float *__restrict w,
                                     const int *__restrict slots, const uint32_t *__restrict pixels,
                                     const Vec2f *__restrict films, uint64_t sample, size_t begin, size_t end,
                                     uint64_t *__restrict dropped) {
    size_t lost = 0;
#if !defined(__SSE2__) // not x86-64: entry by entry
    for (size_t i = begin; i < end; ++i)
        if (!cache.add(slots[i], pixels[i], films[i], sample, mv_entry_value(t, f_nee[i], f_bounce[i], w[i]), w[i]))
            ++dropped[slots[i]], ++lost;
#else
    typedef double D4 __attribute__((vector_size(32)));
    typedef int64_t I4 __attribute__((vector_size(32)));
    static_assert(sizeof(Spectrum) == 12, "entries are read as 16 bytes from each Spectrum");
    const __m128i lanes3 = _mm_set_epi32(0, -1, -1, -1), lane3 = _mm_set_epi32(-1, 0, 0, 0);
    const __m128 nee_mask = _mm_castsi128_ps(t.nee ? lanes3 : _mm_setzero_si128());
    const __m128 bounce_mask = _mm_castsi128_ps(t.bounce ? lanes3 : _mm_setzero_si128());
    const __m128 valid_mask = _mm_castsi128_ps(t.valid ? lanes3 : _mm_setzero_si128());
    const __m128 nw = _mm_setr_ps(t.nee_weight[0], t.nee_weight[1], t.nee_weight[2], 0.f);
    const __m128 bs = _mm_set1_ps(t.b_scale), sfx = _mm_setr_ps(t.suffix[0], t.suffix[1], t.suffix[2], 0.f);
    const __m128 abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    const __m128 exact = _mm_set1_ps(0x1p21f), fits = _mm_set1_ps(float(SplatMax));
    const D4 scale = {SplatScale, SplatScale, SplatScale, SplatScale};
    const D4 magic = {0x1.8p52, 0x1.8p52, 0x1.8p52, 0x1.8p52};
    I4 magic_bits;
    __builtin_memcpy(&magic_bits, &magic, sizeof(magic));
    // In a large cache, the entries of the next few views are loaded while this one's is summed.
    const size_t ahead = cache.large() ? 8 : 0;
    for (size_t i = begin; i < std::min(end, begin + ahead); ++i) cache.prefetch(slots[i], films[i]);
    for (size_t i = begin; i < end; ++i) {
        if (ahead && i + ahead < end) cache.prefetch(slots[i + ahead], films[i + ahead]);
        const __m128 fn = _mm_loadu_ps(&f_nee[i].r), fb = _mm_loadu_ps(&f_bounce[i].r);
        const __m128 L = _mm_add_ps(_mm_and_ps(_mm_mul_ps(fn, nw), nee_mask),
                                    _mm_and_ps(_mm_mul_ps(_mm_mul_ps(fb, bs), sfx), bounce_mask));
        const __m128 wi = _mm_set1_ps(w[i]);
        const __m128 v = _mm_or_ps(_mm_and_ps(_mm_mul_ps(L, wi), valid_mask), _mm_and_ps(wi, _mm_castsi128_ps(lane3)));
        const __m128 mag = _mm_and_ps(v, abs_mask);
        float f[4];
        _mm_storeu_ps(f, v);
        if (!cache.is_box(slots[i])) { // spread over the pixels the view's filter covers
            if (!cache.add(slots[i], pixels[i], films[i], sample, Spectrum(f[0], f[1], f[2]), f[3]))
                ++dropped[slots[i]], ++lost;
            continue;
        }
        if (_mm_movemask_ps(_mm_cmplt_ps(mag, fits)) != 0xf) {
            ++dropped[slots[i]], ++lost;
            continue;
        }
        SplatEntry &p = cache.at(slots[i], pixels[i], films[i]);
        if (_mm_movemask_ps(_mm_cmplt_ps(mag, exact)) == 0xf) {
            const D4 x = D4{f[0], f[1], f[2], f[3]} * scale + magic;
            I4 fixed, sum;
            __builtin_memcpy(&fixed, &x, sizeof(fixed));
            __builtin_memcpy(&sum, &p, sizeof(sum));
            sum += fixed - magic_bits;
            __builtin_memcpy(static_cast<void *>(&p), &sum, sizeof(sum));
        } else {
            for (int c = 0; c < 3; ++c) p.lw[c] += to_fixed(f[c]);
            p.w += to_fixed(f[3]);
        }
        ++p.count;
    }
#endif
    return lost;
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

    for (const MvPendingSamples::Sample &rec : pending.samples) {
        const Spectrum suffix = rec.suffix >= 0 ? pending.radiance[rec.suffix] : Spectrum(0.f);
        const bool bounce = !suffix.is_black();
        const MvSplatTerms t{rec.nee_weight, suffix, rec.b_scale, rec.nee && (rec.shadow < 0 || !pending.shadow_blocked[rec.shadow]),
                            bounce && rec.delta_view < 0, rec.suffix >= 0 ? pending.valid[rec.suffix] != 0 : rec.valid};
        const uint32_t first = rec.first, n = rec.count;
        const Spectrum *f_nee = pending.f_nee.data() + first, *f_bounce = pending.f_bounce.data() + first;
        const float *w = pending.w.data() + first;
        const int *slots = pending.slot.data() + first;
        const uint32_t *pixels = pending.pixel.data() + first;
        const Vec2f *films = pending.film.data() + first;
        if (rec.medium) { // a medium vertex's contributions are native-only radiance of each view (W = 0)
            size_t lost = 0;
            for (uint32_t i = 0; i < n; ++i)
                lost += !sink.native(slots[i], pixels[i], films[i], rec.hash, Spectrum(0.f), 0.f,
                                     mv_entry_value(t, f_nee[i], f_bounce[i], w[i]));
            if (lost) sink.lost(rec.key);
            continue;
        }
        // Two entries on their own: a delta lobe's direction serves its view only, and the
        // native view's entry (i = 0) also carries E.
        const int delta = bounce ? rec.delta_view : -1;
        auto value = [&](int i) {
            if (i != delta) return mv_entry_value(t, f_nee[i], f_bounce[i], w[i]);
            Spectrum L = t.nee ? f_nee[i] * rec.nee_weight : Spectrum(0.f);
            L += rec.delta_bounce * suffix;
            return t.valid ? L * w[i] : Spectrum(0.f);
        };
        size_t lost = !sink.native(slots[0], pixels[0], films[0], rec.hash, value(0), w[0], rec.e);
        if (delta > 0) {
            lost += !sink.shared(slots[delta], pixels[delta], films[delta], rec.hash, value(delta), w[delta]);
            lost += mv_splat_entries(sink.cache, t, f_nee, f_bounce, w, slots, pixels, films, rec.hash, 1,
                                     size_t(delta), sink.dropped);
            lost += mv_splat_entries(sink.cache, t, f_nee, f_bounce, w, slots, pixels, films, rec.hash,
                                     size_t(delta) + 1, n, sink.dropped);
        } else
            lost += mv_splat_entries(sink.cache, t, f_nee, f_bounce, w, slots, pixels, films, rec.hash, 1, n, sink.dropped);
        if (lost) sink.lost(rec.key);
    }
    pending.clear();
}

} // namespace mvpt
