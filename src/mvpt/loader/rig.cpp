// Rig specifications and the poses of the generated views (see rig.h for the rig types).
#include "rig.h"

#include "camera_path.h"
#include "parse_values.h"
#include "../core/suggest.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>

namespace mvpt {

namespace fs = std::filesystem;

namespace {

const std::vector<std::string> kRigTypes = {"stereo", "linear", "grid", "orbit", "path"};
/// The most views a rig makes.
constexpr int64_t MaxRigViews = 100000;

/// Parameters of one rig type, read with checks; every given parameter must be known.
class RigParams {
public:
    RigParams(const RigSpec &spec, std::vector<std::string> known) : m_spec(spec) {
        for (auto &[name, p] : spec.params)
            if (std::find(known.begin(), known.end(), name) == known.end()) {
                std::string list;
                for (auto &k : known) list += (list.empty() ? "" : ", ") + k;
                std::string hint = did_you_mean(name, known);
                throw SceneError(p.loc, spec.prefix() + "the " + spec.type + " rig has no parameter '" + name + "'" +
                                            (hint.empty() ? " (expected: " + list + ")" : hint));
            }
    }

    bool has(const std::string &name) const { return m_spec.params.count(name) != 0; }
    const FileLoc &loc(const std::string &name) const {
        auto it = m_spec.params.find(name);
        return it == m_spec.params.end() ? m_spec.loc : it->second.loc;
    }
    std::string what(const std::string &name) const { return m_spec.prefix() + m_spec.type + " rig '" + name + "'"; }
    [[noreturn]] void fail(const std::string &name, const std::string &msg) const {
        throw SceneError(loc(name), what(name) + " " + msg);
    }

    const std::string &string(const std::string &name) const {
        auto it = m_spec.params.find(name);
        if (it == m_spec.params.end())
            throw SceneError(m_spec.loc, m_spec.prefix() + "the " + m_spec.type + " rig needs '" + name + "'");
        return it->second.value;
    }
    /// A finite number small enough that the views made with it stay finite in single precision.
    double number(const std::string &name) const {
        const double v = parse_float(string(name), loc(name), what(name));
        if (std::fabs(v) > 1e30) fail(name, "must lie within +-1e30, got " + string(name));
        return v;
    }
    double number(const std::string &name, double def) const { return has(name) ? number(name) : def; }
    /// A positive length (NaN, infinity, zero and negative values are errors).
    double length(const std::string &name) const {
        double v = number(name);
        if (!(v > 0)) fail(name, "must be a length > 0, got " + string(name));
        return v;
    }
    /// The number of views along one direction: at least one.
    int count(const std::string &name) const {
        int64_t v = parse_int(string(name), loc(name), what(name));
        if (v < 1) fail(name, "must be at least 1: a rig must produce at least one view (got " + std::to_string(v) + ")");
        if (v > MaxRigViews) fail(name, "is too large (" + std::to_string(v) + " views: at most " + std::to_string(MaxRigViews) + ")");
        return int(v);
    }

private:
    const RigSpec &m_spec;
};

std::string numbered(const char *prefix, int i, int digits) {
    char buf[32];
    std::snprintf(buf, sizeof(buf), "%s%0*d", prefix, digits, i);
    return buf;
}

/// A view translated by (dx, dy) in the base camera's x/y plane; with a focus distance the
/// frustum is sheared so that the base's plane at depth D stays on the same pixels (rig.h).
RigView translated(const RigBase &base, std::string id, double dx, double dy, double focus_distance) {
    RigView v;
    v.id = std::move(id);
    v.to_world = base.to_world * Transform::translate(Vec3f(float(dx), float(dy), 0.f));
    v.ppo_x = base.ppo_x;
    v.ppo_y = base.ppo_y;
    if (focus_distance > 0) {
        // A point (X, Y, D) of the base maps to the near-plane point ((X - dx) / D, (Y - dy) / D) of
        // the view; the film map q = -(2 (u + ppo) - 1) tan gives ppo' = ppo + dx / (2 D tan).
        v.ppo_x += float(dx / (2.0 * focus_distance * base.tan_x));
        v.ppo_y += float(dy / (2.0 * focus_distance * base.tan_y));
    }
    return v;
}

double focus_distance(const RigParams &p) { return p.has("focus_distance") ? p.length("focus_distance") : 0.0; }

std::vector<RigView> stereo(const RigParams &p, const RigBase &base) {
    double ipd = p.has("ipd") ? p.length("ipd") : 0.064, fd = focus_distance(p);
    return {translated(base, "left", 0.5 * ipd, 0, fd), translated(base, "right", -0.5 * ipd, 0, fd)};
}

std::vector<RigView> linear(const RigParams &p, const RigBase &base) {
    int n = p.count("n");
    double baseline = p.length("baseline"), fd = focus_distance(p);
    std::vector<RigView> views;
    for (int i = 0; i < n; ++i) {
        double s = n > 1 ? 0.5 - double(i) / (n - 1) : 0.0; // +x is left: the first view is leftmost
        views.push_back(translated(base, numbered("view", i, 3), s * baseline, 0, fd));
    }
    return views;
}

std::vector<RigView> grid(const RigParams &p, const RigBase &base) {
    int cols, rows;
    if (p.has("size")) {
        if (p.has("cols") || p.has("rows")) p.fail("size", "and cols/rows both give the grid size: use one");
        const std::string &s = p.string("size");
        size_t x = s.find('x');
        if (x == std::string::npos) p.fail("size", "must be COLSxROWS (e.g. 5x5), got '" + s + "'");
        int64_t c = parse_int(s.substr(0, x), p.loc("size"), p.what("size") + " columns");
        int64_t r = parse_int(s.substr(x + 1), p.loc("size"), p.what("size") + " rows");
        if (c < 1 || r < 1)
            p.fail("size", "must be at least 1x1: a rig must produce at least one view (got '" + s + "')");
        // (each factor first: their product may not fit in 64 bits)
        if (c > MaxRigViews || r > MaxRigViews || c * r > MaxRigViews)
            p.fail("size", "is too large ('" + s + "': at most " + std::to_string(MaxRigViews) + " views)");
        cols = int(c);
        rows = int(r);
    } else {
        cols = p.count("cols");
        rows = p.count("rows");
        if (int64_t(cols) * rows > MaxRigViews)
            p.fail("rows", "is too large (" + std::to_string(int64_t(cols) * rows) + " views: at most " +
                               std::to_string(MaxRigViews) + ")");
    }
    double spacing = p.length("spacing"), fd = focus_distance(p);
    std::vector<RigView> views;
    for (int r = 0; r < rows; ++r)
        for (int c = 0; c < cols; ++c) {
            // Row 0 is the top row (+y), column 0 the leftmost (+x).
            double dx = spacing * (0.5 * (cols - 1) - c), dy = spacing * (0.5 * (rows - 1) - r);
            views.push_back(translated(base, "r" + std::to_string(r) + "c" + std::to_string(c), dx, dy, fd));
        }
    return views;
}

std::vector<RigView> orbit(const RigParams &p, const RigBase &base) {
    int n = p.count("n");
    double radius = p.length("radius"), arc = p.number("arc", 360.0);
    if (!(arc > 0 && arc <= 360)) p.fail("arc", "must lie in (0, 360] degrees, got " + p.string("arc"));
    const Matrix4 &m = base.to_world.matrix();
    Vec3f origin(float(m.m[0][3]), float(m.m[1][3]), float(m.m[2][3]));
    Vec3f up(float(m.m[0][1]), float(m.m[1][1]), float(m.m[2][1])), forward(float(m.m[0][2]), float(m.m[1][2]), float(m.m[2][2]));
    Vec3f centre = origin + normalize(forward) * float(radius);
    bool closed = arc >= 360.0;
    std::vector<RigView> views;
    for (int i = 0; i < n; ++i) {
        // A closed orbit starts at the base camera; an open arc spans [-arc/2, arc/2] end to end.
        double angle = closed ? 360.0 * i / n : (n > 1 ? -0.5 * arc + arc * i / (n - 1) : 0.0);
        RigView v;
        v.id = numbered("view", i, 3);
        v.to_world = Transform::translate(centre) * Transform::rotate(normalize(up), float(angle)) *
                     Transform::translate(-centre) * base.to_world;
        v.ppo_x = base.ppo_x;
        v.ppo_y = base.ppo_y;
        views.push_back(v);
    }
    return views;
}

fs::path find_key_file(const RigParams &p, const std::vector<fs::path> &dirs) {
    fs::path f = p.string("file");
    if (f.is_absolute()) {
        if (fs::is_regular_file(f)) return f;
    } else {
        for (auto &d : dirs)
            if (fs::is_regular_file(d / f)) return d / f;
    }
    std::string looked;
    for (auto &d : dirs) looked += (looked.empty() ? "" : ", ") + d.string();
    p.fail("file", "'" + f.string() + "' not found" + (f.is_absolute() || looked.empty() ? "" : " (looked in " + looked + ")"));
}

std::vector<RigView> path(const RigParams &p, const RigBase &base, const std::vector<fs::path> &dirs,
                          std::vector<fs::path> *files) {
    int frames = p.count("frames");
    double fps = p.number("fps", 24.0), shutter = p.number("shutter", 0.5);
    if (!(fps > 0)) p.fail("fps", "must be > 0 frames per second, got " + p.string("fps"));
    if (!(shutter >= 0)) p.fail("shutter", "must be >= 0 (a fraction of the frame time), got " + p.string("shutter"));
    const fs::path key_file = find_key_file(p, dirs);
    CameraPath cam_path = CameraPath::read(key_file);
    if (files) files->push_back(fs::absolute(key_file).lexically_normal());
    if (p.has("interpolation") && !parse_path_interpolation(p.string("interpolation"), &cam_path.interpolation))
        p.fail("interpolation", "must be linear or smooth, got '" + p.string("interpolation") + "'");
    (void) base; // the path replaces the base pose; its film, sampler and lens carry over
    // Within one shutter the pose is sampled at 5 instants (4 segments) and the camera's
    // keyframed to_world interpolates between them (slerp + lerp): close to the path for
    // shutters that are short against the key spacing.
    const int segments = 4;
    std::vector<RigView> views;
    for (int i = 0; i < frames; ++i) {
        RigView v;
        v.id = numbered("frame", i, 4);
        v.has_shutter = true;
        v.shutter_open = float(i / fps);
        v.shutter_close = float(i / fps + shutter / fps);
        v.to_world = cam_path.pose(v.shutter_open);
        v.ppo_x = base.ppo_x;
        v.ppo_y = base.ppo_y;
        if (v.shutter_close > v.shutter_open)
            for (int j = 0; j <= segments; ++j) {
                float t = v.shutter_open + (v.shutter_close - v.shutter_open) * float(j) / segments;
                if (j == segments) t = v.shutter_close;
                v.motion.emplace_back(t, cam_path.pose(t));
            }
        views.push_back(std::move(v));
    }
    return views;
}

} // namespace

RigSpec RigSpec::parse(const std::string &text) {
    RigSpec spec;
    spec.loc = {"--rig " + text}; // messages read "--rig grid:5x5,spacing=nan: grid rig 'spacing': ..."
    size_t colon = text.find(':');
    spec.type = text.substr(0, colon);
    std::string rest = colon == std::string::npos ? "" : text.substr(colon + 1);
    size_t start = 0;
    while (colon != std::string::npos && start <= rest.size()) {
        size_t comma = rest.find(',', start);
        std::string tok = rest.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
        start = comma == std::string::npos ? rest.size() + 1 : comma + 1;
        if (tok.empty()) throw SceneError(spec.loc, "empty item (expected TYPE:name=value,...)");
        size_t eq = tok.find('=');
        std::string name, value;
        if (eq == std::string::npos) {
            // The one positional item: a grid's COLSxROWS or a path's key file.
            if (spec.type == "grid") name = "size";
            else if (spec.type == "path") name = "file";
            else throw SceneError(spec.loc, "expected name=value, got '" + tok + "'");
            value = tok;
        } else {
            name = tok.substr(0, eq);
            value = tok.substr(eq + 1);
        }
        if (name.empty()) throw SceneError(spec.loc, "empty parameter name in '" + tok + "'");
        if (spec.params.count(name)) throw SceneError(spec.loc, "'" + name + "' is given twice");
        spec.params[name] = {value, spec.loc};
    }
    return spec;
}

std::vector<RigView> generate_rig(const RigSpec &spec, const RigBase &base, const std::vector<fs::path> &search_dirs,
                                  std::vector<fs::path> *files) {
    std::vector<RigView> views;
    if (spec.type == "stereo") views = stereo(RigParams(spec, {"ipd", "focus_distance"}), base);
    else if (spec.type == "linear") views = linear(RigParams(spec, {"n", "baseline", "focus_distance"}), base);
    else if (spec.type == "grid")
        views = grid(RigParams(spec, {"size", "cols", "rows", "spacing", "focus_distance"}), base);
    else if (spec.type == "orbit") views = orbit(RigParams(spec, {"n", "radius", "arc"}), base);
    else if (spec.type == "path")
        views = path(RigParams(spec, {"file", "frames", "fps", "shutter", "interpolation"}), base, search_dirs, files);
    else {
        std::string hint = did_you_mean(spec.type, kRigTypes);
        throw SceneError(spec.loc, spec.prefix() + "unknown rig type '" + spec.type + "'" +
                                       (hint.empty() ? " (expected stereo, linear, grid, orbit or path)" : hint));
    }
    if (!spec.id_prefix.empty())
        for (auto &v : views) v.id = spec.id_prefix + "_" + v.id;
    return views;
}

} // namespace mvpt
