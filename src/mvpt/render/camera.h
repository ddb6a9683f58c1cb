// Camera interface (Mitsuba's "sensor"): one view of the scene with its film,
// sampler settings and shutter interval.
#pragma once

#include "../core/math.h"
#include "../core/sampler.h"
#include "../scene/animation.h"
#include "../scene/properties.h"
#include "filter.h"

#include <memory>
#include <string>

namespace mvpt {

/// The `hdrfilm` of a sensor: full film size, the crop window that is rendered, the filter.
struct FilmDesc {
    int width = 768, height = 576;
    int crop_x = 0, crop_y = 0, crop_width = 768, crop_height = 576;
    std::shared_ptr<ReconstructionFilter> filter;
};

class Camera : public Object {
public:
    /// Ray through film position `film` (pixels, full-film coordinates, y down),
    /// lens point `lens` on the unit disk, at scene time `time`. Rays carry unit weight.
    virtual Ray generate_ray(Vec2f film, Vec2f lens, float time) const = 0;
    /// Lens radius (0 for a pinhole).
    virtual float lens_radius() const { return 0.f; }

    std::string id;
    FilmDesc film;
    SamplerKind sampler_kind = SamplerKind::Independent;
    int sample_count = 4;
    uint32_t seed = 0;
    float shutter_open = 0.f, shutter_close = 0.f;

    /// Scene time for a uniform sample in the shutter interval.
    float sample_time(float u) const { return shutter_open + u * (shutter_close - shutter_open); }
};

} // namespace mvpt
