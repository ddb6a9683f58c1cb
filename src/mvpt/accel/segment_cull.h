// Culling of visibility-segment bundles: a multi-view native sample traces one segment
// from its vertex y to every candidate camera (§3 test 5 of the design doc). The segments
// leave one origin and are nearly parallel, so they fit in a thin pyramid; when no
// occluder of the scene can meet that pyramid, every segment is unblocked and none needs
// tracing. The test is conservative: "may block" sends the bundle to Embree.
#pragma once

#include "../render/shape.h"

#include <embree3/rtcore.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
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

private:
    /// The half-spaces and corners of the pyramid along the axes a, u, v (double copies of the
    /// float ones) with slope ranges {su_lo, su_hi, sv_lo, sv_hi} and height h_max, from origin.
    void set_pyramid(const double a[3], const double u[3], const double v[3], const double slopes[4], double h_max);
    /// The box of the end points, padded beyond float rounding; the float copies and the margin.
    void set_box(const float box_lo[3], const float box_hi[3], float t_max_max);
};

/// A convex region that holds a set of segments, for the queries that bound a whole family
/// of bundles at once (RigVisibility): the segments lie in the hull of `vertex` and in every
/// half-space normal.p <= offset (absolute coordinates; any valid bounds, tight or not).
struct ConvexRegion {
    static constexpr int MaxVertices = 16, MaxPlanes = 8;
    int vertices = 0, planes = 0;
    double vertex[MaxVertices][3];
    double normal[MaxPlanes][3], offset[MaxPlanes];
    /// Set by `finish`: |n|_1 per plane, the vertices' box and the margin of the tests.
    double normal_len[MaxPlanes], lo[3], hi[3], eps = 0;
    void add_vertex(const double p[3]);
    void add_plane(const double n[3], double d);
    /// The half-space n.p <= max over the vertices of n.p (the support plane along n).
    void add_support_plane(const double n[3]);
    void finish();
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
    /// The same for a convex region, ignoring occluder `skip` (-1: none).
    bool may_block(const ConvexRegion &r, int64_t skip) const;
    /// The occluders that may_block(b) finds may meet the bundle, up to `max` of them into
    /// `out`: how many, or -1 when there are more.
    int blockers(const SegmentBundle &b, int64_t *out, int max) const;
    /// For the segments from `a` along (dx, dy, dz)[s] to length t_max[s] (those with t_max > 0):
    /// sets hit[s] = 1 unless occluder `i` provably misses segment s (exact in double precision
    /// up to the distance `margin + per_length * t_max[s]`; boxes always may), and leaves the
    /// other entries as they are.
    void may_hit(int64_t i, const double a[3], const float *dx, const float *dy, const float *dz, const float *t_max,
                 size_t n, double margin, double per_length, uint8_t *hit) const;
    size_t size() const { return m_prims.size(); }
    /// The occluder that is primitive `prim` of `shape` (a mesh triangle or a sphere), or -1.
    int64_t occluder_of(const Shape *shape, uint32_t prim) const;
    /// Occluder `i` as a triangle (its vertices, unnormalised normal n = (p1 - p0) x (p2 - p0)
    /// and |n|): false if it is not one.
    bool triangle(int64_t i, double p[3][3], double n[3], double *n_len) const;
    bool is_sphere(int64_t i) const { return m_prims[size_t(i)].kind == Kind::Sphere; }
    /// The box that holds every occluder.
    const double *lower() const { return m_lo; }
    const double *upper() const { return m_hi; }

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
    /// A shape's range of triangles and spheres in the occluder list.
    struct ShapeRange {
        const Shape *shape;
        size_t tri0, tri1, sph0, sph1;
    };
    static Prim triangle_prim(const std::array<Point3f, 3> &t);
    /// Occluder `p` with box `b` into the primitives and Embree's build list: its index, or -1
    /// when the box is empty.
    int64_t add(Prim p, const BoundingBox &b, std::vector<RTCBuildPrimitive> &build);
    /// m_shape_occluders from each shape's range and the occluder index of each list entry.
    void index_shapes(const std::vector<ShapeRange> &ranges, const std::vector<int64_t> &tri_prim,
                      const std::vector<int64_t> &sph_prim);
    void build_tree(RTCDevice device, std::vector<RTCBuildPrimitive> &build);
    bool prim_may_block(const Prim &prim, const SegmentBundle &b) const;
    bool prim_may_block(const Prim &prim, const ConvexRegion &r) const;
    /// may_hit for one segment from `a` to `b` and a triangle or box.
    static bool flat_may_hit(const Prim &prim, const double a[3], const double b[3], double margin);
    /// True when triangle `tri`'s plane has all `n` vertices strictly on one side.
    static bool plane_separates(const Prim &tri, const double (*vertex)[3], int n, double eps);
    /// Depth-first walk of the tree: `keep(inner node)` gives the children to visit (a mask
    /// of 4 lanes), `leaf(prim index)` is true when the primitive may block (stops the walk).
    template <class Keep, class Leaf> bool walk(Keep keep, Leaf leaf) const;
    /// Per shape, the first occluder index of its triangles or its sphere, and their count.
    struct ShapeOccluders {
        int64_t first = -1;
        uint32_t count = 0;
    };
    std::unordered_map<const Shape *, ShapeOccluders> m_shape_occluders;
    double m_lo[3] = {0, 0, 0}, m_hi[3] = {0, 0, 0};

    std::vector<Prim> m_prims;
    RTCBVH m_bvh = nullptr;
    const void *m_root = nullptr;
    /// Largest coordinate magnitude of the occluders (for the float margins).
    float m_extent = 0.f;
};

} // namespace mvpt
