#include "properties.h"

#include "suggest.h"

#include <cmath>

namespace mvpt {


void Properties::set(const std::string &name, Value v, const FileLoc &loc, const std::string &tag) {
    if (m_values.count(name))
        throw SceneError(loc, "parameter '" + name + "' is given twice (first at " + m_values[name].loc.str() + ")");
    for (auto &c : m_children)
        if (!c.name.empty() && c.name == name)
            throw SceneError(loc, "parameter '" + name + "' is given twice (first at " + c.loc.str() + ")");
    m_values[name] = Entry{std::move(v), loc, tag};
}

const FileLoc &Properties::loc_of(const std::string &name) const {
    auto it = m_values.find(name);
    if (it != m_values.end()) return it->second.loc;
    for (auto &c : m_children)
        if (c.name == name) return c.loc;
    return m_loc;
}

void Properties::fail(const std::string &name, const std::string &msg) const {
    std::string what = m_kind.empty() ? "" : m_kind + " '" + m_type + "': ";
    throw SceneError(loc_of(name), what + msg);
}

const Properties::Entry *Properties::find(const std::string &name) const {
    m_asked.insert(name);
    auto it = m_values.find(name);
    if (it == m_values.end()) return nullptr;
    it->second.queried = true;
    return &it->second;
}

template <typename T> const T *Properties::find_as(const std::string &name, const char *expected) const {
    const Entry *e = find(name);
    if (!e) return nullptr;
    if (auto *p = std::get_if<T>(&e->value)) return p;
    fail(name, "parameter '" + name + "' must be of type " + expected + ", got <" + e->tag + ">");
}

bool Properties::get_bool(const std::string &name, bool def) const {
    auto *p = find_as<bool>(name, "boolean");
    return p ? *p : def;
}

int64_t Properties::get_int(const std::string &name, int64_t def) const {
    auto *p = find_as<int64_t>(name, "integer");
    return p ? *p : def;
}

int64_t Properties::get_int(const std::string &name) const {
    auto *p = find_as<int64_t>(name, "integer");
    if (!p) fail(name, "missing required integer parameter '" + name + "'");
    return *p;
}

int64_t Properties::get_int_in(const std::string &name, int64_t def, int64_t lo, int64_t hi) const {
    const int64_t v = get_int(name, def);
    if (v < lo || v > hi)
        fail(name, "'" + name + "' must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
                       std::to_string(v));
    return v;
}

float Properties::get_float(const std::string &name, float def) const {
    const Entry *e = find(name);
    if (!e) return def;
    if (auto *d = std::get_if<double>(&e->value)) return float(*d);
    if (auto *i = std::get_if<int64_t>(&e->value)) return float(*i);
    fail(name, "parameter '" + name + "' must be a float, got <" + e->tag + ">");
}

float Properties::get_float(const std::string &name) const {
    if (!has(name)) fail(name, "missing required float parameter '" + name + "'");
    return get_float(name, 0.f);
}

std::string Properties::get_string(const std::string &name, const std::string &def) const {
    auto *p = find_as<std::string>(name, "string");
    return p ? *p : def;
}

std::string Properties::get_string(const std::string &name) const {
    auto *p = find_as<std::string>(name, "string");
    if (!p) fail(name, "missing required string parameter '" + name + "'");
    return *p;
}

Color3f Properties::get_color(const std::string &name, Color3f def, SpectrumUse use) const {
    const Entry *e = find(name);
    if (!e) return def;
    if (auto *c = std::get_if<Color3f>(&e->value)) return *c;
    if (auto *s = std::get_if<SpectrumCurve>(&e->value)) return spectrum_to_rgb(*s, use);
    if (auto *d = std::get_if<double>(&e->value)) return Color3f(float(*d));
    if (auto *i = std::get_if<int64_t>(&e->value)) return Color3f(float(*i));
    fail(name, "parameter '" + name + "' must be an rgb colour, a spectrum or a float, got <" + e->tag + ">");
}

Vec3f Properties::get_vector(const std::string &name, Vec3f def) const {
    auto *p = find_as<Vec3f>(name, "point/vector");
    return p ? *p : def;
}

Transform Properties::get_transform(const std::string &name, const Transform &def) const {
    const Entry *e = find(name);
    if (!e) return def;
    if (auto *t = std::get_if<Transform>(&e->value)) return *t;
    if (std::holds_alternative<AnimatedTransform>(e->value))
        fail(name, "parameter '" + name + "' cannot be animated on a " + m_kind + " of type '" + m_type + "'");
    fail(name, "parameter '" + name + "' must be a transform, got <" + e->tag + ">");
}

AnimatedTransform Properties::get_animated_transform(const std::string &name) const {
    const Entry *e = find(name);
    if (!e) return AnimatedTransform(Transform());
    if (auto *t = std::get_if<Transform>(&e->value)) return AnimatedTransform(*t);
    if (auto *a = std::get_if<AnimatedTransform>(&e->value)) return *a;
    fail(name, "parameter '" + name + "' must be a transform or an animation, got <" + e->tag + ">");
}

bool Properties::has_texture(const std::string &name) const {
    m_asked.insert(name);
    if (has(name)) return true;
    for (auto &c : m_children)
        if (c.name == name && c.kind == "texture") return true;
    return false;
}

const ChildObject *Properties::named_child(const std::string &name) const {
    m_asked.insert(name);
    for (auto &c : m_children)
        if (c.name == name) {
            c.queried = true;
            return &c;
        }
    return nullptr;
}

std::vector<const ChildObject *> Properties::children_of_kind(const std::string &kind) const {
    std::vector<const ChildObject *> r;
    for (auto &c : m_children)
        if (c.kind == kind) {
            c.queried = true;
            r.push_back(&c);
        }
    return r;
}

const ChildObject *Properties::child_of_kind(const std::string &kind) const {
    auto v = children_of_kind(kind);
    if (v.size() > 1)
        throw SceneError(v[1]->loc, m_kind + " '" + m_type + "' accepts only one " + kind + " (another is at " +
                                        v[0]->loc.str() + ")");
    return v.empty() ? nullptr : v[0];
}

void Properties::check_all_queried() const {
    std::vector<std::string> asked(m_asked.begin(), m_asked.end());
    for (auto &[name, e] : m_values)
        if (!e.queried) {
            std::string hint = did_you_mean(name, asked);
            throw SceneError(e.loc, m_kind + " '" + m_type + "' does not use a parameter named '" + name + "' (<" +
                                        e.tag + ">)" + (hint.empty() ? "; remove it or check its spelling" : hint));
        }
    for (auto &c : m_children)
        if (!c.queried)
            throw SceneError(c.loc, m_kind + " '" + m_type + "' does not accept a nested " + c.kind +
                                        (c.name.empty() ? std::string() : " named '" + c.name + "'" + did_you_mean(c.name, asked)));
}

} // namespace mvpt
