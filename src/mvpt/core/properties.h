// Named, typed parameters of one scene-file object, each with its source
// location and a "was read" flag: a parameter no plugin reads is an error.
#pragma once

#include "error.h"
#include "math.h"
#include "spectrum_rgb.h"
#include "transform.h"
#include "animation.h"

#include <map>
#include <memory>
#include <set>
#include <string>
#include <variant>
#include <vector>

namespace mvpt {

/// Base of every object a scene file can declare (bsdf, shape, sensor, ...).
class Object {
public:
    virtual ~Object() = default;
    /// The mesh attributes that this object and the objects inside it read (mesh_attribute
    /// textures): every shape that uses it must have them (the loader checks).
    std::vector<std::string> mesh_attributes;
};

/// One child object of a scene-file element, with the name it was given (may be empty).
struct ChildObject {
    std::string name, kind, type, id;
    std::shared_ptr<Object> object;
    FileLoc loc;
    mutable bool queried = false;
};

class Properties {
public:
    using Value = std::variant<bool, int64_t, double, std::string, Color3f, SpectrumCurve, Vec3f, Transform,
                               AnimatedTransform>;

    Properties(std::string kind = {}, std::string type = {}, FileLoc loc = {})
        : m_kind(std::move(kind)), m_type(std::move(type)), m_loc(std::move(loc)) {}

    const std::string &kind() const { return m_kind; }
    const std::string &type() const { return m_type; }
    const FileLoc &loc() const { return m_loc; }
    std::string id;

    void set(const std::string &name, Value v, const FileLoc &loc, const std::string &tag);
    bool has(const std::string &name) const { return m_values.count(name) != 0; }
    /// True when parameter `name` was given as a <string> (e.g. a named IOR instead of a float).
    bool is_string(const std::string &name) const {
        auto it = m_values.find(name);
        return it != m_values.end() && std::holds_alternative<std::string>(it->second.value);
    }
    /// True when parameter `name` was given as a <vector> or <point>.
    bool is_vector(const std::string &name) const {
        auto it = m_values.find(name);
        return it != m_values.end() && std::holds_alternative<Vec3f>(it->second.value);
    }
    /// Location of parameter `name`, or of the object itself when it is absent.
    const FileLoc &loc_of(const std::string &name) const;

    bool get_bool(const std::string &name, bool def) const;
    int64_t get_int(const std::string &name, int64_t def) const;
    int64_t get_int(const std::string &name) const;
    /// An integer that must lie in [lo, hi] (an error at the parameter otherwise, never a truncation).
    int64_t get_int_in(const std::string &name, int64_t def, int64_t lo, int64_t hi) const;
    float get_float(const std::string &name, float def) const;
    float get_float(const std::string &name) const;
    std::string get_string(const std::string &name, const std::string &def) const;
    std::string get_string(const std::string &name) const;
    /// An `<rgb>`, `<float>` or `<spectrum>` as RGB; a spectrum converts as Mitsuba's RGB mode does for `use`.
    Color3f get_color(const std::string &name, Color3f def, SpectrumUse use = SpectrumUse::Reflectance) const;
    Vec3f get_vector(const std::string &name, Vec3f def) const;
    Transform get_transform(const std::string &name, const Transform &def = {}) const;
    /// A transform that may be animated (`<animation>` or a plain `<transform>`).
    AnimatedTransform get_animated_transform(const std::string &name) const;
    /// Whether `name` is given, as a value or as a nested/referenced texture (the render
    /// layer's get_texture reads it).
    bool has_texture(const std::string &name) const;
    /// The child object given the name `name` (marked read), or nullptr; `name` counts as
    /// looked up for the "did you mean" hints.
    const ChildObject *named_child(const std::string &name) const;

    /// Child objects (bsdf/emitter/film/...) declared or referenced inside this element.
    void add_child(ChildObject c) { m_children.push_back(std::move(c)); }
    const std::vector<ChildObject> &children() const { return m_children; }
    /// All children of one kind ("bsdf", "emitter", ...); marks them read.
    std::vector<const ChildObject *> children_of_kind(const std::string &kind) const;
    /// The single child of a kind, or nullptr; more than one is an error.
    const ChildObject *child_of_kind(const std::string &kind) const;

    /// Throw a SceneError at the first parameter or child that nobody read.
    void check_all_queried() const;

    [[noreturn]] void fail(const std::string &name, const std::string &msg) const;

private:
    struct Entry {
        Value value;
        FileLoc loc;
        std::string tag;
        mutable bool queried = false;
    };
    const Entry *find(const std::string &name) const;
    template <typename T> const T *find_as(const std::string &name, const char *expected) const;

    std::string m_kind, m_type;
    FileLoc m_loc;
    std::map<std::string, Entry> m_values;
    std::vector<ChildObject> m_children;
    mutable std::set<std::string> m_asked; ///< names the plugin looked up (for "did you mean" hints)
};

} // namespace mvpt
