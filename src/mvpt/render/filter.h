// Pixel reconstruction filters. Path tracing samples them (filter importance sampling:
// each sample's film position is drawn from the filter, so every sample lands in its own
// pixel with unit weight, pbrt-v4 §8.8); multi-view path tracing, whose shared samples land
// anywhere, splats with the density that sampling draws from (eval_1d), so that both
// converge to the same image.
#pragma once

#include "../core/math.h"
#include "../core/properties.h"

#include <algorithm>
#include <vector>

namespace mvpt {

class ReconstructionFilter : public Object {
public:
    /// Offset from the pixel centre, in pixels, distributed like the filter.
    virtual Vec2f sample(Vec2f u) const = 0;
    virtual float radius() const = 0;
    virtual bool is_box() const { return false; }
    /// Density of one axis of `sample`'s offsets at offset d (pixels); the filter is
    /// separable, h(x, y) = eval_1d(x) eval_1d(y), and integrates to 1.
    virtual float eval_1d(float d) const = 0;
    /// The largest value of eval_1d.
    virtual float peak_1d() const = 0;
};

/// Separable filter sampled by inverting a tabulated 1D CDF per axis.
class TabulatedFilter : public ReconstructionFilter {
public:
    Vec2f sample(Vec2f u) const override { return {sample_1d(u.x), sample_1d(u.y)}; }
    float radius() const override { return m_radius; }
    /// The piecewise-constant density that sample_1d inverts: a bin's probability over its width.
    float eval_1d(float d) const override {
        const float x = (d + m_radius) * (float(m_pdf.size()) / (2.f * m_radius));
        return x >= 0.f && x < float(m_pdf.size()) ? m_pdf[size_t(x)] : 0.f;
    }
    float peak_1d() const override { return m_peak; }
    /// The density per bin over [-radius, radius] (eval_1d's table).
    const std::vector<float> &pdf_table() const { return m_pdf; }

protected:
    /// Tabulate f on [-radius, radius]; f must be non-negative.
    template <typename F> void tabulate(float radius, F f) {
        m_radius = radius;
        const int n = 1024;
        m_cdf.assign(n + 1, 0.f);
        for (int i = 0; i < n; ++i) {
            float x = -radius + (i + 0.5f) * 2.f * radius / n;
            m_cdf[i + 1] = m_cdf[i] + std::max(0.f, f(x));
        }
        for (float &c : m_cdf) c /= m_cdf[n];
        m_pdf.resize(n);
        m_peak = 0.f;
        for (int i = 0; i < n; ++i) m_peak = std::max(m_peak, m_pdf[i] = (m_cdf[i + 1] - m_cdf[i]) * float(n) / (2.f * radius));
    }
    float sample_1d(float u) const;

    float m_radius = 0.5f;
    std::vector<float> m_cdf, m_pdf;
    float m_peak = 0.f;
};

} // namespace mvpt
