// The number of splits of the shared vertex chosen per render (docs/multiview-path-tracing.md
// §7, "Choosing the number of splits"): a pilot of native samples, two per pixel at a fixed set
// of pixels, each with PilotSplits splits, gives the variance of a pixel's estimate that splitting
// removes and the part it leaves, and the model of a native sample's cost in the views that share
// it; B is the fewest splits whose variance times cost is near the least.
#pragma once

#include "../../render/splat_film.h"

#include <array>
#include <cstdint>
#include <vector>

namespace mvpt {

/// Splits of each pilot sample's shared vertex.
inline constexpr int PilotSplits = 8;
/// The most splits a render chooses: beyond, the variance times cost changes by a few per cent
/// on the scenes measured (docs/performance.md) while passes grow longer.
inline constexpr int MaxChosenSplits = 16;

/// What one native sample of the pilot brought to its own pixel (luminance, the mean of RGB):
/// the part no split changes (native-only radiance E, medium vertices) and, per split b, the
/// shared part W L_b (zero for a sample whose first vertex is not shared).
struct MvPilotSample {
    SampleKey key = NoSample;
    double e = 0.0;
    double split[PilotSplits] = {};
    uint32_t sharing = 0; ///< |S|, the views sharing its first vertex (0: not shared)
    /// Its first vertex is purely specular (no view can share it): `split` holds PilotSplits
    /// paths traced on from it, each its own estimate of the sample's radiance (e is 0).
    bool delta = false;
};

/// Pilot records, in any order, several per native sample allowed (mv_finish_samples and the
/// unshared paths add to it instead of splatting); both samples of a pixel in one probe.
struct MvSplitProbe {
    std::vector<MvPilotSample> samples;
    /// Two path-traced samples' luminance at each of the probe's pixels (predicted_gain).
    std::vector<std::array<double, 2>> path_traced;
};

/// What the choice is made from, summed over the pilot's pixels, each weighted by 1 / (m^2 +
/// eps) (m: the pixel's pilot mean): the variance of one native sample's estimate at its pixel,
/// a + r / B, split into a (from where the sample lands and what it finds there) and r (what
/// y receives: one split's variance); and the mean model costs of a native sample, c0 + B c1.
struct SplitStatistics {
    double a = 0.0, r = 0.0;
    double c0 = 0.0, c1 = 0.0;
    uint64_t pixels = 0;
    /// The same for the native samples whose first vertex is purely specular, split K ways
    /// (MvConfig::delta_splits): r_d, one path's variance given the sample, and d1, a path's
    /// mean cost per native sample (one path-traced sample each); their a is in a. A native
    /// sample's variance is a + r / B + r_d / K, its cost c0 + B c1 + K d1.
    double r_d = 0.0, d1 = 0.0;
    /// The same by class, for predicted_gain: sums over the pixels whose two samples are both
    /// of the class, a and r as above (r: one path's variance of a specular first vertex, one
    /// split's of a shared one). A shared sample's terms are those of its pixel's pass
    /// estimate, to which |S| views' samples bring as much: times |S|, relative to the pixel's
    /// value, |S| times the sample's own share.
    struct PixelClass {
        double a = 0.0, r = 0.0;
        uint64_t pixels = 0;
    };
    PixelClass specular, environment, shared;
    /// The relative variance of one path-traced sample, the mean over the pilot's pixels.
    double pt_v = 0.0;
    uint64_t pt_pixels = 0;
};

/// The pilot's statistics from the records of every view (pairs of samples at each pixel);
/// `writes`: the splat cache entries a contribution adds to, on average over the views
/// (SplatFootprint::mean_writes).
SplitStatistics split_statistics(const std::vector<MvSplitProbe> &probes, double eps, double writes = 1.0);

/// The most ways a purely specular first vertex's path is split (MvConfig::delta_splits).
inline constexpr int MaxDeltaSplits = 64;

/// The fewest splits in [1, min(most, MaxChosenSplits)] whose (a + r / B + r_d / K) (c0 + B c1 +
/// K d1), the variance of a pixel at equal time, is within 5 % of the least there, each B with
/// its best K (choose_delta_splits); 1 without statistics.
int choose_splits(const SplitStatistics &s, int most = MaxChosenSplits);

/// For B splits of the shared vertex, the K in [1, MaxDeltaSplits] ways to split the path of a
/// purely specular first vertex that makes (a + r / B + r_d / K) (c0 + B c1 + K d1) least; 1
/// without such samples.
int choose_delta_splits(const SplitStatistics &s, int splits);

/// Path tracing's relMSE over multi-view path tracing's at equal time as the pilot predicts it
/// (docs/multiview-path-tracing.md, "Choosing the method"): the mean relative variance of a
/// pixel's pass (each class of pixels as SplitStatistics::PixelClass has it, with B splits and
/// K paths of a specular first vertex) times the model cost of a pass per pixel
/// (c0 + B c1 + K d1), against one path-traced sample's variance at the cost of one; 0 when
/// the pilot cannot tell (too few pixels of each kind).
double predicted_gain(const SplitStatistics &s, int splits, int delta_splits);

/// Under a time budget: the most splits B in [1, MaxChosenSplits] for which `passes` passes, each
/// lasting `unit` (s.c0 + B s.c1) seconds, fit in `left` seconds; 1 when none does. (The paths of
/// specular first vertices, K d1, are in s.c0 there: the caller adds them once K is chosen.)
int splits_fitting(const SplitStatistics &s, double unit, double left, double passes);

} // namespace mvpt
