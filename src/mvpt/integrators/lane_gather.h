// Filling the Lambertian kernels' input columns (lam_col, path_kernels.h) for a chunk of
// lanes from the wavefront's records: one column at a time, 16 lanes per AVX-512 gather
// where the CPU has it (a lane's 30-odd values come from three records of different paths,
// which scalar code copies with one load and one store each). Pure copies: the columns are
// the same bits on every CPU.
#pragma once

#include "wavefront.h"

#include <cstddef>
#include <cstdint>

namespace mvpt {

struct SurfaceInteraction;

/// The records a chunk's lanes are gathered from.
struct LaneSources {
    const SurfaceInteraction *si; ///< per active path
    const WavePath *paths;        ///< per active path
    const ScatterVertex *scatter; ///< per scattering vertex
    const float *const *u;        ///< the scattering vertices' numbers u[0..6] (WaveBuffers::u)
    uint32_t rr_depth;            ///< Russian roulette applies from depth + 1 >= rr_depth
};

/// Lane m of the columns (stride `stride` floats) gets path path[m] at scattering vertex
/// vertex[m]: WiZ, the shading frame, position, geometric normal, reflectance, throughput,
/// Eta, URr, RrOn and the BSDF sample's numbers DirUx, DirUy; with `light_numbers` also the
/// emitter sample's LightUx, LightUy. TwoSided and Emitter are left to the caller.
/// `vector` = false takes the scalar loop on any CPU (the tests compare both).
void gather_lambert_lanes(float *cols, size_t stride, size_t n, const uint32_t *path, const uint32_t *vertex,
                          const LaneSources &src, bool light_numbers, bool vector = true);

} // namespace mvpt
