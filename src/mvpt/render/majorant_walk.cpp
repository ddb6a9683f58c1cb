#include "majorant_walk.h"

namespace mvpt {

MajorantWalk::MajorantWalk(const MajorantGrid &grid, const Volume &volume, float scale, const Ray &ray, float t0,
                           float t1)
    : m_dda(grid, ray, t0, t1), m_volume(volume), m_scale(scale), m_ray(ray), m_t(t0) {}

MajorantWalk::Span MajorantWalk::span(float a, float b, float cap, int depth) const {
    const ValueBounds v = m_volume.segment_bounds(m_ray.at(a), m_ray.at(b));
    return {a, b, std::min(cap, v.hi * m_scale), v.lo * m_scale, depth, v.tight};
}

bool MajorantWalk::is_leaf(const Span &s) const {
    return !(s.hi * (s.t1 - s.t0) > SplitCount) || s.lo >= 0.5f * s.hi || s.depth >= MaxDepth;
}

float MajorantWalk::value_at(float t) const { return m_volume.eval(m_ray.at(t)).max_value() * m_scale; }

bool MajorantWalk::next(MajorantPiece &piece) {
    if (m_has_pending) {
        piece = m_pending;
        m_has_pending = false;
        return true;
    }
    if (m_size == 0) {
        float t_end, bound;
        const float t = m_t;
        if (!m_dda.next(t_end, bound)) return false;
        m_t = t_end;
        piece = MajorantPiece{t, t_end - t, bound};
        // Only a finite piece with many tentative collisions, of a volume that can say more.
        if (!m_volume.refines_bounds() || !(bound * piece.length > SplitCount) || !std::isfinite(piece.length))
            return true;
        m_stack[m_size++] = span(t, t_end, bound, 0);
    }
    for (;;) {
        const Span s = m_stack[--m_size];
        if (is_leaf(s)) {
            piece = MajorantPiece{s.t0, s.t1 - s.t0, s.hi};
            return true;
        }
        const float mid = 0.5f * (s.t0 + s.t1);
        if (!(mid > s.t0 && mid < s.t1)) {
            // No float between the ends: each half holds the extinction at its end.
            const float half = 0.5f * (s.t1 - s.t0);
            piece = MajorantPiece{s.t0, half, value_at(s.t0), s.t0};
            m_pending = MajorantPiece{s.t0, half, value_at(s.t1), s.t1};
            m_has_pending = true;
            return true;
        }
        const Span first = span(s.t0, mid, s.hi, s.depth + 1), second = span(mid, s.t1, s.hi, s.depth + 1);
        if (first.tight && second.tight && first.hi >= s.hi && second.hi >= s.hi && first.lo <= s.lo &&
            second.lo <= s.lo) {
            // Halving tightens neither bound: the extinction spans as much on both halves.
            piece = MajorantPiece{s.t0, s.t1 - s.t0, s.hi};
            return true;
        }
        m_stack[m_size++] = second;
        m_stack[m_size++] = first;
    }
}

} // namespace mvpt
