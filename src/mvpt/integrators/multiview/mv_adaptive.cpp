#include "mv_adaptive.h"

#include "../../core/simd.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>

namespace mvpt {

namespace {
/// Pixels per block of the parallel loops: sums of doubles are taken per block, then over the
/// blocks in order, so that they do not depend on how the blocks meet the threads.
constexpr size_t BlockPixels = 8192;

/// f(begin, end) for every block of [0, n), in parallel (a single block inline).
template <typename F> void for_blocks(size_t n, F &&f) {
    const size_t blocks = (n + BlockPixels - 1) / BlockPixels;
    if (blocks <= 1) return f(size_t(0), n);
    tbb::parallel_for(size_t(0), blocks, [&](size_t b) { f(b * BlockPixels, std::min(n, (b + 1) * BlockPixels)); });
}

/// The sum over [0, n) of f(begin, end) per block, added in block order.
template <typename F> double sum_blocks(size_t n, F &&f) {
    std::vector<double> part((n + BlockPixels - 1) / BlockPixels);
    for_blocks(n, [&](size_t begin, size_t end) { part[begin / BlockPixels] = f(begin, end); });
    double s = 0.0;
    for (double v : part) s += v;
    return s;
}

/// 3x3 box blur with clamped borders, in parallel over rows (a small image inline).
std::vector<double> blur3(const std::vector<double> &v, int w, int h) {
    std::vector<double> out(v.size());
    auto row = [&](int y) {
        for (int x = 0; x < w; ++x) {
            double s = 0.0;
            int n = 0;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    int xx = x + dx, yy = y + dy;
                    if (xx < 0 || yy < 0 || xx >= w || yy >= h) continue;
                    s += v[size_t(yy) * w + xx];
                    ++n;
                }
            out[size_t(y) * w + x] = s / n;
        }
    };
    if (v.size() <= BlockPixels)
        for (int y = 0; y < h; ++y) row(y);
    else
        tbb::parallel_for(0, h, row);
    return out;
}

/// The native count of one pixel at level c: the positive root n of
/// c n^2 + (c r - u) n - a r = 0 (a/n + b/(n + r) = c, u = a + b), rounded to nearest and
/// clamped to [1, max_n]; not finite: max_n. Written without floor and with the clamp
/// before the truncation (the same result for every input), so that loops over it
/// vectorise; the discriminant needs no clamp, as c, a, r >= 0.
inline int32_t native_count(double c, double a, double u, double r, double top) {
    double q = c * r - u;
    double v = (std::sqrt(q * q + 4.0 * c * a * r) - q) / (2.0 * c) + 0.5;
    v = v < top + 0.5 ? v : top + 0.5; // NaN and inf fail the test: max_n
    v = v < 1.0 ? 1.0 : v;
    return int32_t(v); // truncation = floor for v >= 1
}

/// The total of the native counts of n pixels at level c (run once per bisection step).
MVPT_MULTI_ISA int64_t native_total(double c, double top, const double *__restrict a, const double *__restrict u,
                                     const double *__restrict r, size_t n) {
    int64_t s = 0;
    for (size_t i = 0; i < n; ++i) s += native_count(c, a[i], u[i], r[i], top);
    return s;
}
/// The budget spread evenly, the remainder to the first pixels.
void even_map(size_t n, double budget, std::vector<uint16_t> &map) {
    const size_t each = size_t(budget / double(n)), extra = size_t(budget) - each * n;
    for (size_t i = 0; i < n; ++i) map[i] = uint16_t(each + (i < extra ? 1 : 0));
}

/// Per pixel, the terms of the relative variance after `passes` passes, blurred: a (of the
/// native-only part E, times the native samples), unit (a plus b, b of the shared part S times
/// the contributions received: the relative variance of one more native sample) and others
/// (the contributions from other views per pass).
struct PixelTerms {
    std::vector<double> a, unit, others;
};

PixelTerms pixel_terms(const AdaptiveInput &in) {
    const size_t n = size_t(in.width) * in.height;
    const double k = in.passes;
    std::vector<double> mean(n), a(n), b(n), others(n);
    auto variance = [k](double sum, double sq) { return std::max(0.0, (sq - sum * sum / k) / (k - 1.0)); };
    double view_mean = sum_blocks(n, [&](size_t begin, size_t end) {
        double s = 0.0;
        for (size_t i = begin; i < end; ++i) {
            const double v_sum = (in.v_sum[3 * i] + in.v_sum[3 * i + 1] + in.v_sum[3 * i + 2]) / 3.0;
            const double e_sum = in.e_sum[i], s_sum = v_sum - e_sum;
            mean[i] = v_sum / k;
            s += mean[i];
            double own = double(in.native[i]) / k, received = double(in.received[i]) / k;
            // Var(E_pass) ~ a / n and Var(S_pass) ~ b / (n + r) at the mean counts of the passes so far.
            a[i] = variance(e_sum, in.e_sq[i]) * own;
            b[i] = variance(s_sum, in.s_sq[i]) * std::max(received, 1.0);
            others[i] = std::max(0.0, received - own);
        }
        return s;
    });
    view_mean /= double(n);
    const double eps = std::max({0.01 * view_mean * view_mean, in.eps, 1e-12}); // (view mean / 10)^2, in.eps
    for_blocks(n, [&](size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i) {
            double scale = 1.0 / (mean[i] * mean[i] + eps);
            a[i] = std::isfinite(a[i] * scale) ? a[i] * scale : 0.0;
            b[i] = std::isfinite(b[i] * scale) ? b[i] * scale : 0.0;
        }
    });
    PixelTerms t;
    t.a = blur3(a, in.width, in.height);
    b = blur3(b, in.width, in.height);
    t.others = blur3(others, in.width, in.height);
    t.unit = std::move(mean);
    for_blocks(n, [&](size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i) t.unit[i] = t.a[i] + b[i];
    });
    return t;
}

/// The smallest level c (to 1 %) whose native samples total(c) fit in `budget`, `hi` the
/// largest unit term. total(c) decreases in c: bisect on log c (finer changes a count only
/// where its rounding is a coin toss; each step costs a pass over the pixels). The bracket
/// starts around the last pass's c (the statistics change little between passes), else around
/// the c of a/n = c with every n free, and is widened until it holds the answer.
template <typename Total>
double solve_level(Total &&total, double budget, double hi, double sum_unit, double previous_level) {
    const double lowest = hi * 1e-12, highest = hi * 2.0; // total(2 hi) = n
    const bool warm = previous_level >= lowest && previous_level <= highest;
    const double guess = warm ? previous_level : std::clamp(sum_unit / budget, lowest, highest);
    const double spread = warm ? 1.1 : 16.0;
    double lo_c = guess / spread, hi_c = guess * spread;
    while (lo_c > lowest && total(lo_c) <= budget) lo_c = std::max(lo_c / 256.0, lowest);
    while (hi_c < highest && total(hi_c) > budget) hi_c = std::min(hi_c * 256.0, highest);
    if (total(lo_c) <= budget) hi_c = lo_c;
    for (int it = 0; it < 60 && hi_c > lo_c * (1.0 + 1e-2); ++it) {
        double mid = std::sqrt(lo_c * hi_c);
        if (total(mid) <= budget) hi_c = mid;
        else lo_c = mid;
    }
    return hi_c;
}
} // namespace

double adapt_native_map(const AdaptiveInput &in, int max_n, double budget, std::vector<uint16_t> &map) {
    const size_t n = size_t(in.width) * in.height;
    map.assign(n, 1);
    if (n == 0) return 0.0;
    budget = std::clamp(budget, double(n), double(n) * max_n);
    if (in.passes < 2) {
        even_map(n, budget, map);
        return 0.0;
    }
    const PixelTerms t = pixel_terms(in);
    double hi = 0.0;
    for (double u : t.unit) hi = std::max(hi, u);
    if (!(hi > 0.0)) {
        even_map(n, budget, map);
        return 0.0;
    }
    const double top = double(max_n);
    auto total = [&](double c) {
        if (n <= BlockPixels) return double(native_total(c, top, t.a.data(), t.unit.data(), t.others.data(), n));
        return double(tbb::parallel_reduce(
            tbb::blocked_range<size_t>(0, n, BlockPixels), int64_t(0),
            [&](const tbb::blocked_range<size_t> &r, int64_t s) {
                return s + native_total(c, top, t.a.data() + r.begin(), t.unit.data() + r.begin(),
                                        t.others.data() + r.begin(), r.size());
            },
            [](int64_t x, int64_t y) { return x + y; })); // integer sums: the order does not matter
    };
    const double sum_unit = sum_blocks(n, [&](size_t begin, size_t end) {
        double s = 0.0;
        for (size_t i = begin; i < end; ++i) s += t.unit[i];
        return s;
    });
    const double c = solve_level(total, budget, hi, sum_unit, in.previous_level);
    for_blocks(n, [&](size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i) map[i] = uint16_t(native_count(c, t.a[i], t.unit[i], t.others[i], top));
    });
    return c;
}

} // namespace mvpt
