// The majorants along one ray through a volume: the cells of its majorant grid (MajorantDDA),
// each cell whose bound times length (the expected count of tentative collisions) is large
// halved along the ray, with the volume's own bounds on each half, until the count is small.
// Near an extreme voxel a cell's bound is far above the extinction on most of a ray's way
// through it (a trilinear ramp from 0.1 to 1e30, say): the halves follow the ramp in a number
// of steps that grows with the logarithm of the contrast, not the contrast. Any piecewise-
// constant bound along the ray keeps delta and ratio tracking unbiased; these depend on the
// ray alone, not on the random numbers.
#pragma once

#include "volume.h"

namespace mvpt {

/// A stretch of a ray with one bound of the extinction.
struct MajorantPiece {
    float t = 0.f;      ///< where it starts
    float length = 0.f; ///< how far it reaches
    float bound = 0.f;
    /// When finite, the parameter every point of the piece rounds to: a piece between two
    /// adjacent floats is two halves, each bounded by the extinction at its own end.
    float at = std::numeric_limits<float>::quiet_NaN();

    /// The ray parameter at distance `s` into the piece.
    float point(float s) const { return std::isnan(at) ? std::min(t + s, t + length) : at; }
};

class MajorantWalk {
public:
    /// The walk along `ray` over [t0, t1) through `volume` times `scale`, with `grid` its
    /// majorant grid (already scaled).
    MajorantWalk(const MajorantGrid &grid, const Volume &volume, float scale, const Ray &ray, float t0, float t1);
    /// The next piece, false past t1.
    bool next(MajorantPiece &piece);

    /// Tentative collisions a piece is let have before it is halved.
    static constexpr float SplitCount = 8.f;
    /// Halvings of a grid cell's piece at most (a float's mantissa and some).
    static constexpr int MaxDepth = 48;

private:
    /// A part [t0, t1) of a cell's piece with the volume's bounds there.
    struct Span {
        float t0, t1, hi, lo;
        int depth;
        bool tight; ///< the volume's extremes over the span (ValueBounds::tight)
    };
    /// The volume's bounds between parameters a and b, scaled, `hi` at most `cap`.
    Span span(float a, float b, float cap, int depth) const;
    /// True when halving `s` would not pay.
    bool is_leaf(const Span &s) const;
    /// The bound at parameter t: the extinction's largest channel there.
    float value_at(float t) const;

    MajorantDDA m_dda;
    const Volume &m_volume;
    float m_scale;
    Ray m_ray;
    float m_t;
    Span m_stack[MaxDepth + 2];
    int m_size = 0;
    /// The second half of a piece between adjacent floats, when due.
    MajorantPiece m_pending;
    bool m_has_pending = false;
};

} // namespace mvpt
