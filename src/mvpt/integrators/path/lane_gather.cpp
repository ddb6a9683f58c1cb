#include "lane_gather.h"

#include "path_kernels.h"
#include "../../core/simd_gather.h"
#include "../../render/interaction.h"

#include <algorithm>
#include <array>
#include <cstddef>

namespace mvpt {

namespace {

using simd::FieldList;

static_assert(sizeof(SurfaceInteraction) % 4 == 0 && sizeof(WavePath) % 4 == 0 && sizeof(ScatterVertex) % 4 == 0);
static_assert(sizeof(Frame) == 9 * sizeof(float) && sizeof(Vec3f) == 3 * sizeof(float) &&
              sizeof(Color3f) == 3 * sizeof(float));

/// Where the scattering vertex's emitter sample (and its weight) begin.
constexpr size_t EmitterSample = offsetof(ScatterVertex, emitter_sample);
constexpr size_t LightSampleAt = EmitterSample + offsetof(decltype(ScatterVertex::emitter_sample), first);
constexpr size_t WeightAt = EmitterSample + offsetof(decltype(ScatterVertex::emitter_sample), second);

/// The column `wi_z`: -ray.d in the shading frame, its z (Frame::to_local's dot(v, n)), from
/// the lanes' rays and the shading normal already gathered into columns nx .. nx + 2.
void wi_z_column(float *cols, size_t st, size_t n, const uint32_t *path, const Ray *rays, size_t wi_z, size_t nx) {
    for (size_t m = 0; m < n; ++m) {
        const Vec3f normal(cols[nx * st + m], cols[(nx + 1) * st + m], cols[(nx + 2) * st + m]);
        cols[wi_z * st + m] = dot(-rays[path[m]].d, normal);
    }
}

/// One of the scattering vertices' numbers (an array of floats) to column `Column`.
template <size_t Column>
constexpr FieldList Number = FieldList().add(Column, 0);

namespace lam {
using namespace lam_col;
constexpr FieldList si = FieldList()
                             .add(Sx, offsetof(SurfaceInteraction, sh_frame), 9)
                             .add(Px, offsetof(SurfaceInteraction, p), 3)
                             .add(Gx, offsetof(SurfaceInteraction, n), 3);
constexpr FieldList path = FieldList().add(Br, offsetof(WavePath, throughput), 3).add(Eta, offsetof(WavePath, eta));
constexpr FieldList vertex = FieldList().add(Rr, offsetof(ScatterVertex, refl), 3);
} // namespace lam

namespace nee {
using namespace ln_col;
constexpr FieldList si = FieldList()
                             .add(Nx, offsetof(SurfaceInteraction, sh_frame) + offsetof(Frame, n), 3)
                             .add(Px, offsetof(SurfaceInteraction, p), 3)
                             .add(Gx, offsetof(SurfaceInteraction, n), 3);
constexpr FieldList path = FieldList().add(Br, offsetof(WavePath, throughput), 3);
constexpr FieldList vertex = FieldList()
                                 .add(Rr, offsetof(ScatterVertex, refl), 3)
                                 .add(Ldx, LightSampleAt + offsetof(LightSample, d), 3)
                                 .add(Lpx, LightSampleAt + offsetof(LightSample, p), 3)
                                 .add(LDist, LightSampleAt + offsetof(LightSample, dist))
                                 .add(LPdf, LightSampleAt + offsetof(LightSample, pdf))
                                 .add(Wr, WeightAt, 3);
} // namespace nee

} // namespace

void gather_lambert_lanes(float *cols, size_t st, size_t n, const uint32_t *path, const uint32_t *vertex,
                          const LaneSources &src, bool light_numbers, bool vector) {
    using namespace lam_col;
    simd::gather<lam::si>(cols, st, n, path, src.si, sizeof(SurfaceInteraction), vector);
    simd::gather<lam::path>(cols, st, n, path, src.paths, sizeof(WavePath), vector);
    simd::gather<lam::vertex>(cols, st, n, vertex, src.scatter, sizeof(ScatterVertex), vector);
    simd::gather<Number<URr>>(cols, st, n, vertex, src.u[6], sizeof(float), vector);
    simd::gather<Number<DirUx>>(cols, st, n, vertex, src.u[4], sizeof(float), vector);
    simd::gather<Number<DirUy>>(cols, st, n, vertex, src.u[5], sizeof(float), vector);
    if (light_numbers) {
        simd::gather<Number<LightUx>>(cols, st, n, vertex, src.u[1], sizeof(float), vector);
        simd::gather<Number<LightUy>>(cols, st, n, vertex, src.u[2], sizeof(float), vector);
    }
    wi_z_column(cols, st, n, path, src.rays, WiZ, Nx);
    for (size_t m = 0; m < n; ++m) cols[RrOn * st + m] = src.paths[path[m]].depth + 1 >= src.rr_depth ? 1.f : 0.f;
}

void gather_lambert_nee_lanes(float *cols, size_t st, size_t n, const uint32_t *path, const uint32_t *vertex,
                              const LaneSources &src, bool vector) {
    using namespace ln_col;
    simd::gather<nee::si>(cols, st, n, path, src.si, sizeof(SurfaceInteraction), vector);
    simd::gather<nee::path>(cols, st, n, path, src.paths, sizeof(WavePath), vector);
    simd::gather<nee::vertex>(cols, st, n, vertex, src.scatter, sizeof(ScatterVertex), vector);
    wi_z_column(cols, st, n, path, src.rays, WiZ, Nx);
    for (size_t m = 0; m < n; ++m)
        cols[LDelta * st + m] = src.scatter[vertex[m]].emitter_sample.first.delta ? 1.f : 0.f;
}

size_t append_shadow_rays(const float *cols, size_t st, size_t n, size_t o0, const uint32_t *path,
                          const SurfaceInteraction *si, float *const shadow[8], PendingShadow *pending, size_t count,
                          bool vector) {
    // Blocks of lanes: the shadow ray (columns o0 .. o0 + 6) and the lane's number compressed,
    // then its time and its pending contribution (columns o0 + 7 .. 9) looked up.
    constexpr size_t Block = 64;
    static constexpr auto LaneNumber = [] {
        std::array<uint32_t, Block> a{};
        for (size_t m = 0; m < Block; ++m) a[m] = uint32_t(m);
        return a;
    }();
    uint32_t lane[Block + 16];
    for (size_t b = 0; b < n; b += Block) {
        const void *in[8];
        void *out[8];
        for (size_t q = 0; q < 7; ++q) in[q] = cols + (o0 + q) * st + b, out[q] = shadow[q] + count;
        in[7] = LaneNumber.data(), out[7] = lane;
        const size_t kept = simd::compress(in, out, cols + (o0 + 10) * st + b, std::min(Block, n - b), vector);
        for (size_t i = 0; i < kept; ++i) {
            const size_t m = b + lane[i];
            shadow[7][count + i] = si[path[m]].time;
            pending[count + i] = {path[m], Spectrum(cols[(o0 + 7) * st + m], cols[(o0 + 8) * st + m], cols[(o0 + 9) * st + m])};
        }
        count += kept;
    }
    return count;
}

} // namespace mvpt
