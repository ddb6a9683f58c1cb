// The wavefront path tracer's per-path and per-vertex records (integrators/path/path_batch.cpp),
// shared with the loops that gather them into the vector kernels' columns (lane_gather.cpp).
#pragma once

#include "../../core/math.h"
#include "../../render/light.h"

#include <cstdint>
#include <utility>

namespace mvpt {

class Bsdf;
struct BsdfForm;

/// One path between two vertices: li's loop variables (its ray is in the wavefront's rays).
struct WavePath {
    Spectrum result{0.f}, throughput{1.f};
    float eta = 1.f;
    Point3f prev_p;
    float prev_bsdf_pdf = 1.f;
    bool prev_bsdf_delta = true;
    bool valid = false;
    uint32_t depth = 0;
    /// Index of the camera ray (sampler and output slot).
    uint32_t slot = 0;
};

/// A path that scatters at its current vertex: its emitter sample, carried between the
/// shading loops (the vertex's random numbers are in the wavefront's columns u[0..6]).
struct ScatterVertex {
    /// Index of the path among the active ones.
    uint32_t path;
    /// The BSDF at the vertex and its form (looked up once).
    const Bsdf *bsdf;
    const BsdfForm *form;
    /// A Lambertian BSDF's reflectance at the vertex (evaluated once, read by the NEE and sampling loops).
    Color3f refl;
    /// Next-event estimation: whether an emitter was sampled, the sample and its weight.
    bool nee = false;
    /// Whether the BSDF was sampled already (with next-event estimation, by a Lambertian emitter kernel).
    bool sampled = false;
    std::pair<LightSample, Spectrum> emitter_sample;
};

/// Next-event estimate waiting for its shadow ray: added to `path`'s result if unblocked.
struct PendingShadow {
    uint32_t path;
    Spectrum contribution;
};

} // namespace mvpt
