// Reconstruction filters: box, tent, gaussian, mitchell, catmullrom, lanczos (Mitsuba 3's
// definitions and parameters).
#include "../core/plugin.h"
#include "filter.h"

#include <algorithm>

namespace mvpt {

size_t TabulatedFilter::sample_bin(float u) const {
    return size_t(std::upper_bound(m_cdf.begin() + 1, m_cdf.end() - 1, u) - m_cdf.begin()) - 1;
}

float TabulatedFilter::bin_offset(size_t i, float u) const {
    const float width = m_cdf[i + 1] - m_cdf[i];
    const float t = width > 0.f ? (u - m_cdf[i]) / width : 0.5f;
    return -m_radius + (float(i) + t) * 2.f * m_radius / float(m_cdf.size() - 1);
}

namespace {

class BoxFilter final : public ReconstructionFilter {
public:
    Vec2f sample(Vec2f u, float &weight) const override {
        weight = 1.f;
        return {u.x - 0.5f, u.y - 0.5f};
    }
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

/// Mitchell-Netravali cubic of parameters B and C on |x| < 2 [Mitchell and Netravali 1988].
float mitchell_netravali(float x, float b, float c) {
    x = std::abs(x);
    const float x2 = x * x, x3 = x2 * x;
    if (x < 1.f) return ((12.f - 9.f * b - 6.f * c) * x3 + (-18.f + 12.f * b + 6.f * c) * x2 + (6.f - 2.f * b)) / 6.f;
    if (x < 2.f)
        return ((-b - 6.f * c) * x3 + (6.f * b + 30.f * c) * x2 + (-12.f * b - 48.f * c) * x + (8.f * b + 24.f * c)) / 6.f;
    return 0.f;
}

/// Mitsuba 3's mitchell: radius 2, parameters `B` and `C` (1/3 each).
class MitchellFilter final : public TabulatedFilter {
public:
    explicit MitchellFilter(const Properties &p) {
        const float b = p.get_float("B", 1.f / 3.f), c = p.get_float("C", 1.f / 3.f);
        // ∫ over [-2, 2] is 1 for every B and C (the table normalises anyway).
        if (!std::isfinite(b)) p.fail("B", "mitchell 'B' must be finite");
        if (!std::isfinite(c)) p.fail("C", "mitchell 'C' must be finite");
        tabulate(2.f, [=](float x) { return mitchell_netravali(x, b, c); });
    }
};

/// Mitsuba 3's catmullrom: the Mitchell-Netravali cubic with B = 0, C = 1/2.
class CatmullRomFilter final : public TabulatedFilter {
public:
    explicit CatmullRomFilter(const Properties &) {
        tabulate(2.f, [](float x) { return mitchell_netravali(x, 0.f, 0.5f); });
    }
};

/// Mitsuba 3's lanczos: sinc(x) sinc(x / lobes) on |x| < lobes (`lobes`, 3).
class LanczosFilter final : public TabulatedFilter {
public:
    explicit LanczosFilter(const Properties &p) {
        const float r = float(p.get_int_in("lobes", 3, 1, 64));
        tabulate(r, [r](float x) {
            const float a = Pi * std::abs(x), b = a / r;
            return a < 1e-6f ? 1.f : std::sin(a) * std::sin(b) / (a * b);
        });
    }
};

} // namespace

MVPT_REGISTER_PLUGIN("rfilter", "box", [](const Properties &, const LoadContext &) { return std::make_shared<BoxFilter>(); });
MVPT_REGISTER_PLUGIN("rfilter", "tent", [](const Properties &p, const LoadContext &) { return std::make_shared<TentFilter>(p); });
MVPT_REGISTER_PLUGIN("rfilter", "gaussian", [](const Properties &p, const LoadContext &) { return std::make_shared<GaussianFilter>(p); });
MVPT_REGISTER_PLUGIN("rfilter", "mitchell", [](const Properties &p, const LoadContext &) { return std::make_shared<MitchellFilter>(p); });
MVPT_REGISTER_PLUGIN("rfilter", "catmullrom", [](const Properties &p, const LoadContext &) { return std::make_shared<CatmullRomFilter>(p); });
MVPT_REGISTER_PLUGIN("rfilter", "lanczos", [](const Properties &p, const LoadContext &) { return std::make_shared<LanczosFilter>(p); });

} // namespace mvpt
