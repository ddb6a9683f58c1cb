// Participating media (Mitsuba 3's "medium"): extinction sigma_t and single-scattering
// albedo along rays, and a phase function. A medium fills the inside or outside of the
// shapes that name it (`interior` / `exterior`) or surrounds a sensor (`medium`); a ray
// changes medium only where it crosses such a shape (Mitsuba's rule: no nesting stack).
//
// In RGB the extinction differs per channel. Free-flight distances are drawn with one
// channel chosen uniformly and weighted by the mixture of the three channels' densities
// (one-sample MIS over channels, the "hero wavelength" scheme of pbrt-v4): unbiased for every
// channel, and bounded where Mitsuba's weight by the chosen channel alone is not.
#pragma once

#include "../core/math.h"
#include "../core/sampler.h"
#include "../core/properties.h"
#include "phase.h"

#include <memory>

namespace mvpt {

/// Outcome of free-flight sampling along a ray.
struct MediumSample {
    /// True: the ray scatters at distance t inside the medium; false: it reaches the surface.
    bool scattered = false;
    float t = Infinity;
    /// What the path throughput is multiplied by: Tr(t) sigma_s(t) / pdf(t) for a scattering,
    /// Tr(t_surface) / P(no scattering before t_surface) otherwise.
    Spectrum weight{1.f};
};

class Medium : public Object {
public:
    /// Free-flight sampling along `ray` (unit direction, from its origin) before the next
    /// surface at `t_surface` (may be infinite); `u` picks the channel and the distance,
    /// `rs` serves estimators that need more numbers.
    virtual MediumSample sample(const Ray &ray, float t_surface, float u, RandomStream &rs) const = 0;
    /// A distance past which `sample` with this `u` surely does not scatter, known before the
    /// next surface is (homogeneous media: the distance it draws): the surface query can stop
    /// there, which in dense media is most of its cost. Infinite when unknown.
    virtual float free_flight_bound(float u) const { (void)u; return Infinity; }
    /// Transmittance along `ray` over [0, t) (an unbiased estimate where it is not analytic).
    virtual Spectrum transmittance(const Ray &ray, float t, RandomStream &rs) const = 0;
    /// Forced scattering: a distance in [0, t_end) drawn from the free-flight density
    /// conditioned on scattering there, its weight Tr(t) sigma_s(t) / pdf(t | t < t_end) in
    /// `out` (scattered false: no scattering is possible). False where the medium cannot
    /// draw it (its density has no closed form).
    virtual bool sample_within(const Ray &ray, float t_end, float u, MediumSample &out) const {
        (void)ray, (void)t_end, (void)u, (void)out;
        return false;
    }

    /// sigma_t when it is one constant everywhere in the medium (a homogeneous medium), so that
    /// a free flight through it has a density in closed form; false elsewhere.
    virtual bool constant_extinction(Spectrum &sigma_t) const {
        (void)sigma_t;
        return false;
    }
    /// sigma_s at `p` where constant_extinction holds (sigma_t times the albedo there).
    virtual Spectrum scattering(Point3f p) const {
        (void)p;
        return Spectrum(0.f);
    }

    /// Free flights and transmittance estimates given up so far (their walks took too many
    /// steps; weight 0), over every render: the renderer warns of those of its own run.
    virtual uint64_t flights_given_up() const { return 0; }

    const PhaseFunction &phase() const { return *m_phase; }
    /// Mitsuba's `sample_emitters`: next-event estimation at scattering points in this medium.
    bool sample_emitters() const { return m_sample_emitters; }

protected:
    /// The nested `<phase>` (isotropic when absent) and `sample_emitters`.
    void read_common(const Properties &props);

    std::shared_ptr<PhaseFunction> m_phase;
    bool m_sample_emitters = true;
};

} // namespace mvpt
