// The film of a view (film.h): estimates added and folded, developed, saved, loaded and merged.
#include "film.h"

#include "../integrators/multiview/mv_estimator.h"

#include "render_state.h"

#include <algorithm>
#include <cfloat>
#include <climits>

namespace mvpt {

Film::Film(int width_, int height_) : width(width_), height(height_) {
    const size_t pixels = size_t(width) * size_t(height);
    count.assign(pixels, 0), sum.assign(3 * pixels, 0.0), m2.assign(3 * pixels, 0.f);
}

Film::Film(int width_, int height_, int margin_, MvEstimator est, bool cv, bool adaptive) : Film(width_, height_) {
    estimator = est, control_variate = cv, margin = margin_;
    const size_t pixels = count.size();
    w_sum.assign(pixels, 0.f);
    if (estimator == MvEstimator::Weighted) lw.assign(3 * pixels, 0.0), e.assign(3 * pixels, 0.0), w.assign(pixels, 0.0);
    if (adaptive) e_sum.assign(pixels, 0.f), e_sq.assign(pixels, 0.f), s_sq.assign(pixels, 0.f);
    native.assign(pixels, 0), received.assign(pixels, 0);
    map.assign(size_t(width + 2 * margin) * size_t(height + 2 * margin), 1);
    map_total = pixels;
}

size_t Film::bytes_per_pixel(bool multiview, MvEstimator estimator, bool adaptive) {
    size_t b = sizeof(uint32_t) + 3 * sizeof(double) + 3 * sizeof(float);
    if (!multiview) return b;
    b += sizeof(float) + 2 * sizeof(uint32_t) + sizeof(uint16_t);
    if (estimator == MvEstimator::Weighted) b += 7 * sizeof(double);
    if (adaptive) b += 3 * sizeof(float);
    return b;
}

void Film::add_pass(size_t p, const MvPassEstimate &est, double wt) {
    if (estimator == MvEstimator::Weighted) {
        for (int c = 0; c < 3; ++c) lw[3 * p + c] += wt * est.lw[c], e[3 * p + c] += wt * est.e[c];
        w[p] += wt * est.w;
    }
    add(p, est.v, wt);
    w_sum[p] += float(wt * est.w);
    if (!e_sum.empty()) { // the adaptive maps' statistics
        const double s = (est.v[0] / 3.0 + est.v[1] / 3.0 + est.v[2] / 3.0) - est.e_mean;
        e_sum[p] += float(est.e_mean);
        e_sq[p] += float(est.e_mean * est.e_mean);
        s_sq[p] += float(s * s);
    }
}

namespace {
/// The ratio (W*L + E) / W of a pass's sums (0 without contributions, or where W <= min_w): a
/// pixel's estimate from that pass alone in which how many contributions landed cancels. With
/// a non-negative filter it is a weighted mean of the contributions; where the filter has
/// negative lobes, W near 0 makes it explode (the other pass's variance with `lanczos`, 16
/// spp: ×10), so it is not used there: any beta independent of the pass keeps it unbiased.
void pass_ratio(const double v[3], double w, double min_w, double out[3]) {
    for (int c = 0; c < 3; ++c) out[c] = w > min_w ? v[c] / w : 0.0;
}
} // namespace

void Film::fold(MvPassFilm &pass, uint32_t offset, size_t begin, size_t end, double scale, double wt) {
    const bool weighted = estimator == MvEstimator::Weighted;
    for (size_t p = begin; p < end; ++p) {
        const SplatEntry t = take_pass(pass, offset, p);
        if (holding) { // the first two passes, each with the other's ratio as beta
            MvPassEstimate first = take_held(p), second = mv_pass_estimate(t, estimator, nullptr, scale);
            double beta_first[3], beta_second[3];
            const double min_w = signed_filter ? SignedRatioMinW : 0.0;
            pass_ratio(first.v, first.w, min_w, beta_first);
            pass_ratio(second.v, second.w, min_w, beta_second);
            for (int c = 0; c < 3; ++c) {
                first.v[c] += beta_second[c] * (1.0 - first.w);
                second.v[c] += beta_first[c] * (1.0 - second.w);
            }
            add_pass(p, first, 1.0);
            add_pass(p, second, wt);
            continue;
        }
        double beta[3]; // the mean of the earlier passes
        const bool cv = !weighted && control_variate && count[p] > 0;
        if (cv)
            for (int c = 0; c < 3; ++c) beta[c] = sum[3 * p + c] / weight(p);
        add_pass(p, mv_pass_estimate(t, estimator, cv ? beta : nullptr, scale), wt);
    }
}

SplatEntry Film::take_pass(MvPassFilm &pass, uint32_t offset, size_t p) {
    const SplatEntry t = pass.take(offset + uint32_t(p));
    received[p] = uint32_t(std::min<uint64_t>(uint64_t(received[p]) + t.count, UINT32_MAX));
    native[p] += n(p);
    return t;
}

MvPassEstimate Film::take_held(size_t p) {
    MvPassEstimate est;
    for (int c = 0; c < 3; ++c) est.v[c] = sum[3 * p + c], sum[3 * p + c] = 0.0;
    est.w = w_sum[p], w_sum[p] = 0.f;
    if (!e_sum.empty()) est.e_mean = e_sum[p], e_sum[p] = 0.f;
    return est;
}

void Film::hold(MvPassFilm &pass, uint32_t offset, size_t begin, size_t end) {
    for (size_t p = begin; p < end; ++p) {
        const MvPassEstimate est = mv_pass_estimate(take_pass(pass, offset, p), estimator, nullptr);
        for (int c = 0; c < 3; ++c) sum[3 * p + c] = est.v[c];
        w_sum[p] = float(est.w);
        if (!e_sum.empty()) e_sum[p] = float(est.e_mean);
    }
}

void Film::release(size_t begin, size_t end) {
    for (size_t p = begin; p < end; ++p) add_pass(p, take_held(p), 1.0);
}

void Film::develop(size_t p, float rgb[3], float variance[3]) const {
    // k estimates of total weight wk, each weighted by its precision: the squared deviations
    // estimate (k - 1) times the variance of a weight-1 estimate, and the mean's is that over wk.
    const double k = double(count[p]), wk = weight(p);
    for (int c = 0; c < 3; ++c) {
        double mean = k > 0.0 ? sum[3 * p + c] / wk : 0.0;
        if (estimator == MvEstimator::Weighted && k > 0.0)
            mean = e[3 * p + c] / wk + (w[p] > 0.0 ? lw[3 * p + c] / w[p] : 0.0); // the ratio of §5's MWIS
        const double var = k > 1.0 ? std::max(0.0, double(m2[3 * p + c])) / (wk * (k - 1.0)) : 0.0;
        rgb[c] = float(mean);
        variance[c] = float(std::min(var, double(FLT_MAX)));
    }
}

void Film::set_map(const std::vector<uint16_t> &crop) {
    const size_t w = size_t(width + 2 * margin);
    for (size_t y = 0; y < size_t(height); ++y)
        std::copy_n(crop.begin() + long(y * size_t(width)), width, map.begin() + long((y + size_t(margin)) * w + size_t(margin)));
    map_total = 0;
    for (uint16_t v : crop) map_total += v;
}

void Film::save(StateWriter &out) const {
    out.put(int32_t(width)), out.put(int32_t(height)), out.put(nonfinite), out.put(short_weight);
    out.put(count), out.put(sum), out.put(m2);
    if (!multiview()) return;
    out.put(uint32_t(estimator)), out.put(uint32_t(control_variate)), out.put(uint32_t(!e_sum.empty()));
    out.put(int32_t(margin)), out.put(level), out.put(map_total);
    out.put(w_sum), out.put(lw), out.put(e), out.put(w);
    out.put(e_sum), out.put(e_sq), out.put(s_sq), out.put(native), out.put(received), out.put(map);
    out.put(uint32_t(holding));
}

void Film::load(StateReader &in) {
    // The film was made for this render: the file's must have its kind and size.
    const int32_t w_ = in.get<int32_t>(), h_ = in.get<int32_t>();
    if (w_ != width || h_ != height)
        throw StateError("the state has a view of " + std::to_string(w_) + "x" + std::to_string(h_) +
                         " pixels where this render has " + std::to_string(width) + "x" + std::to_string(height));
    nonfinite = in.get<uint64_t>(), short_weight = in.get<double>();
    const size_t n = pixels();
    in.get(count, n), in.get(sum, 3 * n), in.get(m2, 3 * n);
    if (!multiview()) return;
    const uint32_t est = in.get<uint32_t>(), cv = in.get<uint32_t>(), adaptive = in.get<uint32_t>();
    const int32_t m_ = in.get<int32_t>();
    if (est != uint32_t(estimator) || cv != uint32_t(control_variate))
        throw StateError("the state was rendered with another multi-view estimator");
    if (m_ != margin)
        throw StateError("the state has a view whose filter reaches " + std::to_string(m_) + " pixels where this render's reaches " +
                         std::to_string(margin));
    level = in.get<double>(), map_total = in.get<uint64_t>();
    in.get(w_sum, n), in.get(lw, lw.size()), in.get(e, e.size()), in.get(w, w.size());
    // The adaptive maps' statistics as the file has them (a range too short for maps has none).
    const size_t stats = adaptive ? n : 0;
    in.get(e_sum, stats), in.get(e_sq, stats), in.get(s_sq, stats);
    in.get(native, n), in.get(received, n), in.get(map, map.size());
    holding = in.get<uint32_t>() != 0;
}

namespace {

template <typename T> bool all_finite_values(const std::vector<T> &v) {
    return std::all_of(v.begin(), v.end(), [](T x) { return std::isfinite(double(x)); });
}

} // namespace

void Film::check_loaded(int passes, int max_native) const {
    // A state's checksum guards against damage, not against a file made up to pass it: what it
    // asks of the render must be what `passes` passes can have produced.
    auto refuse = [](const std::string &what) { throw StateError("the state is not one a render wrote: " + what); };
    if (!all_finite_values(sum) || !all_finite_values(m2)) refuse("a pixel's sums are not finite");
    if (!(short_weight >= 0.0 && short_weight <= double(passes))) refuse("its passes' weights are out of range");
    if (!multiview()) return;
    if (!all_finite_values(w_sum) || !all_finite_values(lw) || !all_finite_values(e) || !all_finite_values(w) ||
        !all_finite_values(e_sum) || !all_finite_values(e_sq) || !all_finite_values(s_sq) || !(level >= 0.0) ||
        !std::isfinite(level))
        refuse("a pixel's multi-view sums are not finite");
    if (std::any_of(count.begin(), count.end(), [&](uint32_t k) { return k > uint32_t(passes); }))
        refuse("a pixel holds more passes than the state has");
    if (std::any_of(map.begin(), map.end(), [&](uint16_t n) { return n > max_native; }))
        refuse("its sample map asks for more than " + std::to_string(max_native) + " samples in a pixel");
    const uint64_t most = uint64_t(passes) * uint64_t(std::max(max_native, 1));
    if (std::any_of(native.begin(), native.end(), [&](uint32_t n) { return n > most; }))
        refuse("a pixel has taken more samples than its passes can take");
}

void Film::merge(const Film &o) {
    for (size_t p = 0; p < pixels(); ++p) {
        // Chan et al.'s combination, with the two films' total weights.
        const double na = count[p] ? weight(p) : 0.0, nb = o.count[p] ? o.weight(p) : 0.0, n = na + nb;
        for (size_t i = 3 * p; i < 3 * p + 3; ++i) {
            const double delta = (nb > 0.0 ? o.sum[i] / nb : 0.0) - (na > 0.0 ? sum[i] / na : 0.0);
            m2[i] = float(double(m2[i]) + double(o.m2[i]) + (n > 0.0 ? delta * delta * na * nb / n : 0.0));
            sum[i] += o.sum[i];
        }
        count[p] += o.count[p];
    }
    nonfinite += o.nonfinite;
    short_weight += o.short_weight;
    if (!multiview()) return;
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
}

} // namespace mvpt
