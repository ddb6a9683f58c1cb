// Vector kernels of the wavefront path tracer (path_batch.cpp) for its most common vertex:
// a constant Lambertian BSDF (diffuse, or twosided around it). The vertices of a bounce are
// gathered into structure-of-arrays columns, one lane per vertex, and processed by loops
// compiled per instruction set (core/simd.h). Each lane performs PathIntegrator::li's
// scalar operations in li's order (the build has no FMA contraction, and selects replace
// branches), so the results are bit-identical to li's.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace mvpt {

/// Structure-of-arrays storage: `cols` columns of `stride` floats (a multiple of 16).
struct SoaColumns {
    std::vector<float> data;
    size_t stride = 0;
    void resize(size_t cols, size_t n) {
        stride = (n + 15) & ~size_t(15);
        if (data.size() < cols * stride) data.resize(cols * stride);
    }
    float *operator[](size_t c) { return data.data() + c * stride; }
};

/// The columns of a Lambertian vertex, one layout for all its kernels: the emitter-sampling NEE
/// kernels (lq_col) and the BSDF-sampling kernel (ls_col) read the same gathered vertex, so a
/// vertex that samples a quad or sphere emitter is gathered once for both. Inputs, then the
/// BSDF sample's outputs, then next-event estimation's.
namespace lam_col {
enum : size_t {
    WiZ, TwoSided,
    Sx, Sy, Sz, Tx, Ty, Tz, Nx, Ny, Nz, // shading frame
    Px, Py, Pz, Gx, Gy, Gz,             // position, geometric normal
    Rr, Rg, Rb,                         // reflectance
    Br, Bg, Bb,                         // throughput (read by NEE, then updated in place by sampling)
    Eta, URr, RrOn,                     // Russian roulette: eta, its number, whether it applies
    DirUx, DirUy,                       // the BSDF sample's numbers
    LightUx, LightUy, Emitter,          // the emitter sample's numbers, the emitter's table row
    Ox, Oy, Oz, Dx, Dy, Dz, Pdf, Alive, // BSDF sample: the next ray, its density, whether the path continues
    SOx, SOy, SOz, SDx, SDy, SDz, STMax, Cr, Cg, Cb, Ok, // NEE: shadow ray, contribution, whether it counts
    Count
};
}

/// Columns of `lambert_sample_kernel` (flags are 0 or 1): lam_col's.
namespace ls_col {
using namespace lam_col;
enum : size_t { Ux = DirUx, Uy = DirUy };
}

// Blocks that kernel::next_ray_and_roulette reads and writes.
static_assert(ls_col::Nz == ls_col::Sx + 8 && ls_col::Gz == ls_col::Px + 5 && ls_col::RrOn == ls_col::Br + 5 &&
              ls_col::Alive == ls_col::Ox + 7);

/// BSDF sampling (cosine-weighted hemisphere), the next ray (spawn_ray), the throughput update
/// and Russian roulette of n Lambertian vertices: li's "BSDF sampling" and "Russian roulette".
void lambert_sample_kernel(SoaColumns &c, size_t n);

/// Columns of `lambert_nee_kernel`: inputs, then outputs.
namespace ln_col {
enum : size_t {
    WiZ, TwoSided,
    Nx, Ny, Nz,                 // shading normal
    Px, Py, Pz, Gx, Gy, Gz,     // position, geometric normal
    Rr, Rg, Rb,                 // reflectance
    Br, Bg, Bb,                 // throughput
    Ldx, Ldy, Ldz, Lpx, Lpy, Lpz, LDist, LPdf, LDelta, // emitter sample (direction, point, distance, density)
    Wr, Wg, Wb,                 // emitter weight L/pdf
    Ox, Oy, Oz, Dx, Dy, Dz, TMax, Cr, Cg, Cb, Ok, // outputs: shadow ray, contribution, whether f > 0
    Count
};
}

// Blocks that kernel::nee_contribution_and_shadow_ray reads and writes.
static_assert(ln_col::Gz == ln_col::Px + 5 && ln_col::LDelta == ln_col::Ldx + 8 && ln_col::Wb == ln_col::Wr + 2 &&
              ln_col::Bb == ln_col::Br + 2 && ln_col::Ok == ln_col::Ox + 10 && ln_col::Cr == ln_col::Ox + 7);

/// Next-event estimation at n Lambertian vertices given their emitter samples: BSDF value and
/// density, MIS weight, contribution and shadow ray (li's "Next-event estimation" after
/// sample_li). `light_count` is the number of lights (uniform selection).
void lambert_nee_kernel(SoaColumns &c, size_t n, float light_count);

/// Columns of `lambert_quad_nee_kernel` and `lambert_sphere_nee_kernel`: lam_col's, with the
/// emitter sample's numbers and table row as inputs and the NEE outputs.
namespace lq_col {
using lam_col::WiZ, lam_col::TwoSided, lam_col::Nx, lam_col::Ny, lam_col::Nz, lam_col::Px, lam_col::Py, lam_col::Pz,
    lam_col::Gx, lam_col::Gy, lam_col::Gz, lam_col::Rr, lam_col::Rg, lam_col::Rb, lam_col::Br, lam_col::Bg,
    lam_col::Bb, lam_col::Cr, lam_col::Cg, lam_col::Cb, lam_col::Ok, lam_col::Count;
enum : size_t {
    Ux = lam_col::LightUx, Uy = lam_col::LightUy, Quad = lam_col::Emitter,
    Ox = lam_col::SOx, Oy = lam_col::SOy, Oz = lam_col::SOz, Dx = lam_col::SDx, Dy = lam_col::SDy, Dz = lam_col::SDz,
    TMax = lam_col::STMax
};
}

/// Parameters of up to `Max` quad emitters (QuadEmitter in render/lights/area.h), one row per parameter.
struct QuadTable {
    static constexpr size_t Max = 16;
    enum : size_t { Ox, Oy, Oz, E1x, E1y, E1z, E2x, E2y, E2z, Nx, Ny, Nz, InvArea, Lr, Lg, Lb, Params };
    alignas(64) float v[Params * Max] = {};
    float &at(size_t param, size_t quad) { return v[param * Max + quad]; }
};

/// Next-event estimation at n Lambertian vertices towards quad emitters, emitter sampling
/// included (AreaLight::sample_li on a parallelogram mesh, then as lambert_nee_kernel).
/// `one_quad` >= 0 says that every lane chose that quad: its table row is then read as loop
/// invariants instead of lane by lane (which GCC assembles from scalar loads).
void lambert_quad_nee_kernel(SoaColumns &c, size_t n, const QuadTable &quads, float light_count, int one_quad = -1);

/// Parameters of up to `Max` sphere emitters (SphereEmitter in render/lights/area.h), one row per parameter.
struct SphereTable {
    static constexpr size_t Max = 16;
    enum : size_t { Cx, Cy, Cz, Radius, Flip, Lr, Lg, Lb, Params };
    alignas(64) float v[Params * Max] = {};
    float &at(size_t param, size_t sphere) { return v[param * Max + sphere]; }
    float at(size_t param, size_t sphere) const { return v[param * Max + sphere]; }
};

/// `lambert_quad_nee_kernel` towards sphere emitters seen from outside (the Quad column holds the
/// SphereTable row): Sphere::sample_solid_angle's cone sampling, then AreaLight::sample_li.
void lambert_sphere_nee_kernel(SoaColumns &c, size_t n, const SphereTable &spheres, float light_count);

/// The columns of a constant rough conductor vertex, one layout for all its kernels (as
/// lam_col): the NEE kernels (rn_col, rsn_col) and the sampling kernel (rs_col) read the same
/// gathered vertex. Inputs, then the BSDF sample's outputs, then next-event estimation's.
namespace cond_col {
enum : size_t {
    WiX, WiY, WiZ, TwoSided, Beckmann, Alpha, // local wi; RoughConductorInfo
    EtaR, EtaG, EtaB, KR, KG, KB, SpR, SpG, SpB,
    Sx, Sy, Sz, Tx, Ty, Tz, Nx, Ny, Nz, // shading frame
    Px, Py, Pz, Gx, Gy, Gz,             // position, geometric normal
    Br, Bg, Bb,                         // throughput (read by NEE, then updated in place by sampling)
    Eta, URr, RrOn,                     // Russian roulette: eta, its number, whether it applies
    DirUx, DirUy,                       // the BSDF sample's numbers
    Ldx, Ldy, Ldz, Lpx, Lpy, Lpz, LDist, LPdf, LDelta, // emitter sample (direction, point, distance, density)
    Wr, Wg, Wb,                                        // emitter weight L/pdf
    LightUx, LightUy, SphereRow,        // a sphere emitter's sample numbers and SphereTable row
    Ox, Oy, Oz, Dx, Dy, Dz, Pdf, Alive, // BSDF sample: the next ray, its density, whether the path continues
    SOx, SOy, SOz, SDx, SDy, SDz, STMax, Cr, Cg, Cb, Ok, // NEE: shadow ray, contribution, whether f > 0
    Count
};
}

/// Columns of `rough_conductor_sample_kernel` (flags are 0 or 1): cond_col's.
namespace rs_col {
using namespace cond_col;
enum : size_t { Ux = DirUx, Uy = DirUy };
}

static_assert(rs_col::Nz == rs_col::Sx + 8 && rs_col::Gz == rs_col::Px + 5 && rs_col::RrOn == rs_col::Br + 5 &&
              rs_col::Alive == rs_col::Ox + 7);

/// BSDF sampling (visible normals), the next ray, the throughput update and Russian roulette
/// of n constant rough conductor vertices (RoughConductorInfo): li's "BSDF sampling" and
/// "Russian roulette" through RoughConductor::sample (and TwoSidedBsdf's mirroring).
void rough_conductor_sample_kernel(SoaColumns &c, size_t n);

/// Columns of `rough_conductor_nee_kernel`: cond_col's, with the NEE outputs.
namespace rn_col {
using cond_col::WiX, cond_col::WiY, cond_col::WiZ, cond_col::TwoSided, cond_col::Beckmann, cond_col::Alpha,
    cond_col::EtaR, cond_col::EtaG, cond_col::EtaB, cond_col::KR, cond_col::KG, cond_col::KB, cond_col::SpR,
    cond_col::SpG, cond_col::SpB, cond_col::Sx, cond_col::Sy, cond_col::Sz, cond_col::Tx, cond_col::Ty, cond_col::Tz,
    cond_col::Nx, cond_col::Ny, cond_col::Nz, cond_col::Px, cond_col::Py, cond_col::Pz, cond_col::Gx, cond_col::Gy,
    cond_col::Gz, cond_col::Br, cond_col::Bg, cond_col::Bb, cond_col::Ldx, cond_col::Ldy, cond_col::Ldz,
    cond_col::Lpx, cond_col::Lpy, cond_col::Lpz, cond_col::LDist, cond_col::LPdf, cond_col::LDelta, cond_col::Wr,
    cond_col::Wg, cond_col::Wb, cond_col::Cr, cond_col::Cg, cond_col::Cb, cond_col::Ok, cond_col::Count;
enum : size_t {
    Ox = cond_col::SOx, Oy = cond_col::SOy, Oz = cond_col::SOz, Dx = cond_col::SDx, Dy = cond_col::SDy,
    Dz = cond_col::SDz, TMax = cond_col::STMax
};
}

static_assert(rn_col::Gz == rn_col::Px + 5 && rn_col::LDelta == rn_col::Ldx + 8 && rn_col::Wb == rn_col::Wr + 2 &&
              rn_col::Bb == rn_col::Br + 2 && rn_col::Ok == rn_col::Ox + 10 && rn_col::Cr == rn_col::Ox + 7);

/// Next-event estimation at n constant rough conductor vertices given their emitter samples
/// (as lambert_nee_kernel): RoughConductor::eval and ::pdf, MIS, contribution and shadow ray.
void rough_conductor_nee_kernel(SoaColumns &c, size_t n, float light_count);

/// Columns of `rough_conductor_sphere_nee_kernel`: rn_col's (the emitter sample's columns are
/// filled by the kernel), with the emitter sample's numbers and the emitter's SphereTable row.
namespace rsn_col {
enum : size_t { Ux = cond_col::LightUx, Uy = cond_col::LightUy, Sphere = cond_col::SphereRow };
}

/// `rough_conductor_nee_kernel` towards sphere emitters seen from outside, emitter sampling
/// included (Sphere::sample_solid_angle's cone sampling, then AreaLight::sample_li); lanes
/// whose emitter sample is void get Ok = 0.
void rough_conductor_sphere_nee_kernel(SoaColumns &c, size_t n, const SphereTable &spheres, float light_count);

} // namespace mvpt
