// Pixel reconstruction filters. Path tracing samples them (filter importance sampling: each
// sample's film position is drawn from |h|, weighted by h / p, so that every sample lands in
// its own pixel, pbrt-v4 §8.8); multi-view path tracing, whose shared samples land anywhere,
// splats with h itself (eval_1d), so that both converge to the same image. h is the filter
// normalised to integrate to 1; filters with negative lobes (mitchell, catmullrom, lanczos)
// give signed weights.
#pragma once

#include "../core/math.h"
#include "../core/properties.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace mvpt {

class ReconstructionFilter : public Object {
public:
    /// Offset from the pixel centre, in pixels, distributed like |h(x, y)| / ∫|h|; `weight`
    /// is h / p of that offset: 1 for a non-negative filter, ±(∫|h_1d|)^2 otherwise.
    virtual Vec2f sample(Vec2f u, float &weight) const = 0;
    virtual float radius() const = 0;
    virtual bool is_box() const { return false; }
    /// h along one axis at offset d (pixels): the filter is separable, h(x, y) =
    /// eval_1d(x) eval_1d(y), and eval_1d integrates to 1.
    virtual float eval_1d(float d) const = 0;
    /// The largest |eval_1d|.
    virtual float peak_1d() const = 0;
    /// ∫|eval_1d|: 1 for a non-negative filter, more for one with negative lobes.
    virtual float abs_integral_1d() const { return 1.f; }
    bool has_negative_lobes() const { return abs_integral_1d() > 1.f; }
};

/// Separable filter tabulated per axis (1024 bins over [-radius, radius]), sampled by
/// inverting the CDF of |h|.
class TabulatedFilter : public ReconstructionFilter {
public:
    Vec2f sample(Vec2f u, float &weight) const override {
        const size_t bx = sample_bin(u.x), by = sample_bin(u.y);
        weight = std::copysign(1.f, m_h[bx]) * std::copysign(1.f, m_h[by]) * (m_abs_integral * m_abs_integral);
        return {bin_offset(bx, u.x), bin_offset(by, u.y)};
    }
    float radius() const override { return m_radius; }
    /// h per bin (the table's value over the bin's width).
    float eval_1d(float d) const override {
        const float x = (d + m_radius) * (float(m_h.size()) / (2.f * m_radius));
        return x >= 0.f && x < float(m_h.size()) ? m_h[size_t(x)] : 0.f;
    }
    float peak_1d() const override { return m_peak; }
    float abs_integral_1d() const override { return m_abs_integral; }
    /// h per bin over [-radius, radius] (eval_1d's table).
    const std::vector<float> &table() const { return m_h; }

protected:
    /// Tabulates f on [-radius, radius] at the bins' midpoints; f may be negative in places
    /// but must integrate to more than 0.
    template <typename F> void tabulate(float radius, F f) {
        m_radius = radius;
        const int n = 1024;
        std::vector<float> value(n);
        double sum = 0.0, abs_sum = 0.0;
        m_cdf.assign(n + 1, 0.f);
        for (int i = 0; i < n; ++i) {
            value[size_t(i)] = f(-radius + (float(i) + 0.5f) * 2.f * radius / float(n));
            m_cdf[size_t(i) + 1] = m_cdf[size_t(i)] + std::abs(value[size_t(i)]);
            sum += value[size_t(i)], abs_sum += std::abs(value[size_t(i)]);
        }
        for (float &c : m_cdf) c /= m_cdf[size_t(n)];
        // h = sign(f) p ∫|f| / ∫f, p the density of the bins sample_bin draws.
        m_abs_integral = float(abs_sum / sum);
        m_h.resize(size_t(n));
        m_peak = 0.f;
        for (size_t i = 0; i < size_t(n); ++i) {
            const float p = (m_cdf[i + 1] - m_cdf[i]) * float(n) / (2.f * radius);
            m_h[i] = value[i] < 0.f ? -p * m_abs_integral : p * m_abs_integral;
            m_peak = std::max(m_peak, std::abs(m_h[i]));
        }
    }
    /// The bin a uniform number u falls in by the CDF, and the offset it maps to in that bin.
    size_t sample_bin(float u) const;
    float bin_offset(size_t bin, float u) const;

    float m_radius = 0.5f;
    std::vector<float> m_cdf, m_h;
    float m_peak = 0.f, m_abs_integral = 1.f;
};

} // namespace mvpt
