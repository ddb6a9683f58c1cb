#include "mv_film.h"

#include "render_state.h"

#include <algorithm>
#include <cfloat>
#include <climits>

namespace mvpt {

MvFilm::MvFilm(int width_, int height_, int margin_, MvEstimator est, bool cv, bool adaptive)
    : estimator(est), control_variate(cv), width(width_), height(height_), margin(margin_) {
    const size_t pixels = size_t(width) * size_t(height);
    sum.assign(3 * pixels, 0.0), m2.assign(3 * pixels, 0.f), w_sum.assign(pixels, 0.f);
    if (estimator == MvEstimator::Weighted) lw.assign(3 * pixels, 0.0), e.assign(3 * pixels, 0.0), w.assign(pixels, 0.0);
    if (adaptive) e_sum.assign(pixels, 0.f), e_sq.assign(pixels, 0.f), s_sq.assign(pixels, 0.f);
    native.assign(pixels, 0), received.assign(pixels, 0);
    map.assign(size_t(width + 2 * margin) * size_t(height + 2 * margin), 1);
    map_total = pixels;
}

size_t MvFilm::bytes_per_pixel(MvEstimator estimator, bool adaptive) {
    size_t b = 3 * sizeof(double) + 4 * sizeof(float) + 2 * sizeof(uint32_t) + sizeof(uint16_t);
    if (estimator == MvEstimator::Weighted) b += 7 * sizeof(double);
    if (adaptive) b += 3 * sizeof(float);
    return b;
}

void MvFilm::fold(MvPassFilm &pass, uint32_t offset, size_t begin, size_t end) {
    const bool balance = estimator == MvEstimator::Balance, adaptive = !e_sum.empty();
    const double k = double(passes); // earlier passes
    for (size_t p = begin; p < end; ++p) {
        const SplatEntry t = pass.take(offset + uint32_t(p));
        const double w_pass = double(t.w) / SplatScale;
        double v[3], e_mean = 0.0;
        if (balance) {
            // The balance estimate of this pass, W*L + E, plus the control variate beta (1 - sum W):
            // E[sum W] = 1 exactly when D sums over every valid strategy, and beta, the mean of the
            // earlier passes' estimates, is independent of this pass, so the estimate stays
            // unbiased while the noise of how many contributions happened to land in the pixel cancels.
            const bool cv = control_variate && passes > 0;
            for (int c = 0; c < 3; ++c)
                v[c] = double(t.lw[c]) / SplatScale + (cv ? sum[3 * p + c] / k * (1.0 - w_pass) : 0.0);
            e_mean = double(t.e[0]) / SplatScale;
        } else {
            for (int c = 0; c < 3; ++c) {
                const double e_c = double(t.e[c]) / SplatScale;
                v[c] = double(t.lw[c]) / SplatScale;
                lw[3 * p + c] += double(t.lw[c] - t.e[c]) / SplatScale;
                e[3 * p + c] += e_c;
                e_mean += e_c / 3.0;
            }
            w[p] += w_pass;
        }
        double v_mean = 0.0;
        for (int c = 0; c < 3; ++c) {
            // Welford: the deviation from the mean before and after this pass.
            const double before = k > 0.0 ? sum[3 * p + c] / k : 0.0;
            sum[3 * p + c] += v[c];
            m2[3 * p + c] += float((v[c] - before) * (v[c] - sum[3 * p + c] / (k + 1.0)));
            v_mean += v[c] / 3.0;
        }
        w_sum[p] += float(w_pass);
        if (adaptive) {
            const double s = v_mean - e_mean;
            e_sum[p] += float(e_mean);
            e_sq[p] += float(e_mean * e_mean);
            s_sq[p] += float(s * s);
        }
        received[p] = uint32_t(std::min<uint64_t>(uint64_t(received[p]) + t.count, UINT32_MAX));
        native[p] += n(p);
    }
}

void MvFilm::develop(size_t p, float rgb[3], float variance[3]) const {
    const double k = double(passes);
    for (int c = 0; c < 3; ++c) {
        double mean = k > 0.0 ? sum[3 * p + c] / k : 0.0;
        if (estimator == MvEstimator::Weighted && k > 0.0)
            mean = e[3 * p + c] / k + (w[p] > 0.0 ? lw[3 * p + c] / w[p] : 0.0); // the ratio of §5's MWIS
        const double var = k > 1.0 ? std::max(0.0, double(m2[3 * p + c])) / (k * (k - 1.0)) : 0.0;
        rgb[c] = float(mean);
        variance[c] = float(std::min(var, double(FLT_MAX)));
    }
}

void MvFilm::set_map(const std::vector<uint16_t> &crop) {
    const size_t w = size_t(width + 2 * margin);
    for (size_t y = 0; y < size_t(height); ++y)
        std::copy_n(crop.begin() + long(y * size_t(width)), width, map.begin() + long((y + size_t(margin)) * w + size_t(margin)));
    map_total = 0;
    for (uint16_t v : crop) map_total += v;
}

void MvFilm::save(StateWriter &out) const {
    out.put(uint32_t(estimator)), out.put(uint32_t(control_variate)), out.put(uint32_t(!e_sum.empty()));
    out.put(int32_t(width)), out.put(int32_t(height)), out.put(int32_t(margin));
    out.put(passes), out.put(level), out.put(nonfinite), out.put(map_total);
    out.put(sum), out.put(m2), out.put(w_sum), out.put(lw), out.put(e), out.put(w);
    out.put(e_sum), out.put(e_sq), out.put(s_sq), out.put(native), out.put(received), out.put(map);
}

void MvFilm::load(StateReader &in) {
    // The film was made for this render: the file's must have its kind and size.
    const uint32_t est = in.get<uint32_t>(), cv = in.get<uint32_t>(), adaptive = in.get<uint32_t>();
    const int32_t w_ = in.get<int32_t>(), h_ = in.get<int32_t>(), m_ = in.get<int32_t>();
    if (est != uint32_t(estimator) || cv != uint32_t(control_variate))
        throw StateError("the state was rendered with another multi-view estimator");
    if (w_ != width || h_ != height || m_ != margin)
        throw StateError("the state has a view of " + std::to_string(w_) + "x" + std::to_string(h_) + " pixels (margin " +
                         std::to_string(m_) + ") where this render has " + std::to_string(width) + "x" +
                         std::to_string(height) + " (margin " + std::to_string(margin) + ")");
    passes = in.get<uint32_t>(), level = in.get<double>(), nonfinite = in.get<uint64_t>(), map_total = in.get<uint64_t>();
    const size_t n = pixels();
    in.get(sum, sum.size()), in.get(m2, m2.size()), in.get(w_sum, n), in.get(lw, lw.size()), in.get(e, e.size());
    // The adaptive maps' statistics as the file has them (a range too short for maps has none).
    const size_t stats = adaptive ? n : 0;
    in.get(w, w.size()), in.get(e_sum, stats), in.get(e_sq, stats), in.get(s_sq, stats);
    in.get(native, n), in.get(received, n), in.get(map, map.size());
}

void MvFilm::merge(const MvFilm &o) {
    const double na = passes, nb = o.passes, n = na + nb;
    for (size_t i = 0; i < sum.size(); ++i) {
        const double delta = (nb > 0.0 ? o.sum[i] / nb : 0.0) - (na > 0.0 ? sum[i] / na : 0.0);
        m2[i] = float(double(m2[i]) + double(o.m2[i]) + (n > 0.0 ? delta * delta * na * nb / n : 0.0));
        sum[i] += o.sum[i];
    }
    for (size_t i = 0; i < lw.size(); ++i) lw[i] += o.lw[i], e[i] += o.e[i];
    for (size_t p = 0; p < pixels(); ++p) {
        w_sum[p] += o.w_sum[p];
        if (!w.empty()) w[p] += o.w[p];
        native[p] += o.native[p];
        received[p] = uint32_t(std::min<uint64_t>(uint64_t(received[p]) + o.received[p], UINT32_MAX));
    }
    // The adaptive statistics only where both have them (the maps are not used again).
    if (e_sum.size() == o.e_sum.size())
        for (size_t p = 0; p < e_sum.size(); ++p) e_sum[p] += o.e_sum[p], e_sq[p] += o.e_sq[p], s_sq[p] += o.s_sq[p];
    else
        e_sum.clear(), e_sq.clear(), s_sq.clear();
    passes += o.passes;
    nonfinite += o.nonfinite;
}

} // namespace mvpt
