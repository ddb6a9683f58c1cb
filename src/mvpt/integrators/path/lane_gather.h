// Moving a chunk of lanes between the wavefront's records and the vector kernels' columns:
// the Lambertian kernels' inputs (lam_col, path_kernels.h) gathered field by field from the
// records of different paths, and the kernels' shadow rays appended, both by the word
// gathers and compresses of core/simd_gather.h (16 lanes per AVX-512 instruction where the
// CPU has it). Pure copies: the results are the same bits on every CPU.
#pragma once

#include "wavefront.h"

#include <cstddef>
#include <cstdint>

namespace mvpt {

struct SurfaceInteraction;

/// The records a chunk's lanes are gathered from.
struct LaneSources {
    const SurfaceInteraction *si; ///< per active path (its wi is not set for Lambertian vertices)
    const Ray *rays;              ///< per active path: the ray that found its interaction
    const WavePath *paths;        ///< per active path
    const ScatterVertex *scatter; ///< per scattering vertex
    const float *const *u;        ///< the scattering vertices' numbers u[0..6] (WaveBuffers::u)
    uint32_t rr_depth;            ///< Russian roulette applies from depth + 1 >= rr_depth
};

/// Lane m of the columns (stride `stride` floats) gets path path[m] at scattering vertex
/// vertex[m]: WiZ (the cosine of the incoming direction, -ray.d in the shading frame, as
/// SurfaceInteraction::to_local computes it), the shading frame, position, geometric normal, reflectance, throughput,
/// Eta, URr, RrOn and the BSDF sample's numbers DirUx, DirUy; with `light_numbers` also the
/// emitter sample's LightUx, LightUy. TwoSided and Emitter are left to the caller.
/// `vector` = false copies one word at a time on any CPU (the tests compare both).
void gather_lambert_lanes(float *cols, size_t stride, size_t n, const uint32_t *path, const uint32_t *vertex,
                          const LaneSources &src, bool light_numbers, bool vector = true);

/// The ln_col inputs of lambert_nee_kernel for n lanes (path path[m], scattering vertex
/// vertex[m], whose emitter sample is taken): WiZ (as above), shading normal, position, geometric
/// normal, reflectance, throughput, and the emitter sample (direction, point, distance,
/// density, delta flag as 1 or 0, weight). TwoSided is left to the caller.
void gather_lambert_nee_lanes(float *cols, size_t stride, size_t n, const uint32_t *path, const uint32_t *vertex,
                              const LaneSources &src, bool vector = true);

/// The next-event estimates of a kernel's n lanes (paths path[m]), from its output columns
/// o0 .. o0 + 10 (shadow ray origin, direction and t_max, contribution, whether it counts):
/// the lanes that count append their shadow ray (with their interaction's time) to the
/// columns shadow[0..7] and their contribution to `pending`, from position `count` on, in
/// lane order. Returns the new count. The AVX-512 loop stores whole 16-lane steps: the
/// shadow columns need 16 entries to spare past the last one used.
size_t append_shadow_rays(const float *cols, size_t stride, size_t n, size_t o0, const uint32_t *path,
                          const SurfaceInteraction *si, float *const shadow[8], PendingShadow *pending, size_t count,
                          bool vector = true);

} // namespace mvpt
