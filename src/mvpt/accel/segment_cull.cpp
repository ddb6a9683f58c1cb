#include "segment_cull.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <new>

#include "../core/simd.h"
#include "double3.h"
#include "../render/shapes/mesh.h"
#include "../render/shapes/sphere.h"

namespace mvpt {

namespace {

/// Relative margin of the double-precision tests: far above their rounding (~1e-15) and far
/// below the spawn offset of a visibility ray's origin (~5e-6, interaction.h).
constexpr double Margin = 1e-9;

// 8-lane vectors of the loops over segments.
using F8 = simd::f32x8;
using I8 = simd::i32x8;

[[gnu::always_inline]] inline F8 load8(const float *p) { return simd::load<F8>(p); }
/// Horizontal minimum, maximum and sum of the 8 lanes (three shuffles each; the shuffle
/// builtin GCC 12 and Clang share).
[[gnu::always_inline]] inline F8 lane_min(F8 a, F8 b) { return a < b ? a : b; }
[[gnu::always_inline]] inline float hmin(F8 v) {
    v = lane_min(v, __builtin_shufflevector(v, v, 4, 5, 6, 7, 0, 1, 2, 3));
    v = lane_min(v, __builtin_shufflevector(v, v, 2, 3, 0, 1, 6, 7, 4, 5));
    v = lane_min(v, __builtin_shufflevector(v, v, 1, 0, 3, 2, 5, 4, 7, 6));
    return v[0];
}
[[gnu::always_inline]] inline float hmax(F8 v) { return -hmin(-v); }
[[gnu::always_inline]] inline float hsum(F8 v) {
    v += __builtin_shufflevector(v, v, 4, 5, 6, 7, 0, 1, 2, 3);
    v += __builtin_shufflevector(v, v, 2, 3, 0, 1, 6, 7, 4, 5);
    v += __builtin_shufflevector(v, v, 1, 0, 3, 2, 5, 4, 7, 6);
    return v[0];
}

/// Sum of the traced segments' directions (lanes with t_max > 0) over `padded` entries.
MVPT_MULTI_ISA void direction_sum(const float *dx, const float *dy, const float *dz, const float *t_max, size_t padded,
                                  float out[4]) {
    F8 sx = {}, sy = {}, sz = {}, cnt = {};
    const F8 zero = {}, one = zero + 1.f;
    for (size_t b = 0; b < padded; b += 8) {
        const I8 m = load8(t_max + b) > zero;
        sx += m ? load8(dx + b) : zero;
        sy += m ? load8(dy + b) : zero;
        sz += m ? load8(dz + b) : zero;
        cnt += m ? one : zero;
    }
    out[0] = hsum(sx), out[1] = hsum(sy), out[2] = hsum(sz), out[3] = hsum(cnt);
}

/// Ranges over the traced segments of the slopes (u.e / a.e, v.e / a.e) and height a.e of
/// their end points e = t_max d, and the bounding box of o + e; `ok` is false when a traced
/// segment is more than ~75 degrees off a (or not finite).
struct SlopeRanges {
    float su_lo, su_hi, sv_lo, sv_hi, h_max, t_max_max, lo[3], hi[3];
    bool ok;
};
MVPT_MULTI_ISA SlopeRanges slope_ranges(const float *dx, const float *dy, const float *dz, const float *t_max,
                                        size_t padded, const float a[3], const float u[3], const float v[3],
                                        const float o[3]) {
    const F8 zero = {}, inf = zero + INFINITY;
    F8 su_lo = inf, su_hi = -inf, sv_lo = inf, sv_hi = -inf, h_max = zero, t_hi = zero;
    F8 lo[3] = {inf, inf, inf}, hi[3] = {-inf, -inf, -inf};
    I8 bad = {};
    for (size_t b = 0; b < padded; b += 8) {
        const F8 t = load8(t_max + b);
        const I8 m = t > zero;
        const F8 e[3] = {load8(dx + b) * t, load8(dy + b) * t, load8(dz + b) * t};
        const F8 h = a[0] * e[0] + a[1] * e[1] + a[2] * e[2];
        const F8 x = u[0] * e[0] + u[1] * e[1] + u[2] * e[2], y = v[0] * e[0] + v[1] * e[1] + v[2] * e[2];
        const F8 inv = 1.f / (m ? h : zero + 1.f);
        const F8 su = x * inv, sv = y * inv;
        bad |= m & ~((h > 0.25f * t) & (t < inf));
        su_lo = (m & (su < su_lo)) ? su : su_lo;
        su_hi = (m & (su > su_hi)) ? su : su_hi;
        sv_lo = (m & (sv < sv_lo)) ? sv : sv_lo;
        sv_hi = (m & (sv > sv_hi)) ? sv : sv_hi;
        h_max = (m & (h > h_max)) ? h : h_max;
        t_hi = (m & (t > t_hi)) ? t : t_hi;
        for (int c = 0; c < 3; ++c) {
            const F8 p = o[c] + e[c];
            lo[c] = (m & (p < lo[c])) ? p : lo[c];
            hi[c] = (m & (p > hi[c])) ? p : hi[c];
        }
    }
    SlopeRanges r;
    r.su_lo = hmin(su_lo), r.su_hi = hmax(su_hi), r.sv_lo = hmin(sv_lo), r.sv_hi = hmax(sv_hi);
    r.h_max = hmax(h_max), r.t_max_max = hmax(t_hi);
    for (int c = 0; c < 3; ++c) r.lo[c] = std::min(hmin(lo[c]), o[c]), r.hi[c] = std::max(hmax(hi[c]), o[c]);
    bool any_bad = false;
    for (int i = 0; i < 8; ++i) any_bad |= bad[i] != 0;
    r.ok = !any_bad;
    return r;
}
} // namespace

bool SegmentBundle::build(Point3f o, Vec3f across, const float *dx, const float *dy, const float *dz,
                          const float *t_max, size_t n) {
    const size_t padded = (n + 7) / 8 * 8; // the arrays hold whole packets of 8 (Scene::occluded_segments)
    float sum[4];
    direction_sum(dx, dy, dz, t_max, padded, sum);
    const Vec3f s(sum[0], sum[1], sum[2]);
    const float len = norm(s);
    // Empty, or spread over more than ~120 degrees (or not finite): no pyramid.
    if (!(sum[3] > 0.f) || !(len > 0.5f * sum[3]) || !(len < INFINITY)) return false;
    const Vec3f a = s / len;
    // u across a, along `across` if it is not parallel to a (a row of cameras: a flat pyramid).
    Vec3f u = across - a * dot(across, a);
    if (!(squared_norm(u) > 1e-4f)) u = Frame(a).s;
    u = normalize(u);
    const Vec3f v = cross(a, u);
    const float af[3] = {a.x, a.y, a.z}, uf[3] = {u.x, u.y, u.z}, vf[3] = {v.x, v.y, v.z}, of[3] = {o.x, o.y, o.z};
    const SlopeRanges r = slope_ranges(dx, dy, dz, t_max, padded, af, uf, vf, of);
    if (!r.ok) return false;
    // The float slopes and heights err by less than ~1e-6 (1 + |s|) (h > |e| / 4): widened
    // well beyond that, the half-spaces hold the exact segments of the float inputs.
    const double widen = 1e-5;
    const double slopes[4] = {r.su_lo - widen * (1 + std::abs(r.su_lo)), r.su_hi + widen * (1 + std::abs(r.su_hi)),
                              r.sv_lo - widen * (1 + std::abs(r.sv_lo)), r.sv_hi + widen * (1 + std::abs(r.sv_hi))};
    origin[0] = o.x, origin[1] = o.y, origin[2] = o.z;
    const double ad[3] = {a.x, a.y, a.z}, ud[3] = {u.x, u.y, u.z}, vd[3] = {v.x, v.y, v.z};
    set_pyramid(ad, ud, vd, slopes, double(r.h_max) * (1 + widen) + widen);
    set_box(r.lo, r.hi, r.t_max_max);
    return true;
}

void SegmentBundle::set_pyramid(const double ad[3], const double ud[3], const double vd[3], const double slopes[4],
                                double h_max) {
    const double su_lo = slopes[0], su_hi = slopes[1], sv_lo = slopes[2], sv_hi = slopes[3];
    // Half-spaces n.(p - o) <= d: su <= su_hi, su >= su_lo, sv <= sv_hi, sv >= sv_lo, 0 <= h <= h_max
    // (su = u.(p - o) / h: the slope, exact for the float axes a, u, v taken as given).
    for (int c = 0; c < 3; ++c) {
        normal[0][c] = ud[c] - su_hi * ad[c];
        normal[1][c] = su_lo * ad[c] - ud[c];
        normal[2][c] = vd[c] - sv_hi * ad[c];
        normal[3][c] = sv_lo * ad[c] - vd[c];
        normal[4][c] = -ad[c];
        normal[5][c] = ad[c];
    }
    for (int k = 0; k < 5; ++k) offset[k] = 0;
    offset[5] = h_max;
    const double su[2] = {su_lo, su_hi}, sv[2] = {sv_lo, sv_hi};
    for (int c = 0; c < 3; ++c) {
        vertex[0][c] = origin[c];
        for (int q = 0; q < 4; ++q) vertex[1 + q][c] = origin[c] + h_max * (ad[c] + su[q & 1] * ud[c] + sv[q >> 1] * vd[c]);
    }
}

void SegmentBundle::set_box(const float box_lo[3], const float box_hi[3], float t_max_max) {
    // The end points' box: float rounding of o + e is below 1e-6 (|o| + |e|).
    double scale = 1.0 + t_max_max;
    for (int c = 0; c < 3; ++c) scale += std::max(std::abs(box_lo[c]), std::abs(box_hi[c]));
    const double pad = 1e-5 * scale;
    for (int c = 0; c < 3; ++c) {
        lo[c] = box_lo[c] - pad, hi[c] = box_hi[c] + pad;
        lo_f[c] = float(lo[c]), hi_f[c] = float(hi[c]); // the pad exceeds the float rounding
        origin_f[c] = float(origin[c]);
    }
    for (int k = 0; k < 6; ++k) {
        double no = 0;
        for (int c = 0; c < 3; ++c) {
            normal_f[k][c] = float(normal[k][c]);
            no += normal[k][c] * origin[c];
        }
        offset_f[k] = float(offset[k]);
        limit_f[k] = float(offset[k] + no);
        // |n|_1 >= |n|: used as the length in the tests, it only makes them stricter.
        normal_len[k] = std::abs(normal[k][0]) + std::abs(normal[k][1]) + std::abs(normal[k][2]);
        norm1_f[k] = float(normal_len[k]);
    }
    eps = Margin * scale;
}

// ---------------------------------------------------------------------------------------------

namespace {
struct Header {
    uint32_t leaf;
};
struct alignas(32) Inner : Header {
    float lo[3][4], hi[3][4];
    const Header *child[4];
    uint32_t count;
};
struct Leaf : Header {
    uint32_t count;
    uint32_t prim[1]; // `count` entries
};

void *create_node(RTCThreadLocalAllocator alloc, unsigned count, void *) {
    auto *n = new (rtcThreadLocalAlloc(alloc, sizeof(Inner), 32)) Inner{};
    n->leaf = 0;
    n->count = count;
    return n;
}
void set_children(void *node, void **children, unsigned count, void *) {
    for (unsigned i = 0; i < count; ++i) static_cast<Inner *>(node)->child[i] = static_cast<const Header *>(children[i]);
}
void set_bounds(void *node, const RTCBounds **bounds, unsigned count, void *) {
    auto *n = static_cast<Inner *>(node);
    for (unsigned i = 0; i < 4; ++i) {
        const bool used = i < count; // unused lanes get an empty box
        n->lo[0][i] = used ? bounds[i]->lower_x : INFINITY, n->hi[0][i] = used ? bounds[i]->upper_x : -INFINITY;
        n->lo[1][i] = used ? bounds[i]->lower_y : INFINITY, n->hi[1][i] = used ? bounds[i]->upper_y : -INFINITY;
        n->lo[2][i] = used ? bounds[i]->lower_z : INFINITY, n->hi[2][i] = used ? bounds[i]->upper_z : -INFINITY;
    }
}
void *create_leaf(RTCThreadLocalAllocator alloc, const RTCBuildPrimitive *prims, size_t count, void *) {
    auto *l = static_cast<Leaf *>(rtcThreadLocalAlloc(alloc, sizeof(Leaf) + count * sizeof(uint32_t), 16));
    l->leaf = 1;
    l->count = uint32_t(count);
    for (size_t i = 0; i < count; ++i) l->prim[i] = prims[i].primID;
    return l;
}

/// Conservative stand-ins for shapes' surfaces: together they contain everything Embree can hit.
struct OccluderList {
    std::vector<std::array<Point3f, 3>> triangles;
    /// Centre and radius.
    std::vector<std::pair<Point3f, double>> spheres;
    std::vector<BoundingBox> boxes;
};

/// A shape's occluders: a mesh's triangles, a sphere, or else the shape's bounding box.
void add_occluders(const Shape &shape, OccluderList &out) {
    if (auto *mesh = dynamic_cast<const TriangleMesh *>(&shape)) {
        const auto &pos = mesh->data().positions;
        const auto &idx = mesh->data().indices;
        for (size_t i = 0; i + 2 < idx.size(); i += 3)
            out.triangles.push_back({pos[idx[i]], pos[idx[i + 1]], pos[idx[i + 2]]});
    } else if (const std::optional<SphereGeometry> g = sphere_geometry(shape)) {
        out.spheres.emplace_back(g->center, g->radius);
    } else {
        out.boxes.push_back(shape.bounds());
    }
}

/// Box `b` grown by `pad` and rounded outwards to float, so that it holds its primitive exactly.
/// Coordinates are kept out of [-1e-10, 1e-10]: a side at 0 would round out to a denormal,
/// and products with denormals take the slow microcode path in the node tests.
BoundingBox outward(BoundingBox b, double pad) {
    for (int c = 0; c < 3; ++c) {
        float lo = std::nextafter(float((&b.min.x)[c] - pad), -INFINITY);
        float hi = std::nextafter(float((&b.max.x)[c] + pad), INFINITY);
        (&b.min.x)[c] = std::abs(lo) < 1e-10f ? -1e-10f : lo;
        (&b.max.x)[c] = std::abs(hi) < 1e-10f ? 1e-10f : hi;
    }
    return b;
}

/// Whether index[i0..i1) are valid and consecutive: a shape's occluders in primitive order.
bool contiguous(const std::vector<int64_t> &index, size_t i0, size_t i1) {
    for (size_t i = i0; i < i1; ++i)
        if (index[i] < 0 || index[i] != index[i0] + int64_t(i - i0)) return false;
    return i1 > i0;
}
} // namespace

OccluderBvh::OccluderBvh(RTCDevice device, const std::vector<std::shared_ptr<Shape>> &shapes) {
    OccluderList list;
    std::vector<ShapeRange> ranges;
    for (const auto &s : shapes) {
        const size_t tri0 = list.triangles.size(), sph0 = list.spheres.size();
        add_occluders(*s, list);
        ranges.push_back({s.get(), tri0, list.triangles.size(), sph0, list.spheres.size()});
    }
    std::vector<RTCBuildPrimitive> build;
    std::vector<int64_t> tri_prim, sph_prim; // occluder index by list index
    for (const auto &t : list.triangles) {
        BoundingBox b;
        for (const Point3f &v : t) b.expand(v);
        tri_prim.push_back(add(triangle_prim(t), outward(b, 0.0), build));
    }
    for (const auto &[c, r] : list.spheres) {
        BoundingBox b;
        b.min = b.max = c;
        sph_prim.push_back(add({Kind::Sphere, {{c.x, c.y, c.z}, {r, 0, 0}, {}}, {}, 0, {}, {}}, outward(b, r), build));
    }
    index_shapes(ranges, tri_prim, sph_prim);
    for (const BoundingBox &box : list.boxes) {
        // Bounds of analytic shapes and instances are computed in float: pad them relatively.
        double pad = 1e-5 * (1.0 + std::max({std::abs(box.min.x), std::abs(box.min.y), std::abs(box.min.z),
                                               std::abs(box.max.x), std::abs(box.max.y), std::abs(box.max.z)}));
        BoundingBox b = outward(box, pad);
        add({Kind::Box, {{b.min.x, b.min.y, b.min.z}, {b.max.x, b.max.y, b.max.z}, {}}, {}, 0, {}, {}}, b, build);
    }
    if (!build.empty()) build_tree(device, build);
}

OccluderBvh::Prim OccluderBvh::triangle_prim(const std::array<Point3f, 3> &t) {
    Prim p{Kind::Triangle, {}, {}, 0, {}, {}};
    for (int v = 0; v < 3; ++v) p.p[v][0] = t[v].x, p.p[v][1] = t[v].y, p.p[v][2] = t[v].z;
    const double e1[3] = {p.p[1][0] - p.p[0][0], p.p[1][1] - p.p[0][1], p.p[1][2] - p.p[0][2]};
    const double e2[3] = {p.p[2][0] - p.p[0][0], p.p[2][1] - p.p[0][1], p.p[2][2] - p.p[0][2]};
    p.n[0] = e1[1] * e2[2] - e1[2] * e2[1], p.n[1] = e1[2] * e2[0] - e1[0] * e2[2], p.n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    p.n_len = std::sqrt(dot3(p.n, p.n));
    return p;
}

int64_t OccluderBvh::add(Prim p, const BoundingBox &b, std::vector<RTCBuildPrimitive> &build) {
    if (!(b.min.x <= b.max.x)) return -1; // empty or NaN
    RTCBuildPrimitive r;
    r.lower_x = b.min.x, r.lower_y = b.min.y, r.lower_z = b.min.z;
    r.upper_x = b.max.x, r.upper_y = b.max.y, r.upper_z = b.max.z;
    r.geomID = 0;
    r.primID = uint32_t(m_prims.size());
    build.push_back(r);
    p.lo[0] = b.min.x, p.lo[1] = b.min.y, p.lo[2] = b.min.z;
    p.hi[0] = b.max.x, p.hi[1] = b.max.y, p.hi[2] = b.max.z;
    m_prims.push_back(p);
    m_extent = std::max({m_extent, std::abs(b.min.x), std::abs(b.min.y), std::abs(b.min.z), std::abs(b.max.x),
                         std::abs(b.max.y), std::abs(b.max.z)});
    for (int c = 0; c < 3; ++c) {
        const double l = (&b.min.x)[c], h = (&b.max.x)[c];
        m_lo[c] = m_prims.size() == 1 ? l : std::min(m_lo[c], l);
        m_hi[c] = m_prims.size() == 1 ? h : std::max(m_hi[c], h);
    }
    return int64_t(m_prims.size()) - 1;
}

void OccluderBvh::index_shapes(const std::vector<ShapeRange> &ranges, const std::vector<int64_t> &tri_prim,
                               const std::vector<int64_t> &sph_prim) {
    for (const ShapeRange &r : ranges) {
        if (r.sph1 == r.sph0 && contiguous(tri_prim, r.tri0, r.tri1))
            m_shape_occluders[r.shape] = {tri_prim[r.tri0], uint32_t(r.tri1 - r.tri0)};
        else if (r.tri1 == r.tri0 && r.sph1 == r.sph0 + 1 && sph_prim[r.sph0] >= 0)
            m_shape_occluders[r.shape] = {sph_prim[r.sph0], 1};
    }
}

void OccluderBvh::build_tree(RTCDevice device, std::vector<RTCBuildPrimitive> &build) {
    m_bvh = rtcNewBVH(device);
    RTCBuildArguments args = rtcDefaultBuildArguments();
    args.buildQuality = RTC_BUILD_QUALITY_HIGH;
    args.maxBranchingFactor = 4;
    args.maxLeafSize = 4;
    args.bvh = m_bvh;
    args.primitives = build.data();
    args.primitiveCount = build.size();
    args.primitiveArrayCapacity = build.size();
    args.createNode = create_node;
    args.setNodeChildren = set_children;
    args.setNodeBounds = set_bounds;
    args.createLeaf = create_leaf;
    m_root = rtcBuildBVH(&args);
}

OccluderBvh::~OccluderBvh() {
    if (m_bvh) rtcReleaseBVH(m_bvh);
}

bool OccluderBvh::plane_separates(const Prim &tri, const double (*vertex)[3], int n, double eps) {
    // Every vertex strictly on one side, by more than eps |n|.
    const double *p0 = tri.p[0], *nt = tri.n;
    const double tol = eps * tri.n_len;
    int above = 0, below = 0;
    for (int v = 0; v < n; ++v) {
        const double *q = vertex[v];
        const double s = nt[0] * (q[0] - p0[0]) + nt[1] * (q[1] - p0[1]) + nt[2] * (q[2] - p0[2]);
        above += s > tol;
        below += s < -tol;
    }
    return above == n || below == n;
}

bool OccluderBvh::prim_may_block(const Prim &prim, const SegmentBundle &b) const {
    const double eps = b.eps;
    for (int c = 0; c < 3; ++c) // the primitive's box against the end points' box
        if (prim.lo[c] > b.hi[c] || prim.hi[c] < b.lo[c]) return false;
    if (prim.kind == Kind::Triangle) {
        // Separated by the triangle's plane (first: it settles the triangle that y lies on).
        if (plane_separates(prim, b.vertex, 5, eps)) return false;
        // Separated by a plane of the pyramid: all three vertices beyond it, by more than eps |n|.
        double q[3][3];
        for (int v = 0; v < 3; ++v)
            for (int c = 0; c < 3; ++c) q[v][c] = prim.p[v][c] - b.origin[c];
        for (int k = 0; k < 6; ++k) {
            const double *n = b.normal[k], lim = b.offset[k] + eps * b.normal_len[k];
            if (dot3(n, q[0]) > lim && dot3(n, q[1]) > lim && dot3(n, q[2]) > lim) return false;
        }
        return true;
    }
    if (prim.kind == Kind::Sphere) {
        const double *c = prim.p[0], r = prim.p[1][0];
        const double q[3] = {c[0] - b.origin[0], c[1] - b.origin[1], c[2] - b.origin[2]};
        // The plane tangent to the sphere facing the apex, when the apex is outside it (first:
        // it settles the sphere that y lies on).
        const double lm = std::sqrt(dot3(q, q));
        if (lm > r + eps) {
            bool all = true;
            for (int v = 1; v < 5 && all; ++v) { // v = 0, the apex, is outside
                const double w[3] = {b.vertex[v][0] - c[0], b.vertex[v][1] - c[1], b.vertex[v][2] - c[2]};
                all = -dot3(w, q) > (r + eps) * lm;
            }
            if (all) return false;
        }
        for (int k = 0; k < 6; ++k)
            if (dot3(b.normal[k], q) - r * b.normal_len[k] - b.offset[k] > eps * b.normal_len[k]) return false;
        return true;
    }
    for (int k = 0; k < 6; ++k) { // a box: its corner nearest to the inside of each plane
        const double *n = b.normal[k];
        double low = 0;
        for (int c = 0; c < 3; ++c) low += n[c] * ((n[c] >= 0 ? prim.p[0][c] : prim.p[1][c]) - b.origin[c]);
        if (low - b.offset[k] > eps * b.normal_len[k]) return false;
    }
    return true;
}

template <class Keep, class LeafTest> bool OccluderBvh::walk(Keep keep, LeafTest leaf) const {
    if (!m_root) return false;
    const Header *stack[128];
    int sp = 0;
    stack[sp++] = static_cast<const Header *>(m_root);
    while (sp > 0) {
        const Header *h = stack[--sp];
        if (h->leaf) {
            const Leaf *l = static_cast<const Leaf *>(h);
            for (uint32_t i = 0; i < l->count; ++i)
                if (leaf(l->prim[i])) return true;
            continue;
        }
        const Inner *n = static_cast<const Inner *>(h);
        const auto mask = keep(n->lo);
        for (uint32_t c = 0; c < n->count; ++c)
            if (mask[c]) stack[sp++] = n->child[c];
    }
    return false;
}

namespace {
using F4 = simd::f32x4;
using I4 = simd::i32x4;

/// A node's four child boxes (lo[3][4] then hi[3][4]) against a region's float box and
/// half-spaces n.p <= limit (n split into its positive and negative parts): a box is cut off
/// by a plane when its corner nearest to the inside, n+ . lo + n- . hi, lies beyond it.
struct NodeTest {
    float lo[3], hi[3];
    int planes = 0;
    float pos[ConvexRegion::MaxPlanes][3], neg[ConvexRegion::MaxPlanes][3], limit[ConvexRegion::MaxPlanes];

    /// Plane n.p <= limit, where `limit` already holds the margin for the float rounding.
    void add(const float n[3], float lim) {
        // Components below 1e-10 are dropped (no denormal products; the change of n.p is far
        // below the margin).
        for (int c = 0; c < 3; ++c) {
            const float nc = std::abs(n[c]) < 1e-10f ? 0.f : n[c];
            pos[planes][c] = std::max(nc, 0.f), neg[planes][c] = std::min(nc, 0.f);
        }
        limit[planes++] = lim;
    }
    I4 operator()(const float (&node)[3][4]) const {
        F4 box[6];
        std::memcpy(box, node, sizeof(box)); // lo[3][4] then hi[3][4] (Inner's layout)
        I4 keep = (box[0] <= hi[0]) & (box[3] >= lo[0]) & (box[1] <= hi[1]) & (box[4] >= lo[1]) & (box[2] <= hi[2]) &
                  (box[5] >= lo[2]);
        for (int k = 0; k < planes; ++k) {
            const F4 low = (pos[k][0] * box[0] + neg[k][0] * box[3]) + (pos[k][1] * box[1] + neg[k][1] * box[4]) +
                           (pos[k][2] * box[2] + neg[k][2] * box[5]);
            keep &= low <= limit[k];
        }
        return keep;
    }
};
} // namespace

bool OccluderBvh::may_block(const SegmentBundle &b) const { return blockers(b, nullptr, 0) != 0; }

int OccluderBvh::blockers(const SegmentBundle &b, int64_t *out, int max) const {
    // The inner nodes' tests run in float: a box is cut off by a plane only when it lies beyond
    // it by more than their rounding (below 1e-6 |n|_1 (|p| + |o| + |d|) inside the scene).
    const float extent = std::max({m_extent, std::abs(b.origin_f[0]), std::abs(b.origin_f[1]), std::abs(b.origin_f[2])});
    NodeTest test;
    for (int c = 0; c < 3; ++c) test.lo[c] = b.lo_f[c], test.hi[c] = b.hi_f[c];
    // Only the four side planes: the box of the end points already bounds the height.
    for (int k = 0; k < 4; ++k)
        test.add(b.normal_f[k], b.limit_f[k] + 4e-6f * b.norm1_f[k] * (2.f * extent + std::abs(b.offset_f[k])));
    int found = 0;
    const bool more = walk(test, [&](uint32_t i) {
        if (!prim_may_block(m_prims[i], b)) return false;
        if (found == max) return true; // one too many: stop
        out[found++] = int64_t(i);
        return false;
    });
    return more ? -1 : found;
}

void OccluderBvh::may_hit(int64_t i, const double a[3], const float *dx, const float *dy, const float *dz,
                          const float *t_max, size_t n, double margin, double per_length, uint8_t *hit) const {
    const Prim &prim = m_prims[size_t(i)];
    if (prim.kind == Kind::Sphere) { // the segment's point nearest to the centre (unit directions)
        const double *c = prim.p[0], r = prim.p[1][0];
        const double ac[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]}, ac2 = dot3(ac, ac);
        for (size_t s = 0; s < n; ++s) {
            const double t = t_max[s];
            if (hit[s] || !(t > 0)) continue;
            const double d[3] = {dx[s], dy[s], dz[s]}, dd = dot3(d, d);
            const double rm = r + margin + per_length * t;
            const double along = std::clamp(dot3(ac, d) / dd, 0.0, t); // parameter of the nearest point
            const double dist2 = ac2 - 2 * along * dot3(ac, d) + along * along * dd;
            hit[s] = dist2 <= rm * rm;
        }
        return;
    }
    for (size_t s = 0; s < n; ++s) {
        const double t = t_max[s];
        if (hit[s] || !(t > 0)) continue;
        const double b[3] = {a[0] + double(dx[s]) * t, a[1] + double(dy[s]) * t, a[2] + double(dz[s]) * t};
        hit[s] = flat_may_hit(prim, a, b, margin + per_length * t);
    }
}

bool OccluderBvh::flat_may_hit(const Prim &prim, const double a[3], const double b[3], double margin) {
    for (int c = 0; c < 3; ++c)
        if (std::max(a[c], b[c]) < prim.lo[c] - margin || std::min(a[c], b[c]) > prim.hi[c] + margin) return false;
    const double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double len2 = dot3(ab, ab);
    if (prim.kind != Kind::Triangle) return true;
    // Both ends beyond the plane on one side, or the point where the segment meets the
    // plane (the nearest end if it stops short) beyond an edge, by more than the margin.
    const double *p0 = prim.p[0], *n = prim.n, tol = margin * prim.n_len;
    const double da = n[0] * (a[0] - p0[0]) + n[1] * (a[1] - p0[1]) + n[2] * (a[2] - p0[2]);
    const double db = n[0] * (b[0] - p0[0]) + n[1] * (b[1] - p0[1]) + n[2] * (b[2] - p0[2]);
    if ((da > tol && db > tol) || (da < -tol && db < -tol)) return false;
    if (!(std::abs(da - db) > 1e-3 * prim.n_len * std::sqrt(len2))) return true; // nearly in the plane
    const double t = std::clamp(da / (da - db), 0.0, 1.0);
    const double q[3] = {a[0] + t * ab[0], a[1] + t * ab[1], a[2] + t * ab[2]};
    for (int k = 0; k < 3; ++k) {
        const double *p = prim.p[k], *p1 = prim.p[(k + 1) % 3];
        const double e[3] = {p1[0] - p[0], p1[1] - p[1], p1[2] - p[2]}, w[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
        double x[3];
        cross3(e, w, x); // (e x w).n = |e| |n| times the signed distance of q from the edge
        if (dot3(x, n) < -margin * std::sqrt(dot3(e, e)) * prim.n_len) return false;
    }
    return true;
}

bool OccluderBvh::may_block(const ConvexRegion &r, int64_t skip) const {
    const float extent = std::max({m_extent, float(std::max(std::abs(r.lo[0]), std::abs(r.hi[0]))),
                                   float(std::max(std::abs(r.lo[1]), std::abs(r.hi[1]))),
                                   float(std::max(std::abs(r.lo[2]), std::abs(r.hi[2])))});
    NodeTest test;
    for (int c = 0; c < 3; ++c) // rounded outwards: the float box holds the double one
        test.lo[c] = std::nextafter(float(r.lo[c]), -INFINITY), test.hi[c] = std::nextafter(float(r.hi[c]), INFINITY);
    for (int k = 0; k < r.planes; ++k) {
        const float n[3] = {float(r.normal[k][0]), float(r.normal[k][1]), float(r.normal[k][2])};
        test.add(n, float(r.offset[k]) + 4e-6f * float(r.normal_len[k]) * (2.f * extent + 1.f) +
                        4e-6f * std::abs(float(r.offset[k])));
    }
    return walk(test, [&](uint32_t i) { return int64_t(i) != skip && prim_may_block(m_prims[i], r); });
}

bool OccluderBvh::prim_may_block(const Prim &prim, const ConvexRegion &r) const {
    const double eps = r.eps;
    for (int c = 0; c < 3; ++c) // the primitive's box against the region's
        if (prim.lo[c] > r.hi[c] || prim.hi[c] < r.lo[c]) return false;
    auto beyond = [&](int k, const double *p) { return dot3(r.normal[k], p) - r.offset[k] > eps * r.normal_len[k]; };
    if (prim.kind == Kind::Triangle) {
        if (plane_separates(prim, r.vertex, r.vertices, eps)) return false;
        for (int k = 0; k < r.planes; ++k) // or by a half-space of the region
            if (beyond(k, prim.p[0]) && beyond(k, prim.p[1]) && beyond(k, prim.p[2])) return false;
        return true;
    }
    if (prim.kind == Kind::Sphere) {
        const double *c = prim.p[0], rad = prim.p[1][0];
        for (int k = 0; k < r.planes; ++k) // |n|_1 >= |n|: the sphere's nearest point is beyond too
            if (dot3(r.normal[k], c) - rad * r.normal_len[k] - r.offset[k] > eps * r.normal_len[k]) return false;
        return true;
    }
    for (int k = 0; k < r.planes; ++k) { // a box: its corner nearest to the inside of each plane
        const double *n = r.normal[k];
        double low = 0;
        for (int c = 0; c < 3; ++c) low += n[c] * (n[c] >= 0 ? prim.p[0][c] : prim.p[1][c]);
        if (low - r.offset[k] > eps * r.normal_len[k]) return false;
    }
    return true;
}

int64_t OccluderBvh::occluder_of(const Shape *shape, uint32_t prim) const {
    auto it = m_shape_occluders.find(shape);
    if (it == m_shape_occluders.end() || prim >= it->second.count) return -1;
    return it->second.first + int64_t(prim);
}

bool OccluderBvh::triangle(int64_t i, double p[3][3], double n[3], double *n_len) const {
    const Prim &prim = m_prims[size_t(i)];
    if (prim.kind != Kind::Triangle) return false;
    std::memcpy(p, prim.p, sizeof(prim.p));
    std::memcpy(n, prim.n, sizeof(prim.n));
    *n_len = prim.n_len;
    return true;
}

void ConvexRegion::add_vertex(const double p[3]) {
    for (int c = 0; c < 3; ++c) vertex[vertices][c] = p[c];
    ++vertices;
}

void ConvexRegion::add_plane(const double n[3], double d) {
    for (int c = 0; c < 3; ++c) normal[planes][c] = n[c];
    offset[planes++] = d;
}

void ConvexRegion::add_support_plane(const double n[3]) {
    double d = -INFINITY;
    for (int v = 0; v < vertices; ++v) d = std::max(d, dot3(n, vertex[v]));
    add_plane(n, d);
}

void ConvexRegion::finish() {
    double scale = 1.0;
    for (int c = 0; c < 3; ++c) {
        lo[c] = INFINITY, hi[c] = -INFINITY;
        for (int v = 0; v < vertices; ++v) lo[c] = std::min(lo[c], vertex[v][c]), hi[c] = std::max(hi[c], vertex[v][c]);
        scale += std::max(std::abs(lo[c]), std::abs(hi[c]));
    }
    for (int k = 0; k < planes; ++k)
        normal_len[k] = std::abs(normal[k][0]) + std::abs(normal[k][1]) + std::abs(normal[k][2]);
    eps = Margin * scale;
}

} // namespace mvpt
