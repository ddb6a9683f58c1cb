// Reconstruction filters: box, tent, gaussian (Mitsuba's parameters).
#include "../core/plugin.h"
#include "filter.h"

#include <algorithm>

namespace mvpt {

float TabulatedFilter::sample_1d(float u) const {
    size_t n = m_cdf.size() - 1;
    size_t i = size_t(std::upper_bound(m_cdf.begin() + 1, m_cdf.end() - 1, u) - m_cdf.begin()) - 1;
    float width = m_cdf[i + 1] - m_cdf[i];
    float t = width > 0.f ? (u - m_cdf[i]) / width : 0.5f;
    return -m_radius + (float(i) + t) * 2.f * m_radius / float(n);
}

namespace {

class BoxFilter final : public ReconstructionFilter {
public:
    Vec2f sample(Vec2f u) const override { return {u.x - 0.5f, u.y - 0.5f}; }
    float radius() const override { return 0.5f; }
    bool is_box() const override { return true; }
    float eval_1d(float d) const override { return d >= -0.5f && d < 0.5f ? 1.f : 0.f; }
    float peak_1d() const override { return 1.f; }
};

class TentFilter final : public TabulatedFilter {
public:
    explicit TentFilter(const Properties &p) {
        float r = p.get_float("radius", 1.f);
        if (!(r > 0.f)) p.fail("radius", "tent 'radius' must be > 0");
        tabulate(r, [r](float x) { return std::max(0.f, 1.f - std::abs(x) / r); });
    }
};

/// Gaussian minus its value at the radius, radius = 4 stddev (Mitsuba 3's gaussian).
class GaussianFilter final : public TabulatedFilter {
public:
    explicit GaussianFilter(const Properties &p) {
        float sd = p.get_float("stddev", 0.5f);
        if (!(sd > 0.f)) p.fail("stddev", "gaussian 'stddev' must be > 0");
        float r = 4.f * sd, alpha = -1.f / (2.f * sd * sd), bias = std::exp(alpha * r * r);
        tabulate(r, [=](float x) { return std::max(0.f, std::exp(alpha * x * x) - bias); });
    }
};

} // namespace

MVPT_REGISTER_PLUGIN("rfilter", "box", [](const Properties &, const LoadContext &) { return std::make_shared<BoxFilter>(); });
MVPT_REGISTER_PLUGIN("rfilter", "tent", [](const Properties &p, const LoadContext &) { return std::make_shared<TentFilter>(p); });
MVPT_REGISTER_PLUGIN("rfilter", "gaussian", [](const Properties &p, const LoadContext &) { return std::make_shared<GaussianFilter>(p); });

} // namespace mvpt
