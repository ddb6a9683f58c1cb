// Piecewise-constant distributions (1D discrete and 2D lat-long style).
#pragma once

#include "math.h"

#include <algorithm>
#include <vector>

namespace mvpt {

/// Discrete distribution over n weighted items (its CDF in double precision).
class DiscreteDistribution {
public:
    DiscreteDistribution() = default;
    explicit DiscreteDistribution(const std::vector<float> &weights) { build(weights); }

    void build(const std::vector<float> &weights) {
        m_cdf.assign(weights.size() + 1, 0.0);
        for (size_t i = 0; i < weights.size(); ++i) m_cdf[i + 1] = m_cdf[i] + std::max(0.f, weights[i]);
        m_sum = m_cdf.back();
        if (m_sum > 0)
            for (double &c : m_cdf) c /= m_sum;
        // Guide table [Chen & Asau 1974, "On generating random variates from an empirical
        // distribution"]: for u in [j/g, (j+1)/g), the search starts at guide[j], the number
        // of interior CDF entries <= j/g, and scans a few entries (about 4 on average).
        m_guide.clear();
        size_t count = m_cdf.size() >= 2 ? m_cdf.size() - 2 : 0;
        if (count > ShortTable) {
            size_t g = count / 4 + 1, i = 0;
            m_guide.resize(g);
            for (size_t j = 0; j < g; ++j) {
                double t = double(j) / double(g);
                while (i < count && m_cdf[i + 1] <= t) ++i;
                m_guide[j] = uint32_t(i);
            }
        }
    }
    size_t size() const { return m_cdf.empty() ? 0 : m_cdf.size() - 1; }
    double sum() const { return m_sum; }
    float pmf(size_t i) const { return float(m_cdf[i + 1] - m_cdf[i]); }

    /// Index with probability pmf(i); `u` is rescaled to [0, 1) for reuse.
    size_t sample(float u, float *pmf_out = nullptr, float *u_reuse = nullptr) const {
        return sample_from(search_start(u), u, pmf_out, u_reuse);
    }

    /// `sample` in two steps, for staged loops over many u's whose table reads overlap: where
    /// the search for `u` starts (a guide-table entry; 0 for short tables) ...
    size_t search_start(float u) const {
        if (m_guide.empty()) return 0;
        size_t g = m_guide.size();
        double x = double(u) * double(g);
        return m_guide[x > 0.0 ? std::min(size_t(x), g - 1) : 0];
    }
    /// ... and the rest of `sample` from there (`start` = search_start(u)).
    size_t sample_from(size_t start, float u, float *pmf_out = nullptr, float *u_reuse = nullptr) const {
        // i = number of interior CDF entries <= u (std::upper_bound's answer). Short tables
        // (an emitter's few triangles): a branch-free count, as each comparison is a coin
        // flip for a random u. Long ones (envmap rows): the guide table, then a short scan;
        // a binary search's chain of dependent cache misses cost more (matpreview's envmap).
        const double *interior = m_cdf.data() + 1, du = double(u);
        size_t count = m_cdf.size() - 2, i = start;
        if (count <= ShortTable) {
            for (size_t j = 0; j < count; ++j) i += interior[j] <= du;
        } else {
            while (i > 0 && interior[i - 1] > du) --i; // only if j/g rounded above u
            while (i < count && interior[i] <= du) ++i;
        }
        // Skip zero-probability items that upper_bound can land on at their boundary.
        // (The rarely true test first: it predicts well; m_cdf has size() + 1 entries.)
        while (m_cdf[i + 1] == m_cdf[i] && i + 1 < size()) ++i;
        float p = pmf(i);
        if (pmf_out) *pmf_out = p;
        if (u_reuse) *u_reuse = p > 0 ? std::min(float((u - m_cdf[i]) / p), OneMinusEpsilon) : 0.f;
        return i;
    }
    /// The CDF entries a search from `start` reads first (to prefetch them).
    const double *search_data(size_t start) const { return m_cdf.data() + start; }

private:
    /// Tables up to this many interior CDF entries are searched by a plain count.
    static constexpr size_t ShortTable = 16;

    std::vector<double> m_cdf;
    std::vector<uint32_t> m_guide;
    double m_sum = 0;
};

/// Piecewise-constant 2D density on [0,1]^2 over a w x h grid: marginal over
/// rows, conditional within each row (pbrt-v4 PiecewiseConstant2D).
class Distribution2D {
public:
    Distribution2D() = default;
    Distribution2D(const std::vector<float> &values, int w, int h) : m_w(w), m_h(h) {
        m_rows.resize(h);
        std::vector<float> row_sums(h);
        for (int y = 0; y < h; ++y) {
            std::vector<float> row(values.begin() + size_t(y) * w, values.begin() + size_t(y + 1) * w);
            m_rows[y].build(row);
            row_sums[y] = float(m_rows[y].sum());
        }
        m_marginal.build(row_sums);
    }
    /// Point in [0,1)^2 with density `pdf` (w.r.t. area of the unit square).
    Vec2f sample(Vec2f u, float *pdf) const {
        float pm, pc, uy, ux;
        size_t y = m_marginal.sample(u.y, &pm, &uy);
        size_t x = m_rows[y].sample(u.x, &pc, &ux);
        *pdf = pm * pc * float(m_w) * float(m_h);
        return {(float(x) + ux) / float(m_w), (float(y) + uy) / float(m_h)};
    }
    float pdf(Vec2f p) const {
        int x = std::clamp(int(p.x * m_w), 0, m_w - 1), y = std::clamp(int(p.y * m_h), 0, m_h - 1);
        return m_marginal.pmf(y) * m_rows[y].pmf(x) * float(m_w) * float(m_h);
    }
    bool empty() const { return m_marginal.sum() <= 0; }

private:
    int m_w = 0, m_h = 0;
    std::vector<DiscreteDistribution> m_rows;
    DiscreteDistribution m_marginal;
};

} // namespace mvpt
