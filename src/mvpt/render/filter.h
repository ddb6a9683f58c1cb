// Pixel reconstruction filters, used by filter importance sampling: each
// sample's film position is drawn from the filter, so every sample lands in
// its own pixel with unit weight (pbrt-v4 §8.8) and no splatting is needed.
#pragma once

#include "../core/math.h"
#include "../scene/properties.h"

#include <vector>

namespace mvpt {

class ReconstructionFilter : public Object {
public:
    /// Offset from the pixel centre, in pixels, distributed like the filter.
    virtual Vec2f sample(Vec2f u) const = 0;
    virtual float radius() const = 0;
    virtual bool is_box() const { return false; }
};

/// Separable filter sampled by inverting a tabulated 1D CDF per axis.
class TabulatedFilter : public ReconstructionFilter {
public:
    Vec2f sample(Vec2f u) const override { return {sample_1d(u.x), sample_1d(u.y)}; }
    float radius() const override { return m_radius; }

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
    }
    float sample_1d(float u) const;

    float m_radius = 0.5f;
    std::vector<float> m_cdf;
};

} // namespace mvpt
