// The end of a tile's native samples of multi-view path tracing (docs/multiview-path-tracing.md
// §7): the samples whose suffix and shadow ray wait to be traced with the tile's others, and
// the contributions W·L of their sharing views, splatted into the pass's film.
#pragma once

#include "mv_context.h"

#include "../../render/splat_film.h"

#include <cstdint>
#include <vector>

namespace mvpt {

class Medium;
struct MvSplitProbe;

/// An entry's radiance L summed over the splits, in the first three of four floats (the fourth
/// is zero), as one vector.
struct alignas(16) MvEntryRadiance {
    float v[4];
};

/// Native samples whose suffix (the path continuing from the shared bounce, §7) waits to
/// be traced with the other samples of its batch (mv_native_samples) as one wavefront of the
/// path tracer (PathIntegrator::trace_batch), and whose NEE shadow ray waits likewise;
/// mv_finish_samples then splats their contributions.
struct MvPendingSamples {
    /// Per sample: its sharing views' entries [first, first + count) below (the native view
    /// first), its suffix (an index into the suffix arrays, or -1), its valid-path flag when it
    /// has no suffix, the shared NEE's shadow ray (its radiance counts if unblocked) or -1, and
    /// the view that sampled a delta lobe (then only its entry gets the suffix, else -1).
    /// The radiance of entry j (§7) is
    ///   L_j = [nee] f_nee_j * nee_weight + [suffix] (f_bounce_j * b_scale) * suffix,
    /// with delta_bounce in place of f_bounce_j * b_scale for a delta lobe's view.
    struct Sample {
        uint32_t first = 0, count = 0;
        int32_t suffix = -1, delta_view = -1;
        int32_t shadow = -1;
        bool valid = false;
        bool nee = false; ///< nee_weight is not black
        /// A medium vertex (§10): its contributions are added as native-only radiance (to E,
        /// with W = 0), since no fixed sum of their weights is known.
        bool medium = false;
        /// The splits of one shared vertex (§7) are consecutive records, each with its own entries'
        /// f_nee and f_bounce, suffix and light sample; the first holds the entries' slots, pixels,
        /// film positions and W, E, the splats' hash and the group's size here (0 in the others).
        uint32_t splits = 1;
        uint64_t hash = 0; ///< the native sample's Sampler::sample_hash (for the splats' taps)
        SampleKey key = NoSample; ///< the native sample, for the report of dropped contributions
        float b_scale = 0.f;
        /// For a delta view's null event: that view's own probability of a null event over the
        /// probability that the bounce drew it for that view (the validity of §7).
        float null_scale = 0.f;
        Spectrum nee_weight{0.f}, delta_bounce{0.f};
        Spectrum e{0.f}; ///< the native view's own radiance E
    };
    std::vector<Sample> samples;
    /// Per sharing view of each sample: slot, pixel, W = 1/D, and the BSDF values f_k |cos|
    /// towards the light sample and the bounce direction.
    std::vector<int> slot;
    std::vector<uint32_t> pixel; ///< sample-window pixel index
    std::vector<Vec2f> film;     ///< film position (full-film pixels)
    std::vector<float> w;
    std::vector<Spectrum> f_nee, f_bounce; ///< with one more element than the others
    std::vector<MvEntryRadiance> radiance_sum; ///< scratch: a group's L summed over its splits, per entry
    size_t entries = 0; ///< entries in use (the arrays above keep their size between tiles)
    /// Room for n more entries; returns the first.
    size_t add_entries(size_t n);
    /// The suffixes: start rays, path states and sample streams; results.
    std::vector<Ray> rays;
    std::vector<PathState> states;
    std::vector<Sampler> samplers;
    std::vector<const Medium *> media; ///< the medium each suffix starts in (scenes with media)
    std::vector<uint32_t> dims;        ///< the first sampler dimension of each suffix's steps (scenes with media)
    std::vector<Spectrum> radiance;
    std::vector<uint8_t> valid;
    /// The shared NEE's shadow rays, traced as packets with the suffixes; results.
    std::vector<Ray> shadow_rays;
    std::vector<uint8_t> shadow_blocked;
    /// The pilot of the splits' choice (mv_split_choice.h): when set, each sample's
    /// contribution to its own pixel is recorded here instead of splatted.
    MvSplitProbe *probe = nullptr;
    void clear();
};

/// What the entries of one pending sample have in common once its suffix is traced.
struct MvSplatTerms {
    Spectrum nee_weight, suffix;
    float b_scale;
    bool nee, bounce, valid; ///< the light sample is unblocked; the bounce serves every view; a valid sample
};

/// W·L of one entry (§7): ([nee] f_nee * nee_weight + [bounce] (f_bounce * b_scale) * suffix) W,
/// zero when the sample is not valid.
Spectrum mv_entry_value(const MvSplatTerms &t, const Spectrum &f_nee, const Spectrum &f_bounce, float w);

/// Adds to sum[0, n) each entry's L (mv_entry_value without W) of one split; f_nee and f_bounce
/// are read 16 bytes per entry: one Spectrum past n must be readable.
void mv_sum_entries(const MvSplatTerms &t, const Spectrum *f_nee, const Spectrum *f_bounce, size_t n,
                    MvEntryRadiance *sum);

/// Adds entries [begin, end) of one sample to `cache`: W·L and W, with W = w[i] and L = sum[i] *
/// l_scale (the mean of the splits' sum), at film position films[i] (window pixel pixels[i]) of view slots[i], of the native
/// sample with Sampler::sample_hash `sample`, the same bits as SplatCache::add; entries that do
/// not fit are counted in dropped[slot] (and returned).
size_t mv_splat_entries(SplatCache &cache, const MvEntryRadiance *sum, const float *w, float l_scale, const int *slots,
                        const uint32_t *pixels, const Vec2f *films, uint64_t sample, size_t begin, size_t end,
                        uint64_t *dropped);

/// Records radiance `e` that no split changes of native sample `key` into `probe`.
void mv_probe_native(MvSplitProbe &probe, const SampleKey &key, const Spectrum &e);
/// Records the PilotSplits paths traced on from the purely specular first vertex of native
/// sample `key`, each times `scale` (1/n_l), into `probe`.
void mv_probe_delta(MvSplitProbe &probe, const SampleKey &key, const Spectrum *paths, float scale);

/// Trace the pending samples' suffixes as one wavefront and splat their contributions; the
/// suffixes' rays count for the view in `slot` (pending samples are flushed per tile).
void mv_finish_samples(const MvContext &ctx, int slot, MvPendingSamples &pending, MvSplatSink &sink,
                       RayCounters &counters, MvViewStats *stats);

} // namespace mvpt
