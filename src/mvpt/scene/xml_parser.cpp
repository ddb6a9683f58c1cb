#include "xml_parser.h"

#include "parse_values.h"
#include "plugin.h"

#include <pugixml.hpp>

#include <algorithm>
#include <fstream>
#include <set>
#include <sstream>

namespace mvpt {

namespace fs = std::filesystem;

namespace {

const std::set<std::string> kObjectTags = {"bsdf", "emitter", "shape", "sensor", "film", "rfilter",
                                           "sampler", "integrator", "texture"};
const std::set<std::string> kUnsupportedTags = {"medium", "phase", "volume", "spectrum_texture"};

/// Maps byte offsets of one file to line:col.
struct SourceText {
    std::string path;
    std::vector<size_t> line_starts{0};
    explicit SourceText(std::string p, const std::string &text) : path(std::move(p)) {
        for (size_t i = 0; i < text.size(); ++i)
            if (text[i] == '\n') line_starts.push_back(i + 1);
    }
    FileLoc loc(ptrdiff_t offset) const {
        if (offset < 0) return {path, 0, 0};
        auto it = std::upper_bound(line_starts.begin(), line_starts.end(), size_t(offset));
        size_t line = size_t(it - line_starts.begin());
        return {path, int(line), int(size_t(offset) - line_starts[line - 1] + 1)};
    }
};

class Expander {
public:
    explicit Expander(std::map<std::string, std::string> defines) : m_vars(std::move(defines)) {
        for (auto &[k, v] : m_vars) m_from_caller.insert(k);
    }

    XmlNode parse_text(const std::string &text, const std::string &display_path, const fs::path &dir, int depth) {
        if (depth > 32) throw SceneError({display_path, 0, 0}, "<include> nested more than 32 levels (a cycle?)");
        if (depth == 0) m_root_dir = dir;
        auto src = std::make_shared<SourceText>(display_path, text);
        m_sources.push_back(src);
        pugi::xml_document doc;
        pugi::xml_parse_result res = doc.load_buffer(text.data(), text.size(), pugi::parse_default);
        if (!res) throw SceneError(src->loc(res.offset), std::string("malformed XML: ") + res.description());
        pugi::xml_node root = doc.document_element();
        if (!root) throw SceneError({display_path, 1, 1}, "the file has no root element");
        if (std::string(root.name()) != "scene")
            throw SceneError(src->loc(root.offset_debug()),
                             "the root element must be <scene>, got <" + std::string(root.name()) + ">");
        pugi::xml_attribute ver = root.attribute("version");
        if (!ver)
            throw SceneError(src->loc(root.offset_debug()), "<scene> needs a version attribute, e.g. version=\"3.0.0\"");
        int major = std::atoi(ver.value());
        if (major < 2)
            throw SceneError(src->loc(root.offset_debug()),
                             "scene version " + std::string(ver.value()) +
                                 " is the Mitsuba 0.x format; mvpt reads Mitsuba 3 scenes (version 3.x)");
        for (auto a : root.attributes())
            if (std::string(a.name()) != "version" && std::string(a.name()).rfind("xmlns", 0) != 0)
                throw SceneError(src->loc(root.offset_debug()),
                                 "<scene> has an unknown attribute '" + std::string(a.name()) + "'");
        XmlNode out;
        out.tag = "scene";
        out.loc = src->loc(root.offset_debug());
        out.dir = dir;
        expand_children(root, *src, dir, out, depth);
        if (depth == 0) out.search_dirs = m_path_dirs;
        return out;
    }

private:
    void expand_children(const pugi::xml_node &parent, const SourceText &src, const fs::path &dir, XmlNode &out,
                         int depth) {
        for (pugi::xml_node c : parent.children()) {
            if (c.type() != pugi::node_element) {
                if (c.type() == pugi::node_pcdata && std::string(c.value()).find_first_not_of(" \t\r\n") != std::string::npos)
                    throw SceneError(src.loc(c.offset_debug()), "unexpected text inside <" + std::string(parent.name()) + ">");
                continue;
            }
            std::string tag = c.name();
            FileLoc loc = src.loc(c.offset_debug());
            std::vector<std::pair<std::string, std::string>> attrs;
            for (auto a : c.attributes()) attrs.emplace_back(a.name(), substitute(a.value(), loc));

            if (tag == "default") {
                check_attrs(attrs, {"name", "value"}, tag, loc);
                std::string name = required(attrs, "name", tag, loc), value = required(attrs, "value", tag, loc);
                if (!m_from_caller.count(name)) m_vars[name] = value;
                continue;
            }
            if (tag == "path") {
                check_attrs(attrs, {"value"}, tag, loc);
                fs::path p = required(attrs, "value", tag, loc);
                // Relative to the including file, else (Mitsuba's file resolver) to the scene's directory.
                fs::path full = p.is_absolute() ? p : dir / p;
                if (!p.is_absolute() && !fs::is_directory(full)) full = m_root_dir / p;
                if (!fs::is_directory(full)) throw SceneError(loc, "<path> directory '" + p.string() + "' not found");
                m_path_dirs.insert(m_path_dirs.begin(), fs::absolute(full).lexically_normal());
                continue;
            }
            if (tag == "include") {
                check_attrs(attrs, {"filename"}, tag, loc);
                fs::path p = required(attrs, "filename", tag, loc);
                fs::path full = p.is_absolute() ? p : dir / p;
                for (auto &d : m_path_dirs)
                    if (!fs::is_regular_file(full) && !p.is_absolute() && fs::is_regular_file(d / p)) full = d / p;
                if (!fs::is_regular_file(full)) throw SceneError(loc, "included file '" + p.string() + "' not found");
                std::ifstream f(full, std::ios::binary);
                std::stringstream ss;
                ss << f.rdbuf();
                XmlNode inc = parse_text(ss.str(), full.string(), full.parent_path(), depth + 1);
                for (auto &ic : inc.children) out.children.push_back(std::move(ic));
                continue;
            }
            XmlNode n;
            n.tag = tag;
            n.attrs = std::move(attrs);
            n.loc = loc;
            n.dir = dir;
            expand_children(c, src, dir, n, depth);
            out.children.push_back(std::move(n));
        }
    }

    std::string substitute(const std::string &s, const FileLoc &loc) const {
        if (s.find('$') == std::string::npos) return s;
        std::string r;
        for (size_t i = 0; i < s.size();) {
            if (s[i] != '$') { r += s[i++]; continue; }
            size_t j = i + 1;
            while (j < s.size() && (std::isalnum((unsigned char)s[j]) || s[j] == '_')) ++j;
            std::string name = s.substr(i + 1, j - i - 1);
            auto it = m_vars.find(name);
            if (name.empty() || it == m_vars.end())
                throw SceneError(loc, "undefined variable '$" + name + "': add <default name=\"" + name +
                                          "\" value=\"...\"/> or pass -D " + name + "=...");
            r += it->second;
            i = j;
        }
        return r;
    }

    std::map<std::string, std::string> m_vars;
    std::set<std::string> m_from_caller;
    std::vector<fs::path> m_path_dirs;
    fs::path m_root_dir;
    std::vector<std::shared_ptr<SourceText>> m_sources;
};

// ---------------------------------------------------------------------------
// Instantiation

class Instantiator {
public:
    Instantiator(const fs::path &scene_dir, std::vector<fs::path> path_dirs)
        : m_scene_dir(scene_dir), m_path_dirs(std::move(path_dirs)) {}

    void collect_ids(const XmlNode &n) {
        for (auto &c : n.children) {
            if (kObjectTags.count(c.tag))
                if (const std::string *id = c.attr("id")) {
                    auto [it, fresh] = m_ids.emplace(*id, &c);
                    if (!fresh)
                        throw SceneError(c.loc, "duplicate id '" + *id + "' (first declared at " + it->second->loc.str() + ")");
                }
            collect_ids(c);
        }
    }

    void fill_properties(const XmlNode &node, Properties &props) {
        for (auto &c : node.children) {
            const std::string &tag = c.tag;
            if (kObjectTags.count(tag)) {
                check_attrs(c.attrs, {"type", "id", "name"}, tag, c.loc);
                ChildObject co;
                co.kind = tag;
                co.type = required(c.attrs, "type", tag, c.loc);
                co.name = c.attr("name") ? *c.attr("name") : "";
                co.id = c.attr("id") ? *c.attr("id") : "";
                co.loc = c.loc;
                co.object = instantiate_node(c);
                add_child(props, std::move(co));
            } else if (tag == "ref") {
                check_attrs(c.attrs, {"id", "name"}, tag, c.loc);
                std::string id = required(c.attrs, "id", tag, c.loc);
                auto it = m_ids.find(id);
                if (it == m_ids.end()) throw SceneError(c.loc, "<ref> to unknown id '" + id + "'");
                m_referenced.insert(id);
                ChildObject co;
                co.kind = it->second->tag;
                co.type = *it->second->attr("type");
                co.name = c.attr("name") ? *c.attr("name") : "";
                co.id = id;
                co.loc = c.loc;
                co.object = instantiate_node(*it->second);
                add_child(props, std::move(co));
            } else if (kUnsupportedTags.count(tag)) {
                throw SceneError(c.loc, "<" + tag + "> (participating media) is not supported by mvpt");
            } else {
                parse_value_node(c, props);
            }
        }
    }

    std::shared_ptr<Object> instantiate_node(const XmlNode &node) {
        auto cached = m_cache.find(&node);
        if (cached != m_cache.end()) {
            if (!cached->second) throw SceneError(node.loc, "object refers to itself through <ref>");
            return cached->second;
        }
        m_cache[&node] = nullptr; // marks "in progress" for cycle detection
        const std::string &type = *node.attr("type");
        Properties props(node.tag, type, node.loc);
        if (auto *id = node.attr("id")) props.id = *id;
        fill_properties(node, props);
        const PluginFactory *f = PluginRegistry::find(node.tag, type);
        if (!f) {
            std::string known;
            for (auto &t : PluginRegistry::types(node.tag)) known += (known.empty() ? "" : ", ") + t;
            throw SceneError(node.loc, "unknown " + node.tag + " type '" + type + "' (known: " + known + ")");
        }
        LoadContext ctx;
        ctx.search_dirs = {node.dir};
        for (auto &d : m_path_dirs) ctx.search_dirs.push_back(d);
        if (node.dir != m_scene_dir) ctx.search_dirs.push_back(m_scene_dir);
        std::shared_ptr<Object> obj = (*f)(props, ctx);
        props.check_all_queried();
        m_cache[&node] = obj;
        return obj;
    }

    bool referenced(const std::string &id) const { return m_referenced.count(id) != 0; }

private:
    static void add_child(Properties &props, ChildObject co) {
        if (!co.name.empty() && props.has(co.name))
            throw SceneError(co.loc, "parameter '" + co.name + "' is given twice (first at " + props.loc_of(co.name).str() + ")");
        props.add_child(std::move(co));
    }

    fs::path m_scene_dir;
    std::vector<fs::path> m_path_dirs;
    std::map<std::string, const XmlNode *> m_ids;
    std::set<std::string> m_referenced;
    std::map<const XmlNode *, std::shared_ptr<Object>> m_cache;
};

} // namespace

XmlNode parse_scene_file(const fs::path &path, std::map<std::string, std::string> defines) {
    if (!fs::is_regular_file(path)) throw SceneError({path.string(), 0, 0}, "scene file not found");
    std::ifstream f(path, std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    if (!f && !f.eof()) throw SceneError({path.string(), 0, 0}, "cannot read scene file");
    Expander e(std::move(defines));
    return e.parse_text(ss.str(), path.string(), fs::absolute(path).parent_path(), 0);
}

XmlNode parse_scene_string(const std::string &xml, const fs::path &base_dir, std::map<std::string, std::string> defines) {
    Expander e(std::move(defines));
    return e.parse_text(xml, "<string>", fs::absolute(base_dir), 0);
}

SceneTree instantiate_scene(const XmlNode &root, const fs::path &scene_dir) {
    Instantiator inst(scene_dir, root.search_dirs);
    inst.collect_ids(root);
    SceneTree tree;
    tree.scene_dir = scene_dir;
    tree.props = Properties("scene", "scene", root.loc);
    inst.fill_properties(root, tree.props);
    // Objects with an id that something references are owned by their users;
    // the scene itself takes the rest (Mitsuba 3 does the same).
    for (auto &c : tree.props.children())
        if (!c.id.empty() && inst.referenced(c.id)) tree.referenced_ids.insert(c.id);
    return tree;
}

} // namespace mvpt
