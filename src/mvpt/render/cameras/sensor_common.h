// Parameters every sensor shares: id, film, sampler, shutter.
#pragma once

#include "../camera.h"

namespace mvpt {

/// The `hdrfilm` plugin's result.
struct FilmObject : Object {
    FilmDesc desc;
};

/// The sampler plugins' result.
struct SamplerObject : Object {
    SamplerKind kind = SamplerKind::Independent;
    int sample_count = 4;
    uint32_t seed = 0;
};

/// Read id, film (default 768x576 box), sampler (default independent, 4 spp) and shutter.
void read_sensor_common(Camera &cam, const Properties &props);

} // namespace mvpt
