#include "parse_values.h"

#include "../core/suggest.h"
#include "xml_parser.h"

#include <algorithm>
#include <cerrno>
#include <cfloat>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>

namespace mvpt {

void check_attrs(const XmlAttrs &attrs, std::initializer_list<const char *> allowed, const std::string &tag,
                 const FileLoc &loc) {
    for (const XmlAttr &attr : attrs) {
        bool ok = std::any_of(allowed.begin(), allowed.end(), [&](const char *a) { return attr.first == a; });
        if (!ok) {
            std::string list;
            for (const char *a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
            throw SceneError(attr.loc.line > 0 ? attr.loc : loc,
                             "<" + tag + "> has an unknown attribute '" + attr.first + "' (expected: " + list + ")");
        }
    }
}

std::string required(const XmlAttrs &attrs, const std::string &name, const std::string &tag, const FileLoc &loc) {
    for (auto &a : attrs)
        if (a.first == name) return a.second;
    throw SceneError(loc, "<" + tag + "> is missing its '" + name + "' attribute");
}

namespace {
std::string trim(const std::string &s) {
    size_t a = s.find_first_not_of(" \t\r\n"), b = s.find_last_not_of(" \t\r\n");
    return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
}
} // namespace

namespace {
/// Shapes, lights and cameras use transforms in single precision: every entry must fit a float.
bool fits_float(const Transform &t) {
    for (const Matrix4 *m : {&t.matrix(), &t.inverse_matrix()})
        for (auto &row : m->m)
            for (double v : row)
                if (!(std::fabs(v) <= double(FLT_MAX))) return false;
    return true;
}
const char *NotFloat = "transform is not finite in single precision (an entry or its inverse's beyond 3.4e38)";
} // namespace

double parse_float(const std::string &s_, const FileLoc &loc, const std::string &what) {
    std::string s = trim(s_);
    char *end = nullptr;
    errno = 0;
    double v = std::strtod(s.c_str(), &end);
    if (s.empty() || *end != '\0') throw SceneError(loc, what + ": expected a number, got '" + s_ + "'");
    if (!std::isfinite(v) || errno == ERANGE) throw SceneError(loc, what + ": expected a finite number, got '" + s_ + "'");
    return v;
}

int64_t parse_int(const std::string &s_, const FileLoc &loc, const std::string &what) {
    std::string s = trim(s_);
    char *end = nullptr;
    errno = 0;
    long long v = std::strtoll(s.c_str(), &end, 10);
    if (s.empty() || *end != '\0' || errno == ERANGE)
        throw SceneError(loc, what + ": expected an integer, got '" + s_ + "'");
    return v;
}

std::vector<double> parse_float_list(const std::string &s, const FileLoc &loc, const std::string &what) {
    std::vector<double> r;
    std::string tok;
    auto flush = [&] {
        if (!tok.empty()) r.push_back(parse_float(tok, loc, what));
        tok.clear();
    };
    for (char c : s) {
        if (c == ',' || c == ' ' || c == '\t' || c == '\n' || c == '\r') flush();
        else tok += c;
    }
    flush();
    return r;
}

namespace {

Vec3f parse_xyz(const XmlNode &n, const std::string &what, float def) {
    if (const std::string *v = n.attr("value")) {
        if (n.attr("x") || n.attr("y") || n.attr("z"))
            throw SceneError(n.loc, "<" + n.tag + "> takes either 'value' or x/y/z attributes, not both");
        auto l = parse_float_list(*v, n.attr_loc("value"), what);
        if (l.size() == 1) return Vec3f(float(l[0]));
        if (l.size() != 3)
            throw SceneError(n.attr_loc("value"), what + ": expected 3 numbers, got " + std::to_string(l.size()));
        return {float(l[0]), float(l[1]), float(l[2])};
    }
    Vec3f r(def);
    const char *names[3] = {"x", "y", "z"};
    for (int i = 0; i < 3; ++i)
        if (const std::string *a = n.attr(names[i])) r[i] = float(parse_float(*a, n.attr_loc(names[i]), what));
    return r;
}

Vec3f parse_vec3_attr(const XmlNode &n, const char *attr, const std::string &what) {
    const std::string *v = n.attr(attr);
    if (!v) throw SceneError(n.loc, "<" + n.tag + "> is missing its '" + attr + "' attribute");
    auto l = parse_float_list(*v, n.attr_loc(attr), what + " '" + attr + "'");
    if (l.size() != 3) throw SceneError(n.attr_loc(attr), what + " '" + attr + "': expected 3 numbers");
    return {float(l[0]), float(l[1]), float(l[2])};
}

} // namespace

Transform parse_transform_ops(const XmlNode &node) {
    Transform t;
    for (auto &op : node.children) {
        const std::string &tag = op.tag;
        Transform m;
        if (tag == "translate") {
            check_attrs(op.attrs, {"x", "y", "z", "value"}, tag, op.loc);
            m = Transform::translate(parse_xyz(op, "<translate>", 0.f));
        } else if (tag == "scale") {
            check_attrs(op.attrs, {"x", "y", "z", "value"}, tag, op.loc);
            Vec3f s = parse_xyz(op, "<scale>", 1.f);
            if (s.x == 0 || s.y == 0 || s.z == 0) throw SceneError(op.loc, "<scale> by zero makes the transform singular");
            m = Transform::scale(s);
        } else if (tag == "rotate") {
            check_attrs(op.attrs, {"x", "y", "z", "value", "angle"}, tag, op.loc);
            Vec3f axis = parse_xyz(op, "<rotate> axis", 0.f);
            if (squared_norm(axis) == 0) throw SceneError(op.loc, "<rotate> needs a non-zero axis (x, y, z)");
            float angle = float(parse_float(required(op.attrs, "angle", tag, op.loc), op.attr_loc("angle"), "<rotate> angle"));
            m = Transform::rotate(axis, angle);
        } else if (tag == "matrix") {
            check_attrs(op.attrs, {"value"}, tag, op.loc);
            auto l = parse_float_list(required(op.attrs, "value", tag, op.loc), op.attr_loc("value"), "<matrix>");
            Matrix4 mm;
            if (l.size() == 16) {
                for (int i = 0; i < 16; ++i) mm.m[i / 4][i % 4] = l[i];
            } else if (l.size() == 9) {
                for (int i = 0; i < 9; ++i) mm.m[i / 3][i % 3] = l[i];
            } else {
                throw SceneError(op.attr_loc("value"), "<matrix> needs 16 (or 9) numbers, got " + std::to_string(l.size()));
            }
            bool ok = true;
            Matrix4 inv = mm.inverse(&ok);
            if (!ok) throw SceneError(op.loc, "<matrix> is singular");
            m = Transform(mm, inv);
        } else if (tag == "lookat") {
            check_attrs(op.attrs, {"origin", "target", "up"}, tag, op.loc);
            Vec3f o = parse_vec3_attr(op, "origin", "<lookat>"), tg = parse_vec3_attr(op, "target", "<lookat>");
            Vec3f up = op.attr("up") ? parse_vec3_attr(op, "up", "<lookat>") : Vec3f(0, 1, 0);
            Vec3f dir = tg - o;
            if (squared_norm(dir) == 0) throw SceneError(op.loc, "<lookat> origin and target coincide");
            if (squared_norm(cross(normalize(up), normalize(dir))) < 1e-12f)
                throw SceneError(op.loc, "<lookat> 'up' is parallel to the view direction");
            m = Transform::look_at(o, tg, up);
        } else {
            std::string hint = did_you_mean(tag, {"translate", "rotate", "scale", "matrix", "lookat"}, "<", ">");
            throw SceneError(op.loc, "unknown transform operation <" + tag + ">" +
                                         (hint.empty() ? " (expected translate, rotate, scale, matrix or lookat)" : hint));
        }
        if (!fits_float(m)) throw SceneError(op.loc, NotFloat);
        t = m * t;
    }
    if (!fits_float(t)) throw SceneError(node.loc, NotFloat);
    return t;
}

namespace {

/// `wavelength:value, ...` pairs, or one constant (Mitsuba's Properties::Spectrum).
SpectrumCurve parse_spectrum_pairs(const std::string &text, const FileLoc &loc, const std::string &what) {
    std::vector<std::string> tokens;
    std::string tok;
    for (char c : text + " ") {
        if (c == ',' || c == ' ' || c == '\t' || c == '\n' || c == '\r') {
            if (!tok.empty()) tokens.push_back(tok);
            tok.clear();
        } else {
            tok += c;
        }
    }
    if (tokens.empty()) throw SceneError(loc, what + ": expected a number or wavelength:value pairs, got nothing");
    if (tokens.size() == 1 && tokens[0].find(':') == std::string::npos)
        return SpectrumCurve::uniform(parse_float(tokens[0], loc, what));
    SpectrumCurve s;
    for (const std::string &t : tokens) {
        size_t colon = t.find(':');
        if (colon == std::string::npos || t.find(':', colon + 1) != std::string::npos)
            throw SceneError(loc, what + ": expected wavelength:value pairs (e.g. \"400:0.3, 500:0.5\"), got '" + t + "'");
        s.wavelengths.push_back(parse_float(t.substr(0, colon), loc, what + " wavelength in '" + t + "'"));
        s.values.push_back(parse_float(t.substr(colon + 1), loc, what + " value in '" + t + "'"));
    }
    return s;
}

/// A spectral data file (`.spd`): one "wavelength value" pair per line, '#' comments.
SpectrumCurve read_spectrum_file(const std::filesystem::path &path, const std::string &what) {
    std::ifstream in(path);
    if (!in) throw SceneError({path.string()}, what + ": cannot read the spectrum file");
    SpectrumCurve s;
    std::string line;
    for (int line_no = 1; std::getline(in, line); ++line_no) {
        std::string data = line.substr(0, line.find('#'));
        std::vector<double> l = parse_float_list(data, {path.string(), line_no, 1}, what);
        if (l.empty()) continue;
        if (l.size() != 2)
            throw SceneError({path.string(), line_no, 1},
                             what + ": expected 'wavelength value' on each line, got " + std::to_string(l.size()) + " numbers");
        s.wavelengths.push_back(l[0]);
        s.values.push_back(l[1]);
    }
    if (s.wavelengths.empty()) throw SceneError({path.string()}, what + ": the spectrum file holds no data");
    return s;
}

/// A `<spectrum>` element: `value` (constant or pairs) or `filename` (an .spd file).
SpectrumCurve parse_spectrum(const XmlNode &n, const std::string &name, const LoadContext &ctx) {
    const std::string *value = n.attr("value"), *file = n.attr("filename");
    std::string what = "spectrum '" + name + "'";
    if (bool(value) == bool(file))
        throw SceneError(n.loc, "<spectrum> needs either a 'value' or a 'filename' attribute (not both)");
    const char *attr = value ? "value" : "filename";
    SpectrumCurve s = value ? parse_spectrum_pairs(*value, n.attr_loc(attr), what)
                            : read_spectrum_file(ctx.resolve(*file, n.attr_loc(attr)), what);
    std::string problem = s.validate();
    if (!problem.empty()) throw SceneError(n.attr_loc(attr), what + ": " + problem);
    return s;
}

/// A <boolean>'s value: true/1 or false/0, in any case.
bool parse_bool(const XmlNode &n, const std::string &name) {
    std::string v = required(n.attrs, "value", n.tag, n.loc), lv = v;
    std::transform(lv.begin(), lv.end(), lv.begin(), ::tolower);
    if (lv == "true" || lv == "1") return true;
    if (lv == "false" || lv == "0") return false;
    throw SceneError(n.attr_loc("value"), "boolean '" + name + "': expected true or false, got '" + v + "'");
}

/// An <rgb>'s value: one number (grey) or three.
Color3f parse_rgb(const XmlNode &n, const std::string &name) {
    auto l = parse_float_list(required(n.attrs, "value", n.tag, n.loc), n.attr_loc("value"), "rgb '" + name + "'");
    if (l.size() == 1) return Color3f(float(l[0]));
    if (l.size() == 3) return Color3f(float(l[0]), float(l[1]), float(l[2]));
    throw SceneError(n.attr_loc("value"), "rgb '" + name + "': expected 1 or 3 numbers, got " + std::to_string(l.size()));
}

/// An <animation>: <transform time="..."> keyframes at distinct times.
AnimatedTransform parse_animation(const XmlNode &n) {
    std::vector<std::pair<float, Transform>> keys;
    for (auto &k : n.children) {
        if (k.tag != "transform")
            throw SceneError(k.loc, "<animation> may only contain <transform time=\"...\"> keyframes, got <" + k.tag + ">");
        check_attrs(k.attrs, {"time"}, "transform", k.loc);
        float time = float(parse_float(required(k.attrs, "time", "transform", k.loc), k.attr_loc("time"), "keyframe time"));
        keys.emplace_back(time, parse_transform_ops(k));
    }
    if (keys.empty()) throw SceneError(n.loc, "<animation> needs at least one <transform time=\"...\"> keyframe");
    for (size_t i = 0; i < keys.size(); ++i)
        for (size_t j = i + 1; j < keys.size(); ++j)
            if (keys[i].first == keys[j].first)
                throw SceneError(n.loc, "<animation> has two keyframes at time " + std::to_string(keys[i].first));
    AnimatedTransform at;
    std::string err;
    if (!AnimatedTransform::from_keys(keys, at, err)) throw SceneError(n.loc, err);
    return at;
}

[[noreturn]] void unknown_element(const XmlNode &n) {
    static const std::vector<std::string> known = {"float", "integer", "boolean", "string", "rgb", "spectrum",
                                                   "point", "vector", "transform", "animation", "ref", "bsdf",
                                                   "emitter", "shape", "sensor", "film", "rfilter", "sampler",
                                                   "integrator", "texture", "include", "default"};
    std::string hint = did_you_mean(n.tag, known, "<", ">");
    throw SceneError(n.loc, "unknown element <" + n.tag + ">" +
                                (hint.empty() ? " (expected a value such as <float>, <rgb>, <transform> or an object "
                                                "such as <bsdf>, <shape>, <texture>)"
                                              : hint));
}

/// <float>, <integer>, <boolean>, <string> and <rgb>: a name and a value, no children.
void parse_named_value(const XmlNode &n, Properties &props) {
    const std::string &tag = n.tag;
    check_attrs(n.attrs, {"name", "value"}, tag, n.loc);
    if (!n.children.empty()) throw SceneError(n.children[0].loc, "<" + tag + "> cannot have child elements");
    const std::string name = required(n.attrs, "name", tag, n.loc);
    if (tag == "float")
        props.set(name, parse_float(required(n.attrs, "value", tag, n.loc), n.attr_loc("value"), "float '" + name + "'"),
                  n.loc, tag);
    else if (tag == "integer")
        props.set(name, parse_int(required(n.attrs, "value", tag, n.loc), n.attr_loc("value"), "integer '" + name + "'"),
                  n.loc, tag);
    else if (tag == "boolean") props.set(name, parse_bool(n, name), n.loc, tag);
    else if (tag == "string") props.set(name, required(n.attrs, "value", tag, n.loc), n.loc, tag);
    else props.set(name, parse_rgb(n, name), n.loc, tag);
}

} // namespace

void parse_value_node(const XmlNode &n, Properties &props, const LoadContext &ctx) {
    const std::string &tag = n.tag;
    auto name_of = [&] { return required(n.attrs, "name", tag, n.loc); };
    auto no_children = [&] {
        if (!n.children.empty()) throw SceneError(n.children[0].loc, "<" + tag + "> cannot have child elements");
    };
    if (tag == "float" || tag == "integer" || tag == "boolean" || tag == "string" || tag == "rgb") {
        parse_named_value(n, props);
    } else if (tag == "spectrum") {
        if (const std::string *type = n.attr("type"))
            throw SceneError(n.attr_loc("type"), "<spectrum type=\"" + *type + "\"> (e.g. blackbody) needs Mitsuba's spectral "
                                                 "variants; mvpt renders in RGB (give 'value' or 'filename')");
        check_attrs(n.attrs, {"name", "value", "filename"}, tag, n.loc);
        no_children();
        std::string name = name_of();
        props.set(name, parse_spectrum(n, name, ctx), n.loc, tag);
    } else if (tag == "point" || tag == "vector") {
        check_attrs(n.attrs, {"name", "value", "x", "y", "z"}, tag, n.loc);
        no_children();
        std::string name = name_of();
        props.set(name, parse_xyz(n, tag + " '" + name + "'", 0.f), n.loc, tag);
    } else if (tag == "transform") {
        check_attrs(n.attrs, {"name"}, tag, n.loc);
        props.set(name_of(), parse_transform_ops(n), n.loc, tag);
    } else if (tag == "animation") {
        check_attrs(n.attrs, {"name"}, tag, n.loc);
        AnimatedTransform at = parse_animation(n);
        props.set(name_of(), at, n.loc, tag);
    } else {
        unknown_element(n);
    }
}

} // namespace mvpt
