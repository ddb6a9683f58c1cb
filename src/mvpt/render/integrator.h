// Integrator interface: radiance along a camera ray.
#pragma once

#include "../core/math.h"
#include "../core/sampler.h"
#include "../core/properties.h"

namespace mvpt {

class Medium;
class Scene;

/// Per-thread ray and event counters (summed after a pass).
struct RayCounters {
    uint64_t camera_rays = 0, rays = 0, shadow_rays = 0, nonfinite = 0;
    RayCounters &operator+=(const RayCounters &o) {
        camera_rays += o.camera_rays; rays += o.rays; shadow_rays += o.shadow_rays; nonfinite += o.nonfinite;
        return *this;
    }
};

/// Sample dimensions of the camera ray; path vertices use blocks after it.
inline constexpr uint32_t DimFilm = 0, DimLens = 1, DimTime = 2, DimCameraEnd = 3;

class Integrator : public Object {
public:
    virtual Spectrum li(const Scene &scene, const Ray &ray, Sampler &sampler, RayCounters &counters) const = 0;
    /// Radiance along `n` camera rays, ray i with its own started `samplers[i]`, into
    /// `out[i]`; must equal `li` per ray. The rays start in `medium` (the sensor's; only an
    /// integrator of media reads it). The default calls `li` for each.
    virtual void li_batch(const Scene &scene, const Ray *rays, Sampler *samplers, Spectrum *out, size_t n,
                          RayCounters &counters, const Medium *medium = nullptr) const {
        (void)medium;
        for (size_t i = 0; i < n; ++i) out[i] = li(scene, rays[i], samplers[i], counters);
    }
    virtual std::string name() const = 0;
};

} // namespace mvpt
