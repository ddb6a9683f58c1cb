#include "animation.h"

#include <algorithm>
#include <cmath>

namespace mvpt {

namespace {

Quaternion quat_from_matrix(const double r[3][3]) {
    // Shepperd's method, choosing the largest diagonal term for stability.
    Quaternion q;
    double tr = r[0][0] + r[1][1] + r[2][2];
    if (tr > 0) {
        double s = std::sqrt(tr + 1.0) * 2;
        q = {0.25 * s, (r[2][1] - r[1][2]) / s, (r[0][2] - r[2][0]) / s, (r[1][0] - r[0][1]) / s};
    } else if (r[0][0] > r[1][1] && r[0][0] > r[2][2]) {
        double s = std::sqrt(1.0 + r[0][0] - r[1][1] - r[2][2]) * 2;
        q = {(r[2][1] - r[1][2]) / s, 0.25 * s, (r[0][1] + r[1][0]) / s, (r[0][2] + r[2][0]) / s};
    } else if (r[1][1] > r[2][2]) {
        double s = std::sqrt(1.0 + r[1][1] - r[0][0] - r[2][2]) * 2;
        q = {(r[0][2] - r[2][0]) / s, (r[0][1] + r[1][0]) / s, 0.25 * s, (r[1][2] + r[2][1]) / s};
    } else {
        double s = std::sqrt(1.0 + r[2][2] - r[0][0] - r[1][1]) * 2;
        q = {(r[1][0] - r[0][1]) / s, (r[0][2] + r[2][0]) / s, (r[1][2] + r[2][1]) / s, 0.25 * s};
    }
    return q;
}

Quaternion slerp(Quaternion a, Quaternion b, double t) {
    double d = a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z;
    if (d < 0) { b = {-b.w, -b.x, -b.y, -b.z}; d = -d; }
    double wa, wb;
    if (d > 0.9995) {
        wa = 1 - t; wb = t;
    } else {
        double th = std::acos(std::min(d, 1.0)), s = std::sin(th);
        wa = std::sin((1 - t) * th) / s; wb = std::sin(t * th) / s;
    }
    Quaternion q{wa * a.w + wb * b.w, wa * a.x + wb * b.x, wa * a.y + wb * b.y, wa * a.z + wb * b.z};
    double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
    return {q.w / n, q.x / n, q.y / n, q.z / n};
}

Transform compose(Vec3f s, Quaternion q, Vec3f t) {
    double w = q.w, x = q.x, y = q.y, z = q.z;
    double r[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                      {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                      {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
    // M = T R S; its inverse S^-1 R^T T^-1 in closed form (no general 4x4 inversion per call).
    Matrix4 m, inv;
    double sc[3] = {s.x, s.y, s.z}, tr[3] = {t.x, t.y, t.z};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            m.m[i][j] = r[i][j] * sc[j];
            inv.m[i][j] = r[j][i] / sc[i];
        }
    for (int i = 0; i < 3; ++i) {
        m.m[i][3] = tr[i];
        inv.m[i][3] = -(inv.m[i][0] * tr[0] + inv.m[i][1] * tr[1] + inv.m[i][2] * tr[2]);
    }
    return {m, inv};
}

} // namespace

AnimatedTransform::AnimatedTransform(const Transform &t) {
    TransformKey k;
    k.original = t;
    m_keys.push_back(k);
}

bool AnimatedTransform::from_keys(std::vector<std::pair<float, Transform>> keys, AnimatedTransform &out,
                                  std::string &error) {
    std::stable_sort(keys.begin(), keys.end(), [](auto &a, auto &b) { return a.first < b.first; });
    out.m_keys.clear();
    for (auto &[time, tr] : keys) {
        const Matrix4 &m = tr.matrix();
        if (m.m[3][0] != 0 || m.m[3][1] != 0 || m.m[3][2] != 0 || m.m[3][3] != 1) {
            error = "an animation keyframe must be affine (no projective part)";
            return false;
        }
        TransformKey k;
        k.time = time;
        k.original = tr;
        double cols[3][3], sc[3];
        for (int j = 0; j < 3; ++j) {
            for (int i = 0; i < 3; ++i) cols[j][i] = m.m[i][j];
            sc[j] = std::sqrt(cols[j][0] * cols[j][0] + cols[j][1] * cols[j][1] + cols[j][2] * cols[j][2]);
            if (sc[j] == 0) { error = "an animation keyframe has a zero scale"; return false; }
        }
        if (m.determinant3x3() < 0) sc[0] = -sc[0]; // keep R a proper rotation
        double r[3][3];
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) r[i][j] = cols[j][i] / sc[j];
        for (int a = 0; a < 3; ++a)
            for (int b = a + 1; b < 3; ++b) {
                double d = r[0][a] * r[0][b] + r[1][a] * r[1][b] + r[2][a] * r[2][b];
                if (std::abs(d) > 1e-4) {
                    error = "an animation keyframe contains a shear, which cannot be interpolated";
                    return false;
                }
            }
        k.scale = {float(sc[0]), float(sc[1]), float(sc[2])};
        k.rotation = quat_from_matrix(r);
        k.translation = {float(m.m[0][3]), float(m.m[1][3]), float(m.m[2][3])};
        out.m_keys.push_back(k);
    }
    return true;
}

Transform AnimatedTransform::eval(float time) const {
    if (m_keys.empty()) return {};
    if (m_keys.size() == 1 || time <= m_keys.front().time) return m_keys.front().original;
    if (time >= m_keys.back().time) return m_keys.back().original;
    size_t i = 0;
    while (i + 2 < m_keys.size() && m_keys[i + 1].time <= time) ++i;
    const TransformKey &a = m_keys[i], &b = m_keys[i + 1];
    float t = (b.time > a.time) ? (time - a.time) / (b.time - a.time) : 0.f;
    return compose(lerp(t, a.scale, b.scale), slerp(a.rotation, b.rotation, t), lerp(t, a.translation, b.translation));
}

} // namespace mvpt
