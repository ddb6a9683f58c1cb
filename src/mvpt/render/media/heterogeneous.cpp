// The `heterogeneous` medium: sigma_t and albedo given as volumes (grids or constants), times
// `scale`. Free flights by delta tracking [Woodcock 1965] against local majorants: the
// extinction's majorant grid, refined along each ray (MajorantWalk). The optical depth to the
// next tentative collision, -ln(1 - u), is spent piece by piece (majorant times length; a piece
// of majorant 0 costs nothing). In RGB as spectral tracking: a tentative collision is real with
// probability mean(sigma_t) / majorant and weights each channel by what its own collision
// density asks (sigma_s / mean(sigma_t) when real, (majorant - sigma_t) / (majorant -
// mean(sigma_t)) when null; both at most 3), so every channel stays unbiased [Kutz et al.
// 2017]. Transmittance by ratio tracking against the same majorants [Novák et al. 2014],
// with Russian roulette once it is small.
// Outside the extinction volume's box the medium is empty.
#include "../../core/plugin.h"
#include "../majorant_walk.h"
#include "../medium.h"
#include "../volume.h"

#include <atomic>

namespace mvpt {

namespace {

/// Tentative collisions one flight may take before it is given up (weight 0, counted): a
/// guard against a walk that would not end in reasonable time.
constexpr int MaxFlightCollisions = 1 << 22;

class Heterogeneous final : public Medium {
public:
    explicit Heterogeneous(const Properties &props) {
        read_common(props);
        m_scale = props.get_float("scale", 1.f);
        if (!(m_scale >= 0.f) || !std::isfinite(m_scale)) props.fail("scale", "scale must be finite and >= 0");
        m_sigma_t = get_volume(props, "sigma_t", Color3f(1.f), SpectrumUse::Unbounded);
        m_albedo = get_volume(props, "albedo", Color3f(0.75f), SpectrumUse::Reflectance);
        check_volume_range(props, "sigma_t", *m_sigma_t, 0.f, Infinity, "an extinction coefficient");
        check_volume_range(props, "albedo", *m_albedo, 0.f, 1.f, "the scattering share of extinction");
        const float majorant = m_sigma_t->max_value() * m_scale;
        if (!std::isfinite(majorant) || majorant < 0.f) props.fail("sigma_t", "the extinction must be finite and >= 0");
        m_majorants = m_sigma_t->majorant_grid();
        m_majorants.scale(m_scale);
        m_bounds = m_sigma_t->bounds();
        m_empty = !(majorant > 0.f);
    }

    MediumSample sample(const Ray &ray, float t_surface, float u, RandomStream &rs) const override {
        MediumSample ms;
        ms.t = t_surface;
        float t0, t1;
        if (m_empty || !clip(ray, t_surface, t0, t1)) return ms;
        Spectrum w(1.f);
        const Walk end = walk(ray, t0, t1, u, rs, [&](const MajorantPiece &piece, float s) {
            const float t = piece.point(s);
            const Point3f p = ray.at(t);
            const Spectrum sigma_t = extinction(p, piece.bound);
            const float mean = sigma_t.mean();
            if (!(piece.bound > mean) || rs.next_1d() * piece.bound < mean) {
                ms.scattered = true, ms.t = t;
                ms.weight = w * sigma_t * m_albedo->eval(p) * (1.f / mean);
                return false;
            }
            w *= (Spectrum(piece.bound) - sigma_t) * (1.f / (piece.bound - mean));
            return true;
        });
        if (end == Walk::GaveUp) ms.weight = Spectrum(0.f);
        else if (end == Walk::Ended) ms.weight = w;
        return ms;
    }

    Spectrum transmittance(const Ray &ray, float t, RandomStream &rs) const override {
        float t0, t1;
        if (m_empty || !clip(ray, t, t0, t1)) return Spectrum(1.f);
        Spectrum tr(1.f);
        const Walk end = walk(ray, t0, t1, rs.next_1d(), rs, [&](const MajorantPiece &piece, float s) {
            tr *= Spectrum(1.f) - extinction(ray.at(piece.point(s)), piece.bound) * (1.f / piece.bound);
            return roulette(tr, rs);
        });
        return end == Walk::Ended ? tr : Spectrum(0.f);
    }

    uint64_t flights_given_up() const override { return m_given_up.load(std::memory_order_relaxed); }

private:
    /// The part [t0, t1) of [0, t_max) inside the extinction's box; false when empty.
    bool clip(const Ray &ray, float t_max, float &t0, float &t1) const {
        t0 = 0.f, t1 = t_max;
        for (int a = 0; a < 3; ++a) {
            const float inv = 1.f / ray.d[a];
            float near = (m_bounds.min[a] - ray.o[a]) * inv, far = (m_bounds.max[a] - ray.o[a]) * inv;
            if (near > far) std::swap(near, far);
            if (!std::isnan(near)) t0 = std::max(t0, near);
            if (!std::isnan(far)) t1 = std::min(t1, far);
        }
        return t0 < t1;
    }

    /// sigma_t at `p`, each channel at most the local majorant `bound` (only a point within
    /// rounding of a majorant cell's face can exceed it).
    Spectrum extinction(Point3f p, float bound) const {
        const Spectrum s = m_sigma_t->eval(p) * m_scale;
        return {std::min(s.r, bound), std::min(s.g, bound), std::min(s.b, bound)};
    }

    /// Russian roulette on a ratio-tracking estimate that has fallen below 1/4: it goes on
    /// with probability 4 max(tr), divided by it, so that it ends in dense media (a product of
    /// factors of at most 1/2 would otherwise sit on the smallest float), as pbrt-v4 does.
    static bool roulette(Spectrum &tr, RandomStream &rs) {
        const float q = tr.max_value();
        if (q >= 0.25f) return true;
        if (!(rs.next_1d() < 4.f * q)) return false;
        tr *= 1.f / (4.f * q);
        return true;
    }

    enum class Walk { Ended, Stopped, GaveUp };

    /// The tentative collisions along `ray` over [t0, t1): optical depths -ln(1 - u) (the
    /// first from u0, the next from `rs` after each collision) spent piece by piece against the
    /// local majorants; `collide(piece, s)` at each, at distance s into its piece, false to
    /// stop there. A walk past MaxFlightCollisions gives up, counted (flights_given_up).
    template <typename Collide>
    Walk walk(const Ray &ray, float t0, float t1, float u0, RandomStream &rs, Collide &&collide) const {
        float tau = -std::log1p(-u0); // optical depth to the next tentative collision
        int collisions = 0;
        MajorantWalk pieces(m_majorants, *m_sigma_t, m_scale, ray, t0, t1);
        for (MajorantPiece piece; pieces.next(piece);) {
            if (!(piece.bound > 0.f)) continue;
            for (float s = 0.f;;) {
                const float room = (piece.length - s) * piece.bound;
                if (!(tau < room)) {
                    tau -= room;
                    break;
                }
                s += tau / piece.bound;
                if (++collisions > MaxFlightCollisions) {
                    m_given_up.fetch_add(1, std::memory_order_relaxed);
                    return Walk::GaveUp;
                }
                if (!collide(piece, s)) return Walk::Stopped;
                tau = -std::log1p(-rs.next_1d());
            }
        }
        return Walk::Ended;
    }

    std::shared_ptr<Volume> m_sigma_t, m_albedo;
    float m_scale = 1.f;
    bool m_empty = true;
    MajorantGrid m_majorants;
    BoundingBox m_bounds;
    mutable std::atomic<uint64_t> m_given_up{0};
};

} // namespace

MVPT_REGISTER_PLUGIN("medium", "heterogeneous", [](const Properties &p, const LoadContext &) {
    return std::make_shared<Heterogeneous>(p);
});

} // namespace mvpt
