#include "mv_adaptive.h"

#include <algorithm>
#include <cmath>

namespace mvpt {

namespace {
/// 3x3 box blur with clamped borders.
std::vector<double> blur3(const std::vector<double> &v, int w, int h) {
    std::vector<double> out(v.size());
    for (int y = 0; y < h; ++y)
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
    return out;
}
} // namespace

void adapt_native_map(const AdaptiveInput &in, int max_n, double budget, std::vector<uint16_t> &map) {
    const size_t n = size_t(in.width) * in.height;
    map.assign(n, 1);
    if (n == 0) return;
    budget = std::clamp(budget, double(n), double(n) * max_n);
    if (in.passes < 2) {
        // Even spread of the budget, the remainder to the first pixels.
        size_t each = size_t(budget / double(n)), extra = size_t(budget) - each * n;
        for (size_t i = 0; i < n; ++i) map[i] = uint16_t(each + (i < extra ? 1 : 0));
        return;
    }
    const double k = in.passes;
    std::vector<double> mean(n), var(n);
    double view_mean = 0.0;
    for (size_t i = 0; i < n; ++i) {
        double m = 0.0, v = 0.0;
        for (int c = 0; c < 3; ++c) {
            double mc = in.sum[3 * i + c] / k;
            m += mc;
            v += std::max(0.0, (in.sum_sq[3 * i + c] - k * mc * mc) / (k - 1.0));
        }
        mean[i] = m / 3.0;
        var[i] = v / 3.0;
        view_mean += mean[i];
    }
    view_mean /= double(n);
    const double eps = std::max(0.01 * view_mean * view_mean, 1e-12); // (view mean / 10)^2
    std::vector<double> unit(n), others(n);
    for (size_t i = 0; i < n; ++i) {
        double rel = var[i] / (mean[i] * mean[i] + eps);
        double received = double(in.received[i]) / k, own = double(in.native[i]) / k;
        unit[i] = std::isfinite(rel) ? rel * std::max(received, 1.0) : 0.0;
        others[i] = std::max(0.0, received - own);
    }
    unit = blur3(unit, in.width, in.height);
    others = blur3(others, in.width, in.height);

    auto count = [&](double c, size_t i) {
        double v = std::floor(unit[i] / c - others[i] + 0.5);
        return std::clamp(v, 1.0, double(max_n));
    };
    auto total = [&](double c) {
        double s = 0.0;
        for (size_t i = 0; i < n; ++i) s += count(c, i);
        return s;
    };
    double hi = 0.0;
    for (double u : unit) hi = std::max(hi, u);
    if (!(hi > 0.0)) {
        AdaptiveInput none = in;
        none.passes = 0;
        adapt_native_map(none, max_n, budget, map);
        return;
    }
    // total(c) decreases in c: bisect on log c for the smallest c with total(c) <= budget.
    double lo_c = hi * 1e-12, hi_c = hi * 2.0; // total(hi_c) = n (every pixel at 1)
    if (total(lo_c) <= budget) hi_c = lo_c;
    for (int it = 0; it < 60 && hi_c > lo_c * (1.0 + 1e-9); ++it) {
        double mid = std::sqrt(lo_c * hi_c);
        if (total(mid) <= budget) hi_c = mid;
        else lo_c = mid;
    }
    for (size_t i = 0; i < n; ++i) map[i] = uint16_t(count(hi_c, i));
}

} // namespace mvpt
