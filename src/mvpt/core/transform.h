// 4x4 affine/projective transforms with cached inverse.
#pragma once

#include "math.h"

namespace mvpt {

/// Row-major 4x4 matrix (double precision: keyframes and long chains of
/// scene-file operations stay exact enough, rays use the float copy).
struct Matrix4 {
    double m[4][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};

    static Matrix4 identity() { return {}; }
    Matrix4 operator*(const Matrix4 &b) const {
        Matrix4 r;
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) {
                double s = 0;
                for (int k = 0; k < 4; ++k) s += m[i][k] * b.m[k][j];
                r.m[i][j] = s;
            }
        return r;
    }
    bool operator==(const Matrix4 &b) const {
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j)
                if (m[i][j] != b.m[i][j]) return false;
        return true;
    }
    Matrix4 transpose() const {
        Matrix4 r;
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) r.m[i][j] = m[j][i];
        return r;
    }
    /// Inverse by Gauss-Jordan elimination; `ok` is false for a singular matrix.
    Matrix4 inverse(bool *ok = nullptr) const;
    double determinant3x3() const {
        return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
               m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
               m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    }
    bool is_finite() const;
};

/// A transform and its inverse.
class Transform {
public:
    Transform() = default;
    explicit Transform(const Matrix4 &m);
    Transform(const Matrix4 &m, const Matrix4 &inv) : m_m(m), m_inv(inv) {}

    static Transform translate(Vec3f t);
    static Transform scale(Vec3f s);
    /// Rotation by `angle_deg` degrees about a unit `axis` (right-handed).
    static Transform rotate(Vec3f axis, float angle_deg);
    /// Camera-to-world frame looking from `origin` at `target` (Mitsuba's convention:
    /// local +z is the view direction, +x is left, +y is up).
    static Transform look_at(Vec3f origin, Vec3f target, Vec3f up);

    Transform operator*(const Transform &b) const { return {m_m * b.m_m, b.m_inv * m_inv}; }
    Transform inverse() const { return {m_inv, m_m}; }
    const Matrix4 &matrix() const { return m_m; }
    const Matrix4 &inverse_matrix() const { return m_inv; }
    bool is_identity() const { return m_m == Matrix4::identity(); }
    /// True when the linear part flips orientation (negative determinant).
    bool flips_handedness() const { return m_m.determinant3x3() < 0; }

    Point3f point(Point3f p) const;
    /// (Inline: an out-of-line call returns the vector in two registers that callers store and
    /// reload across the halves, a failed store-to-load forward per call in hot loops.)
    Vec3f vector(Vec3f v) const {
        return {float(m_m.m[0][0] * v.x + m_m.m[0][1] * v.y + m_m.m[0][2] * v.z),
                float(m_m.m[1][0] * v.x + m_m.m[1][1] * v.y + m_m.m[1][2] * v.z),
                float(m_m.m[2][0] * v.x + m_m.m[2][1] * v.y + m_m.m[2][2] * v.z)};
    }
    /// Normals transform with the inverse transpose; the result is not normalized.
    Normal3f normal(Normal3f n) const;

private:
    Matrix4 m_m, m_inv;
};

} // namespace mvpt
