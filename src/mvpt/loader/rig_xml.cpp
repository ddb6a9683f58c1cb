// Rigs in scene files and on the command line: expansion into plain <sensor> elements.
//
// Scene files write a rig as an element of mvpt's own namespace,
//   <scene version="3.0.0" xmlns:mvpt="urn:mvpt">
//     <mvpt:rig type="grid" size="5x5" spacing="0.05" focus_distance="3" id="lf">
//       <sensor type="perspective"> ... the base camera ... </sensor>
//     </mvpt:rig>
// directly inside <scene>. The element name is matched literally as `mvpt:rig` (the XML is
// not namespace-processed, and the xmlns declaration is optional but keeps the file valid
// namespaced XML); every attribute but `type` and `id` is a rig parameter (rig.h), `id` prefixes
// the view ids ("lf_r0c0"). Each generated sensor is a copy of the base camera with its own
// id, a `to_world` matrix (an <animation> of matrices over the shutter for path rigs),
// principal_point_offset_x/_y when sheared, and shutter_open/_close for path rigs.
#include "rig.h"

#include <algorithm>

#include "../core/memory.h"
#include "../render/cameras/field_of_view.h"
#include "load_control.h"
#include "parse_values.h"

#include <cstdio>

namespace mvpt {

namespace fs = std::filesystem;

bool is_rig_element(const std::string &tag) { return tag == "mvpt:rig"; }

namespace {

std::string format_number(double v, int digits) {
    char buf[40];
    std::snprintf(buf, sizeof(buf), "%.*g", digits, v);
    return buf;
}

XmlNode element(const std::string &tag, XmlAttrs attrs, const XmlNode &like) {
    XmlNode n;
    n.tag = tag;
    n.attrs = std::move(attrs);
    n.loc = like.loc;
    n.dir = like.dir;
    return n;
}

XmlNode matrix_node(const Transform &t, const XmlNode &like) {
    std::string v;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) v += (v.empty() ? "" : " ") + format_number(t.matrix().m[i][j], 17);
    return element("matrix", {XmlAttr("value", v, like.loc)}, like);
}

XmlNode float_node(const std::string &name, double value, const XmlNode &like) {
    return element("float", {XmlAttr("name", name, like.loc), XmlAttr("value", format_number(value, 9), like.loc)}, like);
}

/// The pose, field of view and principal point of the base camera `sensor`; a film given as
/// <ref id="..."/> is looked up among the top-level elements of `scene`.
RigBase rig_base(const XmlNode &sensor, const std::string &where, const XmlNode &scene) {
    const std::string *type = sensor.attr("type");
    if (!type || (*type != "perspective" && *type != "thinlens"))
        throw SceneError(sensor.loc, where + ": the base camera must be a perspective or thinlens <sensor>" +
                                         (type ? ", got '" + *type + "'" : std::string()));
    RigBase base;
    Properties props("sensor", *type, sensor.loc);
    int width = 768, height = 576; // hdrfilm's defaults
    int64_t crop[4] = {0, 0, -1, -1}; // offset x, y; width, height (-1: to the film's edge)
    for (const XmlNode &c : sensor.children) {
        const std::string *name = c.attr("name");
        if (name && *name == "to_world") {
            if (c.tag == "animation")
                throw SceneError(c.loc, where + ": the base camera of a rig must have a static 'to_world' "
                                                "(a path rig animates the views itself)");
            if (c.tag == "transform") base.to_world = parse_transform_ops(c);
        } else if (name && (c.tag == "float" || c.tag == "string") &&
                   (*name == "fov" || *name == "fov_axis" || *name == "focal_length" ||
                    *name == "principal_point_offset_x" || *name == "principal_point_offset_y")) {
            parse_value_node(c, props, {});
        } else if (c.tag == "film" || c.tag == "ref") {
            const XmlNode *film = &c;
            if (c.tag == "ref") {
                film = nullptr;
                for (const XmlNode &top : scene.children)
                    if (top.tag == "film" && top.attr("id") && c.attr("id") && *top.attr("id") == *c.attr("id")) film = &top;
                if (!film) continue; // a shared sampler, or a film declared later (then hdrfilm's default size)
            }
            for (const XmlNode &f : film->children) {
                const std::string *fname = f.attr("name"), *value = f.attr("value");
                if (f.tag != "integer" || !fname || !value) continue;
                if (*fname == "width") width = int(parse_int(*value, f.attr_loc("value"), "film width"));
                if (*fname == "height") height = int(parse_int(*value, f.attr_loc("value"), "film height"));
                const char *crops[4] = {"crop_offset_x", "crop_offset_y", "crop_width", "crop_height"};
                for (int i = 0; i < 4; ++i)
                    if (*fname == crops[i]) crop[i] = parse_int(*value, f.attr_loc("value"), crops[i]);
            }
        }
    }
    if (width <= 0 || height <= 0) throw SceneError(sensor.loc, where + ": the base camera's film size must be positive");
    read_field_of_view(props, width, height, &base.tan_x, &base.tan_y);
    base.ppo_x = props.get_float("principal_point_offset_x", 0.f);
    base.ppo_y = props.get_float("principal_point_offset_y", 0.f);
    // The crop window's pixels, clamped to the film (the film checks the window itself when made).
    const int64_t cw = crop[2] >= 0 ? crop[2] : width - crop[0], ch = crop[3] >= 0 ? crop[3] : height - crop[1];
    base.pixels = double(std::clamp<int64_t>(cw, 0, width)) * double(std::clamp<int64_t>(ch, 0, height));
    return base;
}

/// Refuses, before its views are made, a rig whose views' images cannot all be in memory at
/// once when the caller renders every view (the renderer's preflight, renderer.cpp, would
/// refuse it only after the load, which for 10^5 views takes seconds and GiB).
void check_rig_fits(size_t views, const RigBase &base, const RigSpec &spec) {
    if (!load_control().every_view_rendered) return;
    const double need = double(views) * base.pixels * MinBytesPerRenderedPixel;
    const MemoryRoom room = available_memory();
    if (room.bytes > 0.0 && need > room.bytes)
        throw SceneError(spec.loc, spec.prefix() + "the rig's " + std::to_string(views) + " views need at least " +
                                       std::to_string(int64_t(need / (1 << 20))) + " MiB of memory for their images, but " +
                                       room.limit + " leaves " + std::to_string(int64_t(room.bytes / (1 << 20))) +
                                       " MiB (make fewer views or smaller films)");
}

/// Removes the `id` of every element declared inside `node` (not of a <ref>, whose id names what
/// it refers to).
void drop_nested_ids(XmlNode &node) {
    for (XmlNode &c : node.children) {
        if (c.tag != "ref")
            c.attrs.erase(std::remove_if(c.attrs.begin(), c.attrs.end(), [](const XmlAttr &a) { return a.first == "id"; }),
                          c.attrs.end());
        drop_nested_ids(c);
    }
}

/// A copy of the base sensor posed as `view`; new elements carry the location `at`. Only the
/// first copy (`first`) keeps the ids of the film, sampler or filter declared inside the base
/// sensor: the others would declare them again (the same objects, for references to them).
XmlNode view_sensor(const XmlNode &base, const RigView &view, const XmlNode &at, bool first) {
    XmlNode s = base;
    if (!first) drop_nested_ids(s);
    s.attrs.clear();
    for (const XmlAttr &a : base.attrs)
        if (a.first != "id") s.attrs.push_back(a);
    s.attrs.emplace_back("id", view.id, at.loc);
    auto replaced = [&](const XmlNode &c) {
        const std::string *name = c.attr("name");
        if (!name) return false;
        if (*name == "to_world" || *name == "principal_point_offset_x" || *name == "principal_point_offset_y") return true;
        return view.has_shutter && (*name == "shutter_open" || *name == "shutter_close");
    };
    std::vector<XmlNode> children = std::move(s.children);
    s.children.clear();
    for (XmlNode &c : children)
        if (!replaced(c)) s.children.push_back(std::move(c));
    if (view.motion.empty()) {
        XmlNode t = element("transform", {XmlAttr("name", "to_world", at.loc)}, at);
        t.children.push_back(matrix_node(view.to_world, at));
        s.children.push_back(std::move(t));
    } else {
        XmlNode anim = element("animation", {XmlAttr("name", "to_world", at.loc)}, at);
        for (auto &[time, pose] : view.motion) {
            XmlNode key = element("transform", {XmlAttr("time", format_number(time, 9), at.loc)}, at);
            key.children.push_back(matrix_node(pose, at));
            anim.children.push_back(std::move(key));
        }
        s.children.push_back(std::move(anim));
    }
    if (view.ppo_x != 0.f) s.children.push_back(float_node("principal_point_offset_x", view.ppo_x, at));
    if (view.ppo_y != 0.f) s.children.push_back(float_node("principal_point_offset_y", view.ppo_y, at));
    if (view.has_shutter) {
        s.children.push_back(float_node("shutter_open", view.shutter_open, at));
        s.children.push_back(float_node("shutter_close", view.shutter_close, at));
    }
    return s;
}

} // namespace

std::vector<XmlNode> expand_rig_element(const XmlNode &rig, const XmlNode &scene, const std::vector<fs::path> &search_dirs,
                                        std::vector<fs::path> *files) {
    RigSpec spec;
    spec.where = "<" + rig.tag + ">";
    spec.loc = rig.loc;
    spec.type = required(rig.attrs, "type", rig.tag, rig.loc);
    for (const XmlAttr &a : rig.attrs) {
        if (a.first == "type") continue;
        if (a.first == "id") spec.id_prefix = a.second;
        else if (a.first.rfind("xmlns", 0) != 0) spec.params[a.first] = {a.second, a.loc.line > 0 ? a.loc : rig.loc};
    }
    const XmlNode *base = nullptr;
    for (const XmlNode &c : rig.children) {
        if (c.tag != "sensor" || base)
            throw SceneError(c.loc, spec.where + " contains exactly one <sensor> (the base camera), got " +
                                        (c.tag == "sensor" ? "a second <sensor>" : "<" + c.tag + ">"));
        base = &c;
    }
    if (!base) throw SceneError(rig.loc, spec.where + " needs a <sensor> inside it: the base camera of the rig");
    const RigBase base_view = rig_base(*base, spec.where, scene);
    const std::vector<RigView> views = generate_rig(spec, base_view, search_dirs, files);
    check_rig_fits(views.size(), base_view, spec);
    std::vector<XmlNode> out;
    for (const RigView &v : views) {
        check_load_cancelled();
        out.push_back(view_sensor(*base, v, rig, out.empty()));
    }
    return out;
}

void apply_rig_option(XmlNode &root, const std::string &text) {
    RigSpec spec = RigSpec::parse(text);
    size_t first = root.children.size();
    for (size_t i = 0; i < root.children.size() && first == root.children.size(); ++i)
        if (root.children[i].tag == "sensor") first = i;
    if (first == root.children.size())
        throw SceneError(root.loc, "--rig needs a base camera, but the scene has no <sensor>");
    std::vector<fs::path> dirs = {fs::current_path(), root.dir};
    for (auto &d : root.search_dirs) dirs.push_back(d);
    const XmlNode base = root.children[first];
    const RigBase base_view = rig_base(base, "--rig", root);
    const std::vector<RigView> poses = generate_rig(spec, base_view, dirs, &root.source_files);
    check_rig_fits(poses.size(), base_view, spec);
    std::vector<XmlNode> views;
    for (const RigView &v : poses) {
        check_load_cancelled();
        views.push_back(view_sensor(base, v, base, views.empty()));
    }
    std::vector<XmlNode> children;
    for (size_t i = 0; i < root.children.size(); ++i) {
        if (i == first)
            for (auto &v : views) children.push_back(std::move(v));
        if (root.children[i].tag != "sensor") children.push_back(std::move(root.children[i]));
    }
    root.children = std::move(children);
}

} // namespace mvpt
