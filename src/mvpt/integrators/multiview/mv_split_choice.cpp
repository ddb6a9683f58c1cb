// The splits of the shared vertex chosen from a pilot (§7, "Choosing the number of splits").
#include "mv_split_choice.h"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace mvpt {

namespace {

/// The model cost of a native sample, in path-traced samples (docs/performance.md, "Choosing
/// the number of splits"): c0 = 1 + (KappaShift + KappaWrite (w - 1)) (|S| - 1) for the camera
/// ray, the shifts, the visibility, the sums D and the splats of a shared vertex (w: the splat
/// cache entries a contribution adds to, 1 for a box filter), and c1 = SplitPath + KappaLobe |S|
/// per split for its light sample, bounce and suffix and the lobes of every sharing view. A
/// sample that no view shares costs one path: 1 + 0 B.
constexpr double KappaShift = 0.04, KappaWrite = 0.03, SplitPath = 1.3, KappaLobe = 0.005;
/// choose_splits takes the fewest splits whose variance times cost is within this of the least.
constexpr double SplitTolerance = 1.05;

/// The samples of one probe (of one view) ordered by pixel, then sample index, each native
/// sample's records summed into one.
std::vector<MvPilotSample> merged(std::vector<MvPilotSample> s) {
    auto order = [](const MvPilotSample &a) { return std::make_tuple(a.key[2], a.key[3], a.key[0]); };
    std::sort(s.begin(), s.end(), [&](const auto &a, const auto &b) { return order(a) < order(b); });
    std::vector<MvPilotSample> out;
    for (const MvPilotSample &r : s) {
        if (out.empty() || out.back().key != r.key) {
            out.push_back(r);
            continue;
        }
        MvPilotSample &m = out.back();
        m.e += r.e;
        for (int b = 0; b < PilotSplits; ++b) m.split[b] += r.split[b];
        m.sharing = std::max(m.sharing, r.sharing);
        m.delta |= r.delta;
    }
    return out;
}

/// A sample's estimate at its pixel, E + the mean of its splits, and one split's variance
/// (unbiased, over the splits).
std::pair<double, double> estimate(const MvPilotSample &s) {
    double mean = 0.0, var = 0.0;
    for (double v : s.split) mean += v;
    mean /= PilotSplits;
    for (double v : s.split) var += (v - mean) * (v - mean);
    return {s.e + mean, var / (PilotSplits - 1)};
}

/// A pixel's pair of samples (`total`: their spread, `r`: their splits' or paths' variance, `m`:
/// their mean) into the class both belong to, if they do.
void add_to_class(SplitStatistics &st, const MvPilotSample &x1, const MvPilotSample &x2, double total, double r,
                  double m, double eps) {
    SplitStatistics::PixelClass *c = nullptr;
    double scale = 1.0, sharing = 0.5 * double(x1.sharing + x2.sharing);
    if (x1.delta && x2.delta) c = &st.specular;
    else if (!x1.delta && !x2.delta && !x1.sharing && !x2.sharing) c = &st.environment, r = 0.0;
    else if (x1.sharing && x2.sharing) c = &st.shared, scale = sharing, m *= sharing;
    if (!c) return;
    const double weight = scale / (m * m + eps);
    c->a += weight * (total - r / PilotSplits);
    c->r += weight * r;
    ++c->pixels;
}

} // namespace

SplitStatistics split_statistics(const std::vector<MvSplitProbe> &probes, double eps, double writes) {
    SplitStatistics st;
    const double per_view = KappaShift + KappaWrite * std::max(writes - 1.0, 0.0);
    uint64_t samples = 0;
    for (const MvSplitProbe &probe : probes) {
        const std::vector<MvPilotSample> s = merged(probe.samples);
        for (const MvPilotSample &x : s) {
            const double ns = x.sharing;
            st.c0 += x.sharing ? 1.0 + per_view * (ns - 1.0) : x.delta ? 0.0 : 1.0;
            st.c1 += x.sharing ? SplitPath + KappaLobe * ns : 0.0;
            st.d1 += x.delta ? 1.0 : 0.0; // (each of its K paths, the first with its camera ray, one path)
            ++samples;
        }
        // Pairs of samples of one pixel: (X1 - X2)^2 / 2 estimates the variance of one, a + r / PilotSplits.
        for (size_t i = 0; i + 1 < s.size(); ++i) {
            if (s[i].key[2] != s[i + 1].key[2] || s[i].key[3] != s[i + 1].key[3]) continue;
            const auto [x1, r1] = estimate(s[i]);
            const auto [x2, r2] = estimate(s[i + 1]);
            const double m = 0.5 * (x1 + x2), weight = 1.0 / (m * m + eps);
            // The spread of a specular first vertex's paths is r_d's, of a shared vertex's splits r's.
            const double total = 0.5 * (x1 - x2) * (x1 - x2), r = 0.5 * (r1 + r2);
            const double r_d = 0.5 * ((s[i].delta ? r1 : 0.0) + (s[i + 1].delta ? r2 : 0.0));
            st.a += weight * (total - r / PilotSplits);
            st.r += weight * (r - r_d);
            st.r_d += weight * r_d;
            add_to_class(st, s[i], s[i + 1], total, r, m, eps);
            ++st.pixels, ++i;
        }
    }
    if (samples) st.c0 /= double(samples), st.c1 /= double(samples), st.d1 /= double(samples);
    for (const MvSplitProbe &probe : probes)
        for (const auto &[x1, x2] : probe.path_traced) {
            const double m = 0.5 * (x1 + x2);
            st.pt_v += 0.5 * (x1 - x2) * (x1 - x2) / (m * m + eps);
            ++st.pt_pixels;
        }
    if (st.pt_pixels) st.pt_v /= double(st.pt_pixels);
    return st;
}

namespace {
/// The variance of a pixel at equal time with B splits and K paths of a specular first vertex.
double equal_time_variance(const SplitStatistics &s, int b, int k) {
    // a may come out below zero (the pairs' spread is itself noisy): splitting then removes
    // nearly all the variance, and the cost alone bounds B.
    const double a = std::max(s.a, 0.0), r_d = std::max(s.r_d, 0.0);
    return (a + s.r / b + r_d / k) * (s.c0 + b * s.c1 + k * s.d1);
}
} // namespace

int choose_delta_splits(const SplitStatistics &s, int splits) {
    if (!(s.r_d > 0.0) || !(s.d1 > 0.0) || !std::isfinite(s.a + s.r + s.r_d)) return 1;
    int best = 1;
    for (int k = 2; k <= MaxDeltaSplits; ++k)
        if (equal_time_variance(s, splits, k) < equal_time_variance(s, splits, best)) best = k;
    return best;
}

int choose_splits(const SplitStatistics &s, int most) {
    if (!(s.r > 0.0) || !(s.c1 > 0.0) || !std::isfinite(s.a + s.r + s.r_d)) return 1;
    auto cost = [&](int b) { return equal_time_variance(s, b, choose_delta_splits(s, b)); };
    const int last = std::clamp(most, 1, MaxChosenSplits);
    double best = INFINITY;
    for (int b = 1; b <= last; ++b) best = std::min(best, cost(b));
    // The product is flat near its least and the pilot's a is noisy: the fewest splits within
    // SplitTolerance of the least (shorter passes, the same efficiency within the model's error).
    for (int b = 1; b <= last; ++b)
        if (cost(b) <= SplitTolerance * best) return b;
    return last;
}

double predicted_gain(const SplitStatistics &s, int splits, int delta_splits) {
    const uint64_t pixels = s.shared.pixels + s.specular.pixels + s.environment.pixels;
    if (pixels < 16 || s.pt_pixels < 16) return 0.0;
    const double b = std::max(splits, 1), k = std::max(delta_splits, 1);
    auto pass = [](const SplitStatistics::PixelClass &c, double ways) {
        return std::max(c.a, 0.0) + std::max(c.r, 0.0) / ways;
    };
    const double v_mv = (pass(s.shared, b) + pass(s.specular, k) + std::max(s.environment.a, 0.0)) / double(pixels);
    const double c_mv = s.c0 + b * s.c1 + k * s.d1;
    const double gain = s.pt_v / (v_mv * c_mv);
    return std::isfinite(gain) && gain > 0.0 ? gain : 0.0;
}

int splits_fitting(const SplitStatistics &s, double unit, double left, double passes) {
    int most = MaxChosenSplits;
    while (most > 1 && passes * unit * (s.c0 + most * s.c1) > left) --most;
    return most;
}

} // namespace mvpt
