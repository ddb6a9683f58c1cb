#include "mv_film.h"

#include <algorithm>
#include <climits>

namespace mvpt {

MvFilm::MvFilm(int width_, int height_, int margin_, MvEstimator est, bool cv)
    : estimator(est), control_variate(cv), width(width_), height(height_), margin(margin_) {
    const size_t pixels = size_t(width) * size_t(height);
    e_sum.assign(pixels, 0.f), e_sq.assign(pixels, 0.f), s_sq.assign(pixels, 0.f);
    native.assign(pixels, 0), received.assign(pixels, 0);
    map.assign(size_t(width + 2 * margin) * size_t(height + 2 * margin), 1);
    if (estimator == MvEstimator::Balance) {
        ratio.assign(4 * pixels, 0.f);
    } else {
        lw.assign(3 * pixels, 0.0);
        e.assign(3 * pixels, 0.0);
        w.assign(pixels, 0.0);
    }
}

size_t MvFilm::bytes_per_pixel(MvEstimator estimator) {
    size_t sums = estimator == MvEstimator::Balance ? 4 * sizeof(float) : 7 * sizeof(double);
    return sums + 3 * sizeof(float) + 2 * sizeof(uint32_t) + sizeof(uint16_t);
}

void MvFilm::fold(MvPassFilm &pass, uint32_t offset, size_t begin, size_t end, PassSums out) {
    const bool balance = estimator == MvEstimator::Balance;
    for (size_t p = begin; p < end; ++p) {
        const SplatEntry t = pass.take(offset + uint32_t(p));
        const double w_pass = double(t.w) / SplatScale;
        double v[3], e_mean = 0.0;
        if (balance) {
            // The balance estimate of this pass, W*L + E, plus the control variate beta (1 - sum W):
            // E[sum W] = 1 exactly when D sums over every valid strategy, and beta, the ratio
            // estimate of the earlier passes, is independent of this pass, so the estimate stays
            // unbiased while the noise of how many contributions happened to land in the pixel cancels.
            float *r = &ratio[4 * p];
            const bool cv = control_variate && r[3] > 0.f;
            for (int c = 0; c < 3; ++c) {
                const double lw_e = double(t.lw[c]) / SplatScale;
                v[c] = lw_e + (cv ? double(r[c]) / double(r[3]) * (1.0 - w_pass) : 0.0);
                r[c] += float(lw_e);
            }
            r[3] += float(w_pass);
            e_mean = double(t.e[0]) / SplatScale;
        } else {
            for (int c = 0; c < 3; ++c) {
                const double lw_e = double(t.lw[c]) / SplatScale, e_c = double(t.e[c]) / SplatScale;
                v[c] = lw_e;
                lw[3 * p + c] += double(t.lw[c] - t.e[c]) / SplatScale;
                e[3 * p + c] += e_c;
                e_mean += e_c / 3.0;
            }
            w[p] += w_pass;
        }
        double v_mean = 0.0;
        for (int c = 0; c < 3; ++c) {
            out.sum[3 * p + c] += v[c];
            out.sum_sq[3 * p + c] += v[c] * v[c];
            v_mean += v[c] / 3.0;
        }
        ++out.count[p];
        const double s = v_mean - e_mean;
        e_sum[p] += float(e_mean);
        e_sq[p] += float(e_mean * e_mean);
        s_sq[p] += float(s * s);
        received[p] = uint32_t(std::min<uint64_t>(uint64_t(received[p]) + t.count, UINT32_MAX));
        native[p] += n(p);
    }
}

void MvFilm::set_map(const std::vector<uint16_t> &crop) {
    const size_t w = size_t(width + 2 * margin);
    for (size_t y = 0; y < size_t(height); ++y)
        std::copy_n(crop.begin() + long(y * size_t(width)), width, map.begin() + long((y + size_t(margin)) * w + size_t(margin)));
}

float MvFilm::weight_sum(size_t p, uint32_t passes) const {
    if (passes == 0) return 0.f;
    return float((estimator == MvEstimator::Balance ? double(ratio[4 * p + 3]) : w[p]) / double(passes));
}

} // namespace mvpt
