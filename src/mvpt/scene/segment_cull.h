// Culling of visibility-segment bundles: a multi-view native sample traces one segment
// from its vertex y to every candidate camera (§3 test 5 of the design doc). The segments
// leave one origin and are nearly parallel, so they fit in a thin pyramid; when no
// occluder of the scene can meet that pyramid, every segment is unblocked and none needs
// tracing. The test is conservative: "may block" sends the bundle to Embree.
#pragma once

#include "../render/shape.h"

#include <embree3/rtcore.h>

#include <cstddef>
#include <vector>

namespace mvpt {

/// A bounding volume of segments o + t d_i, t in [0, t_i]: the pyramid with apex o spanned
/// by the segments (the slopes of their end points along two axes across the mean
/// direction a, and 0 <= a.(p - o) <= the largest such height), and their bounding box.
struct SegmentBundle {
    /// Build from the traced segments (t_max > 0) among n (the arrays hold n rounded up to
    /// a multiple of 8); `across` orients the pyramid (the direction in which the segments'
    /// far ends spread most, e.g. along a row of cameras). False when the segments spread
    /// too widely for one pyramid (then the bundle proves nothing) or none is traced.
    bool build(Point3f o, Vec3f across, const float *dx, const float *dy, const float *dz, const float *t_max,
               size_t n);

    /// Six half-spaces n.(p - o) <= d whose intersection holds every segment; `normal_len`
    /// bounds |n| from above (|n|_1).
    double normal[6][3], offset[6], normal_len[6];
    /// The pyramid's apex and the four corners of its far cap.
    double vertex[5][3];
    /// The segments' bounding box.
    double lo[3], hi[3];
    double origin[3];
    /// Absolute margin of the double-precision tests (relative 1e-9 of the bundle's scale).
    double eps;
    /// Float copies for the box tests of the tree's inner nodes (OccluderBvh::may_block
    /// adds the margin that their rounding needs).
    float normal_f[6][3], offset_f[6];
    /// Per plane: d + n.o (the bound on n.p) and |n|_1.
    float limit_f[6], norm1_f[6];
    float lo_f[3], hi_f[3], origin_f[3];
};

/// Occluders of a static scene (every shape's triangles, spheres or bounding box) in a
/// 4-wide BVH built by Embree's BVH builder, for `may_block` queries.
class OccluderBvh {
public:
    OccluderBvh(RTCDevice device, const std::vector<std::shared_ptr<Shape>> &shapes);
    ~OccluderBvh();
    OccluderBvh(const OccluderBvh &) = delete;
    OccluderBvh &operator=(const OccluderBvh &) = delete;
    /// False only if no occluder can meet any segment of the bundle (exact in double
    /// precision, up to a relative margin of 1e-9, i.e. far below the spawn offset).
    bool may_block(const SegmentBundle &b) const;
    size_t size() const { return m_prims.size(); }

private:
    enum class Kind : uint32_t { Triangle, Sphere, Box };
    /// A triangle (p[0..2]), a sphere (p[0] centre, p[1][0] radius) or a box (p[0] min, p[1] max).
    struct Prim {
        Kind kind;
        double p[3][3];
        /// A triangle's (unnormalised) normal and its length.
        double n[3], n_len;
        /// The box that holds the primitive.
        double lo[3], hi[3];
    };
    bool prim_may_block(const Prim &prim, const SegmentBundle &b) const;

    std::vector<Prim> m_prims;
    RTCBVH m_bvh = nullptr;
    const void *m_root = nullptr;
    /// Largest coordinate magnitude of the occluders (for the float margins).
    float m_extent = 0.f;
};

} // namespace mvpt
