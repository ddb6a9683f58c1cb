#include "camera_path.h"

#include <cmath>

namespace mvpt {

bool parse_path_interpolation(const std::string &name, PathInterpolation *out) {
    if (name == "linear") *out = PathInterpolation::Linear;
    else if (name == "smooth") *out = PathInterpolation::Smooth;
    else return false;
    return true;
}

namespace {

double number(const JsonValue &v, const std::string &what) {
    if (v.kind != JsonValue::Kind::Number) throw SceneError(v.loc, what + ": expected a number, got " + v.kind_name());
    return v.number;
}

Vec3f vec3(const JsonValue &v, const std::string &what) {
    if (v.kind != JsonValue::Kind::Array || v.items.size() != 3)
        throw SceneError(v.loc, what + ": expected an array of 3 numbers");
    return {float(number(v.items[0], what)), float(number(v.items[1], what)), float(number(v.items[2], what))};
}

/// A key's "matrix": 16 numbers or 4 rows of 4, row-major; must be a rigid, unmirrored pose.
Matrix4 matrix(const JsonValue &v) {
    const char *what = "key 'matrix'";
    std::vector<double> l;
    if (v.kind == JsonValue::Kind::Array && v.items.size() == 4 && v.items[0].kind == JsonValue::Kind::Array) {
        for (auto &row : v.items) {
            if (row.kind != JsonValue::Kind::Array || row.items.size() != 4)
                throw SceneError(row.loc, std::string(what) + ": expected 4 rows of 4 numbers");
            for (auto &x : row.items) l.push_back(number(x, what));
        }
    } else if (v.kind == JsonValue::Kind::Array && v.items.size() == 16) {
        for (auto &x : v.items) l.push_back(number(x, what));
    } else {
        throw SceneError(v.loc, std::string(what) + ": expected 16 numbers (row-major) or 4 rows of 4");
    }
    Matrix4 m;
    for (int i = 0; i < 16; ++i) m.m[i / 4][i % 4] = l[i];
    if (m.m[3][0] != 0 || m.m[3][1] != 0 || m.m[3][2] != 0 || m.m[3][3] != 1)
        throw SceneError(v.loc, std::string(what) + ": the last row must be 0 0 0 1");
    for (int i = 0; i < 3; ++i)
        for (int j = i; j < 3; ++j) {
            double d = m.m[0][i] * m.m[0][j] + m.m[1][i] * m.m[1][j] + m.m[2][i] * m.m[2][j];
            if (std::abs(d - (i == j ? 1.0 : 0.0)) > 1e-3)
                throw SceneError(v.loc, std::string(what) + ": a camera pose must be a rigid motion (no scale or shear)");
        }
    if (m.determinant3x3() < 0) throw SceneError(v.loc, std::string(what) + ": a camera pose must not mirror");
    return m;
}

CameraKey read_key(const JsonValue &k) {
    if (k.kind != JsonValue::Kind::Object) throw SceneError(k.loc, std::string("a key must be an object, got ") + k.kind_name());
    CameraKey key;
    key.loc = k.loc;
    const JsonValue *time = k.find("time");
    if (!time) throw SceneError(k.loc, "a key needs a \"time\"");
    key.time = float(number(*time, "key 'time'"));
    const JsonValue *m = k.find("matrix");
    const JsonValue *pos = k.find("position"), *tgt = k.find("target"), *up = k.find("up");
    for (auto &[name, value] : k.members)
        if (name != "time" && name != "matrix" && name != "position" && name != "target" && name != "up")
            throw SceneError(value.loc, "unknown key field \"" + name + "\" (expected time, position, target, up or matrix)");
    if (m) {
        if (pos || tgt || up) throw SceneError(k.loc, "a key gives either \"matrix\" or \"position\"/\"target\"/\"up\", not both");
        Matrix4 mm = matrix(*m);
        key.position = {float(mm.m[0][3]), float(mm.m[1][3]), float(mm.m[2][3])};
        key.up = {float(mm.m[0][1]), float(mm.m[1][1]), float(mm.m[2][1])};
        key.target = key.position + Vec3f(float(mm.m[0][2]), float(mm.m[1][2]), float(mm.m[2][2]));
        return key;
    }
    if (!pos || !tgt) throw SceneError(k.loc, "a key needs \"position\" and \"target\" (or a \"matrix\")");
    key.position = vec3(*pos, "key 'position'");
    key.target = vec3(*tgt, "key 'target'");
    if (up) key.up = vec3(*up, "key 'up'");
    Vec3f dir = key.target - key.position;
    if (!(squared_norm(dir) > 0.f)) throw SceneError(tgt->loc, "key 'target' coincides with its 'position'");
    if (!(squared_norm(up ? key.up : Vec3f(0, 1, 0)) > 0.f) || squared_norm(cross(normalize(key.up), normalize(dir))) < 1e-12f)
        throw SceneError(up ? up->loc : k.loc, "key 'up' is parallel to the view direction (or zero)");
    return key;
}

/// Cubic Hermite basis on [0, 1] for values a, b and (time-scaled) tangents ma, mb.
Vec3f hermite(float s, Vec3f a, Vec3f b, Vec3f ma, Vec3f mb) {
    float s2 = s * s, s3 = s2 * s;
    return a * (2 * s3 - 3 * s2 + 1) + ma * (s3 - 2 * s2 + s) + b * (-2 * s3 + 3 * s2) + mb * (s3 - s2);
}

} // namespace

CameraPath CameraPath::from_json(const JsonValue &doc) {
    CameraPath path;
    path.loc = doc.loc;
    const JsonValue *keys = &doc;
    if (doc.kind == JsonValue::Kind::Object) {
        for (auto &[name, value] : doc.members)
            if (name != "keys" && name != "interpolation")
                throw SceneError(value.loc, "unknown field \"" + name + "\" (expected \"keys\" and \"interpolation\")");
        keys = doc.find("keys");
        if (!keys) throw SceneError(doc.loc, "the camera path needs a \"keys\" array");
        if (const JsonValue *interp = doc.find("interpolation")) {
            if (interp->kind != JsonValue::Kind::String || !parse_path_interpolation(interp->string, &path.interpolation))
                throw SceneError(interp->loc, "\"interpolation\" must be \"linear\" or \"smooth\"");
            path.loc = interp->loc;
        }
    }
    if (keys->kind != JsonValue::Kind::Array) throw SceneError(keys->loc, "\"keys\" must be an array of keyframes");
    if (keys->items.empty()) throw SceneError(keys->loc, "the camera path has no keys");
    for (auto &k : keys->items) {
        CameraKey key = read_key(k);
        if (!path.m_keys.empty() && !(key.time > path.m_keys.back().time))
            throw SceneError(k.loc, "key times must increase: " + std::to_string(key.time) + " follows " +
                                        std::to_string(path.m_keys.back().time));
        path.m_keys.push_back(key);
    }
    return path;
}

CameraPath CameraPath::read(const std::filesystem::path &file) { return from_json(read_json_file(file)); }

void CameraPath::eval(float time, Vec3f *position, Vec3f *target, Vec3f *up) const {
    const std::vector<CameraKey> &k = m_keys;
    auto set = [&](const CameraKey &key) { *position = key.position; *target = key.target; *up = key.up; };
    if (k.size() == 1 || time <= k.front().time) return set(k.front());
    if (time >= k.back().time) return set(k.back());
    size_t i = 0;
    while (i + 2 < k.size() && k[i + 1].time <= time) ++i;
    const CameraKey &a = k[i], &b = k[i + 1];
    float h = b.time - a.time, s = (time - a.time) / h;
    if (interpolation == PathInterpolation::Linear) {
        *position = lerp(s, a.position, b.position);
        *target = lerp(s, a.target, b.target);
        *up = lerp(s, a.up, b.up);
        return;
    }
    // Catmull-Rom tangent at key j for the member `f` (non-uniform times), times h for [0, 1].
    auto tangent = [&](size_t j, Vec3f CameraKey::*f) {
        size_t lo = j > 0 ? j - 1 : j, hi = j + 1 < k.size() ? j + 1 : j;
        return (k[hi].*f - k[lo].*f) * (h / (k[hi].time - k[lo].time));
    };
    for (auto [out, f] : {std::pair{position, &CameraKey::position}, std::pair{target, &CameraKey::target},
                          std::pair{up, &CameraKey::up}})
        *out = hermite(s, a.*f, b.*f, tangent(i, f), tangent(i + 1, f));
}

Transform CameraPath::pose(float time) const {
    Vec3f p, t, u;
    eval(time, &p, &t, &u);
    Vec3f dir = t - p;
    if (!(squared_norm(dir) > 1e-12f) || !(squared_norm(u) > 0.f) ||
        squared_norm(cross(normalize(u), normalize(dir))) < 1e-10f)
        throw SceneError(loc, "the camera path is degenerate at time " + std::to_string(time) +
                                  " (the interpolated target meets the position, or up is along the view direction)");
    return Transform::look_at(p, t, u);
}

} // namespace mvpt
