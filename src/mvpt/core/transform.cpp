#include "transform.h"

#include <cmath>
#include <utility>

namespace mvpt {

Matrix4 Matrix4::inverse(bool *ok) const {
    double a[4][8];
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            a[i][j] = m[i][j];
            a[i][j + 4] = (i == j) ? 1.0 : 0.0;
        }
    for (int c = 0; c < 4; ++c) {
        int piv = c;
        for (int r = c + 1; r < 4; ++r)
            if (std::abs(a[r][c]) > std::abs(a[piv][c])) piv = r;
        if (std::abs(a[piv][c]) < 1e-300) {
            if (ok) *ok = false;
            return {};
        }
        if (piv != c)
            for (int j = 0; j < 8; ++j) std::swap(a[c][j], a[piv][j]);
        double inv = 1.0 / a[c][c];
        for (int j = 0; j < 8; ++j) a[c][j] *= inv;
        for (int r = 0; r < 4; ++r) {
            if (r == c) continue;
            double f = a[r][c];
            if (f == 0.0) continue;
            for (int j = 0; j < 8; ++j) a[r][j] -= f * a[c][j];
        }
    }
    Matrix4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r.m[i][j] = a[i][j + 4];
    if (ok) *ok = true;
    return r;
}

bool Matrix4::is_finite() const {
    for (auto &row : m)
        for (double v : row)
            if (!std::isfinite(v)) return false;
    return true;
}

Transform::Transform(const Matrix4 &m) : m_m(m) {
    bool ok = true;
    m_inv = m.inverse(&ok);
    if (!ok) m_inv = Matrix4(); // singular: callers validate with matrix checks
}

Transform Transform::translate(Vec3f t) {
    Matrix4 m, inv;
    m.m[0][3] = t.x; m.m[1][3] = t.y; m.m[2][3] = t.z;
    inv.m[0][3] = -t.x; inv.m[1][3] = -t.y; inv.m[2][3] = -t.z;
    return {m, inv};
}

Transform Transform::scale(Vec3f s) {
    Matrix4 m, inv;
    m.m[0][0] = s.x; m.m[1][1] = s.y; m.m[2][2] = s.z;
    inv.m[0][0] = 1.0 / s.x; inv.m[1][1] = 1.0 / s.y; inv.m[2][2] = 1.0 / s.z;
    return {m, inv};
}

Transform Transform::rotate(Vec3f axis, float angle_deg) {
    // Like Mitsuba 3 (drjit's rotate), the axis is used as given: a unit axis gives
    // a rotation; other lengths give the same (non-rigid) matrix Mitsuba builds.
    double x = axis.x, y = axis.y, z = axis.z;
    double th = angle_deg * 3.14159265358979323846 / 180.0;
    double c = std::cos(th), s = std::sin(th), t = 1 - c;
    Matrix4 m;
    m.m[0][0] = t * x * x + c;     m.m[0][1] = t * x * y - s * z; m.m[0][2] = t * x * z + s * y;
    m.m[1][0] = t * x * y + s * z; m.m[1][1] = t * y * y + c;     m.m[1][2] = t * y * z - s * x;
    m.m[2][0] = t * x * z - s * y; m.m[2][1] = t * y * z + s * x; m.m[2][2] = t * z * z + c;
    return Transform(m);
}

Transform Transform::look_at(Vec3f origin, Vec3f target, Vec3f up) {
    auto norm3 = [](double v[3]) {
        double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        for (int i = 0; i < 3; ++i) v[i] /= l;
    };
    auto cross3 = [](const double a[3], const double b[3], double r[3]) {
        r[0] = a[1] * b[2] - a[2] * b[1];
        r[1] = a[2] * b[0] - a[0] * b[2];
        r[2] = a[0] * b[1] - a[1] * b[0];
    };
    double dir[3] = {double(target.x) - origin.x, double(target.y) - origin.y, double(target.z) - origin.z};
    norm3(dir);
    double upd[3] = {up.x, up.y, up.z}, left[3], new_up[3];
    norm3(upd);
    cross3(upd, dir, left);
    norm3(left);
    cross3(dir, left, new_up);
    Matrix4 m;
    for (int i = 0; i < 3; ++i) {
        m.m[i][0] = left[i];
        m.m[i][1] = new_up[i];
        m.m[i][2] = dir[i];
    }
    m.m[0][3] = origin.x; m.m[1][3] = origin.y; m.m[2][3] = origin.z;
    return Transform(m);
}

Point3f Transform::point(Point3f p) const {
    double r[4];
    for (int i = 0; i < 4; ++i)
        r[i] = m_m.m[i][0] * p.x + m_m.m[i][1] * p.y + m_m.m[i][2] * p.z + m_m.m[i][3];
    if (r[3] != 1.0) return {float(r[0] / r[3]), float(r[1] / r[3]), float(r[2] / r[3])};
    return {float(r[0]), float(r[1]), float(r[2])};
}

Normal3f Transform::normal(Normal3f n) const {
    return {float(m_inv.m[0][0] * n.x + m_inv.m[1][0] * n.y + m_inv.m[2][0] * n.z),
            float(m_inv.m[0][1] * n.x + m_inv.m[1][1] * n.y + m_inv.m[2][1] * n.z),
            float(m_inv.m[0][2] * n.x + m_inv.m[1][2] * n.y + m_inv.m[2][2] * n.z)};
}

} // namespace mvpt
