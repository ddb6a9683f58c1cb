#include "rig_visibility.h"

#include "../core/sampler.h"
#include "double3.h"

#include <algorithm>
#include <cmath>
#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace mvpt {

namespace {
bool normalize3(double *a) {
    const double l = std::sqrt(dot3(a, a));
    if (!(l > 1e-12) || !std::isfinite(l)) return false;
    for (int c = 0; c < 3; ++c) a[c] /= l;
    return true;
}
/// A unit vector perpendicular to unit `a`.
void perpendicular(const double *a, double *out) {
    const double e[3] = {std::abs(a[0]) < 0.6 ? 1.0 : 0.0, std::abs(a[0]) < 0.6 ? 0.0 : 1.0, 0.0};
    cross3(a, e, out);
    normalize3(out);
}
/// The part of `v` perpendicular to unit `a`, normalised; any perpendicular if that is too short.
void orthonormal(const double *v, const double *a, double *out) {
    const double d = dot3(v, a);
    for (int c = 0; c < 3; ++c) out[c] = v[c] - d * a[c];
    if (dot3(out, out) < 1e-8 || !normalize3(out)) perpendicular(a, out);
}
} // namespace

RigVisibility::RigVisibility(const OccluderBvh &occluders, const std::vector<Point3f> &lens_points, Vec3f across,
                             int cells)
    : m_occ(occluders) {
    // The rig's box in the frame (e1 along `across`, e2 along the widest spread across it, e3).
    double mean[3] = {0, 0, 0};
    for (const Point3f &p : lens_points) mean[0] += p.x, mean[1] += p.y, mean[2] += p.z;
    for (double &m : mean) m /= double(std::max<size_t>(lens_points.size(), 1));
    double e[3][3];
    const double acr[3] = {across.x, across.y, across.z};
    std::copy(acr, acr + 3, e[0]);
    if (!normalize3(e[0])) e[0][0] = 1, e[0][1] = e[0][2] = 0;
    std::copy(e[0], e[0] + 3, m_across);
    double widest[3] = {0, 0, 0}, widest_len = 0;
    for (const Point3f &p : lens_points) {
        const double q[3] = {p.x - mean[0], p.y - mean[1], p.z - mean[2]};
        const double d = dot3(q, e[0]);
        const double r[3] = {q[0] - d * e[0][0], q[1] - d * e[0][1], q[2] - d * e[0][2]};
        if (dot3(r, r) > widest_len) widest_len = dot3(r, r), std::copy(r, r + 3, widest);
    }
    orthonormal(widest, e[0], e[1]);
    cross3(e[0], e[1], e[2]);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (const Point3f &p : lens_points) {
        const double q[3] = {p.x - mean[0], p.y - mean[1], p.z - mean[2]};
        for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], dot3(q, e[k])), hi[k] = std::max(hi[k], dot3(q, e[k]));
    }
    // Widened relatively: the box holds the float lens points despite the rounding of the frame.
    double scale = 1.0;
    for (const Point3f &p : lens_points) scale = std::max({scale, double(std::abs(p.x)), double(std::abs(p.y)), double(std::abs(p.z))});
    for (int k = 0; k < 3; ++k) lo[k] -= 1e-6 * scale, hi[k] += 1e-6 * scale;
    for (int i = 0; i < 8; ++i)
        for (int c = 0; c < 3; ++c)
            m_rig[i][c] = mean[c] + (i & 1 ? hi[0] : lo[0]) * e[0][c] + (i & 2 ? hi[1] : lo[1]) * e[1][c] +
                          (i & 4 ? hi[2] : lo[2]) * e[2][c];
    for (int c = 0; c < 3; ++c) m_rig_centre[c] = mean[c];

    // The grid over the occluders' box, cubic cells.
    double extent = 0;
    for (int c = 0; c < 3; ++c) extent = std::max(extent, occluders.upper()[c] - occluders.lower()[c]);
    m_size = std::max(extent, 1e-6) / double(std::max(cells, 1));
    for (int c = 0; c < 3; ++c) {
        m_lo[c] = occluders.lower()[c];
        m_dims[c] = std::max(1, int(std::ceil((occluders.upper()[c] - m_lo[c]) / m_size)));
        m_lo_f[c] = float(m_lo[c]);
    }
    m_inv_size_f = float(1.0 / m_size);
    m_keyed.resize(occluders.size());
    for (size_t i = 0; i < occluders.size(); ++i) {
        double p[3][3], n[3], n_len;
        m_keyed[i] = occluders.is_sphere(int64_t(i)) ||
                     (occluders.triangle(int64_t(i), p, n, &n_len) && 0.5 * n_len >= 0.25 * m_size * m_size);
    }
    m_table = TableMemory(size_t(1) << TableBits);
}

RigVisibility::~RigVisibility() = default;

RigVisibility::TableMemory::TableMemory(size_t entries) : m_bytes(entries * sizeof(std::atomic<uint64_t>)) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    // Anonymous pages (zero-filled: every entry empty), in 2 MB pages where the kernel allows:
    // the entries are read at random, and with 4 KB pages nearly every read also missed the TLB.
    constexpr size_t Huge = size_t(2) << 20;
    m_mapped = m_bytes + Huge;
    void *p = mmap(nullptr, m_mapped, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) throw std::bad_alloc();
    m_base = p;
    char *aligned = reinterpret_cast<char *>((reinterpret_cast<uintptr_t>(p) + Huge - 1) & ~uintptr_t(Huge - 1));
    madvise(aligned, m_bytes, MADV_HUGEPAGE); // a hint: without it the table still works
    m_entries = reinterpret_cast<std::atomic<uint64_t> *>(aligned);
    for (size_t i = 0; i < entries; ++i) new (m_entries + i) std::atomic<uint64_t>(0);
#else
    m_entries = new std::atomic<uint64_t>[entries];
    for (size_t i = 0; i < entries; ++i) m_entries[i].store(0, std::memory_order_relaxed);
#endif
}

RigVisibility::TableMemory &RigVisibility::TableMemory::operator=(TableMemory &&o) noexcept {
    std::swap(m_entries, o.m_entries), std::swap(m_base, o.m_base);
    std::swap(m_bytes, o.m_bytes), std::swap(m_mapped, o.m_mapped);
    return *this;
}

RigVisibility::TableMemory::~TableMemory() {
    if (!m_entries) return;
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    munmap(m_base, m_mapped);
#else
    delete[] m_entries;
#endif
}

bool RigVisibility::finest_cell(Point3f o, int64_t finest[3]) const {
    const float fx = (o.x - m_lo_f[0]) * m_inv_size_f, fy = (o.y - m_lo_f[1]) * m_inv_size_f,
                fz = (o.z - m_lo_f[2]) * m_inv_size_f;
    // (Negated comparisons: NaN fails them.)
    if (!(fx >= 0.f && fy >= 0.f && fz >= 0.f && fx < float(m_dims[0]) && fy < float(m_dims[1]) &&
          fz < float(m_dims[2])))
        return false;
    finest[0] = int64_t(fx), finest[1] = int64_t(fy), finest[2] = int64_t(fz);
    return true;
}

uint64_t RigVisibility::cell_key(const int64_t finest[3], int level, int64_t own, int64_t idx[3]) const {
    const int shift = Levels - 1 - level;
    int64_t dims[3];
    for (int c = 0; c < 3; ++c) idx[c] = finest[c] >> shift, dims[c] = (m_dims[c] + (1 << shift) - 1) >> shift;
    const uint64_t cells = uint64_t(m_dims[0]) * uint64_t(m_dims[1]) * uint64_t(m_dims[2]);
    const uint64_t cell = uint64_t((idx[2] * dims[1] + idx[1]) * dims[0] + idx[0]);
    return ((uint64_t(level) * cells + cell) * uint64_t(m_occ.size()) + uint64_t(own)) + 1;
}

bool RigVisibility::unblocked(Point3f o, int64_t own) const {
    int64_t finest[3];
    if (own < 0 || !m_keyed[size_t(own)] || !finest_cell(o, finest)) return false;
    // From coarse to fine: a coarse cell that is unblocked settles it; otherwise its sub-cell
    // holding o may still be.
    for (int level = 0; level < Levels; ++level) {
        int64_t idx[3];
        const uint64_t key = cell_key(finest, level, own, idx);
        bool found = false, free = false;
        for (uint64_t probe = 0, slot = mix_bits(key) & TableMask; probe < MaxProbes && !found;
             ++probe, slot = (slot + 1) & TableMask) {
            uint64_t e = m_table[slot].load(std::memory_order_relaxed);
            if (e == 0) {
                free = evaluate(idx, Levels - 1 - level, own);
                if (m_table[slot].compare_exchange_strong(e, key << 1 | uint64_t(free), std::memory_order_relaxed)) {
                    found = true;
                    break;
                }
            }
            if (e >> 1 == key) found = true, free = (e & 1) != 0;
        }
        if (!found) free = evaluate(idx, Levels - 1 - level, own); // the table is full around this key: not cached
        if (free) return true;
    }
    return false;
}

void RigVisibility::prefetch(Point3f o, int64_t own) const {
    int64_t finest[3], idx[3];
    if (own < 0 || !m_keyed[size_t(own)] || !finest_cell(o, finest)) return;
    for (int level = 0; level < Levels; ++level)
        __builtin_prefetch(&m_table[mix_bits(cell_key(finest, level, own, idx)) & TableMask]);
}

bool RigVisibility::evaluate(const int64_t idx[3], int shift, int64_t own) const {
    m_evaluated.fetch_add(1, std::memory_order_relaxed);
    // The cell, widened beyond the float rounding of the lookup.
    const double size = m_size * double(int64_t(1) << shift);
    double lo[3], hi[3], coord = 0;
    for (int c = 0; c < 3; ++c) {
        lo[c] = m_lo[c] + double(idx[c]) * size, hi[c] = lo[c] + size;
        coord = std::max({coord, std::abs(lo[c]), std::abs(hi[c])});
    }
    const double pad = 1e-5 * (1.0 + coord);
    for (int c = 0; c < 3; ++c) lo[c] -= pad, hi[c] += pad;

    // The segments lie in the hull of the cell and the rig's box.
    ConvexRegion r;
    for (int i = 0; i < 8; ++i) {
        const double p[3] = {i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1], i & 4 ? hi[2] : lo[2]};
        r.add_vertex(p);
    }
    for (int i = 0; i < 8; ++i) r.add_vertex(m_rig[i]);
    add_wedge(lo, hi, r);
    add_own_plane(lo, hi, own, r);
    r.finish();
    return !m_occ.may_block(r, own);
}

void RigVisibility::add_wedge(const double lo[3], const double hi[3], ConvexRegion &r) const {
    // A wedge around the axis a from the cell's centre to the rig's (its sides from the slopes
    // of the rig's corners seen from the cell's centre), and caps along a.
    const double centre[3] = {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
    double a[3] = {m_rig_centre[0] - centre[0], m_rig_centre[1] - centre[1], m_rig_centre[2] - centre[2]};
    if (!normalize3(a)) return;
    double u[3], v[3];
    orthonormal(m_across, a, u);
    cross3(a, u, v);
    double su_lo = INFINITY, su_hi = -INFINITY, sv_lo = INFINITY, sv_hi = -INFINITY;
    bool wedge = true;
    for (int i = 0; i < 8 && wedge; ++i) {
        const double q[3] = {m_rig[i][0] - centre[0], m_rig[i][1] - centre[1], m_rig[i][2] - centre[2]};
        const double h = dot3(q, a);
        wedge = h > 0.25 * std::sqrt(dot3(q, q));
        const double su = dot3(q, u) / h, sv = dot3(q, v) / h;
        su_lo = std::min(su_lo, su), su_hi = std::max(su_hi, su);
        sv_lo = std::min(sv_lo, sv), sv_hi = std::max(sv_hi, sv);
    }
    if (wedge) {
        double n[4][3];
        for (int c = 0; c < 3; ++c) {
            n[0][c] = u[c] - su_hi * a[c], n[1][c] = su_lo * a[c] - u[c];
            n[2][c] = v[c] - sv_hi * a[c], n[3][c] = sv_lo * a[c] - v[c];
        }
        for (auto &nk : n) r.add_support_plane(nk);
    }
    const double minus_a[3] = {-a[0], -a[1], -a[2]};
    r.add_support_plane(a);
    r.add_support_plane(minus_a);
}

void RigVisibility::add_own_plane(const double lo[3], const double hi[3], int64_t own, ConvexRegion &r) const {
    // The plane of the triangle that y lies on: when the whole rig is strictly on one side of
    // it, so is every segment (it leaves y offset towards its lens point, by at least
    // ~4e-6 (1 + |y|), interaction.h), so the segments keep above a height tol.
    double tp[3][3], tn[3], tn_len;
    if (!m_occ.triangle(own, tp, tn, &tn_len) || !(tn_len > 0)) return;
    double lo_coord = 0;
    for (int c = 0; c < 3; ++c)
        if (lo[c] > 0 || hi[c] < 0) lo_coord = std::max(lo_coord, std::min(std::abs(lo[c]), std::abs(hi[c])));
    const double tol = 1e-6 * (1.0 + lo_coord);
    double nh[3] = {tn[0] / tn_len, tn[1] / tn_len, tn[2] / tn_len};
    double h_min = INFINITY, h_max = -INFINITY;
    for (const auto &p : m_rig) {
        const double q[3] = {p[0] - tp[0][0], p[1] - tp[0][1], p[2] - tp[0][2]};
        h_min = std::min(h_min, dot3(nh, q)), h_max = std::max(h_max, dot3(nh, q));
    }
    if (h_max < 0) { // orient towards the rig
        for (double &c : nh) c = -c;
        h_min = -h_max;
    }
    if (h_min > 2 * tol) {
        const double below[3] = {-nh[0], -nh[1], -nh[2]}; // -h <= -tol
        r.add_plane(below, -(dot3(nh, tp[0]) + tol));
    }
}

} // namespace mvpt
