#include "xml_parser.h"

#include "legacy_upgrade.h"
#include "load_control.h"
#include "parse_values.h"
#include "../core/plugin.h"
#include "rig.h"
#include "../core/suggest.h"
#include "../render/shape.h"

#include <pugixml.hpp>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>

namespace mvpt {

namespace fs = std::filesystem;

namespace {

const std::set<std::string> kObjectTags = {"bsdf", "emitter", "shape", "sensor", "film", "rfilter", "sampler",
                                           "integrator", "texture", "medium", "phase", "volume"};

/// Maps byte offsets of one file to line:col.
struct SourceText {
    std::string path;
    std::string text;
    std::vector<size_t> line_starts{0};
    SourceText(std::string p, std::string t) : path(std::move(p)), text(std::move(t)) {
        for (size_t i = 0; i < text.size(); ++i)
            if (text[i] == '\n') line_starts.push_back(i + 1);
    }
    FileLoc loc(ptrdiff_t offset) const {
        if (offset < 0) return {path, 0, 0};
        auto it = std::upper_bound(line_starts.begin(), line_starts.end(), size_t(offset));
        size_t line = size_t(it - line_starts.begin());
        return {path, int(line), int(size_t(offset) - line_starts[line - 1] + 1)};
    }
    /// Location of an element's '<' (pugixml's offset_debug points at its name).
    FileLoc element_loc(const pugi::xml_node &n) const { return loc(n.offset_debug() - 1); }

    /// The element's attributes with the location of each name, found by re-scanning the
    /// start tag (pugixml keeps no attribute offsets; the tag has already been validated).
    XmlAttrs attributes(const pugi::xml_node &n) const {
        XmlAttrs out;
        size_t i = size_t(n.offset_debug()) + std::strlen(n.name());
        for (pugi::xml_attribute a : n.attributes()) {
            FileLoc at;
            while (i < text.size() && std::isspace((unsigned char)text[i])) ++i;
            if (text.compare(i, std::strlen(a.name()), a.name()) == 0) {
                at = loc(ptrdiff_t(i));
                i = text.find_first_of("\"'", i);
                if (i != std::string::npos) i = text.find(text[i], i + 1);
                i = i == std::string::npos ? text.size() : i + 1;
            } else {
                i = text.size(); // unexpected layout: fall back to the element's location
            }
            out.emplace_back(a.name(), a.value(), at);
        }
        return out;
    }

    /// After pugixml reports mismatched tags: find the element that was left open by
    /// replaying the start/end tags up to the error and name it.
    [[noreturn]] void fail_unclosed(ptrdiff_t error_offset) const {
        std::vector<std::pair<std::string, size_t>> open;
        size_t i = 0, end = std::min(text.size(), size_t(std::max<ptrdiff_t>(error_offset, 0)) + 1);
        auto skip_past = [&](const char *marker) {
            size_t j = text.find(marker, i);
            i = j == std::string::npos ? text.size() : j + std::strlen(marker);
        };
        auto read_name = [&](size_t j) {
            size_t k = j;
            while (k < text.size() && !std::isspace((unsigned char)text[k]) && text[k] != '>' && text[k] != '/') ++k;
            return text.substr(j, k - j);
        };
        while (i < end) {
            i = text.find('<', i);
            if (i == std::string::npos || i >= end) break;
            if (text.compare(i, 4, "<!--") == 0) { skip_past("-->"); continue; }
            if (text.compare(i, 9, "<![CDATA[") == 0) { skip_past("]]>"); continue; }
            if (text.compare(i, 2, "<?") == 0) { skip_past("?>"); continue; }
            if (text.compare(i, 2, "<!") == 0) { skip_past(">"); continue; }
            if (text.compare(i, 2, "</") == 0) {
                size_t at = i;
                std::string name = read_name(i + 2);
                skip_past(">");
                bool is_open = std::any_of(open.begin(), open.end(), [&](const auto &o) { return o.first == name; });
                if (!is_open)
                    throw SceneError(loc(ptrdiff_t(at)), "malformed XML: </" + name + "> closes no open element" +
                                                             (open.empty() ? std::string()
                                                                           : " (expected </" + open.back().first + ">)"));
                if (open.back().first != name)
                    throw SceneError(loc(ptrdiff_t(open.back().second)),
                                     "malformed XML: <" + open.back().first + "> is not closed (expected </" +
                                         open.back().first + "> before the </" + name + "> at " + loc(ptrdiff_t(at)).str() + ")");
                open.pop_back();
                continue;
            }
            size_t at = i;
            std::string name = read_name(i + 1);
            char quote = 0;
            for (++i; i < text.size(); ++i) {
                char c = text[i];
                if (quote) { if (c == quote) quote = 0; }
                else if (c == '"' || c == '\'') quote = c;
                else if (c == '>') break;
            }
            bool self_closing = i < text.size() && text[i - 1] == '/';
            if (!self_closing) open.emplace_back(name, at);
            ++i;
        }
        if (!open.empty())
            throw SceneError(loc(ptrdiff_t(open.back().second)),
                             "malformed XML: <" + open.back().first + "> is not closed before the end of the file");
        throw SceneError(loc(error_offset), "malformed XML: start and end tags do not match");
    }
};

/// pugixml's status as a message that says what was expected.
std::string describe(const pugi::xml_parse_result &res) {
    switch (res.status) {
        case pugi::status_bad_attribute: return "malformed XML: bad attribute syntax (expected name=\"value\")";
        case pugi::status_bad_start_element: return "malformed XML: bad start tag (expected <name attribute=\"value\" ...> or />)";
        case pugi::status_bad_end_element: return "malformed XML: bad end tag (expected </name>)";
        case pugi::status_bad_comment: return "malformed XML: bad comment (expected <!-- ... -->)";
        case pugi::status_unrecognized_tag: return "malformed XML: unrecognised tag after '<'";
        default: return std::string("malformed XML: ") + res.description();
    }
}

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
        // Names, ids, values and file names are text: a byte that is not UTF-8 is an error where it is.
        if (const size_t bad = first_invalid_utf8(text); bad != std::string::npos)
            throw SceneError(src->loc(ptrdiff_t(bad)), "a byte that is not UTF-8 text: " +
                                                           escape_invalid_utf8(text.substr(bad, 1)) +
                                                           " (scene files are UTF-8)");
        pugi::xml_document doc;
        pugi::xml_parse_result res = doc.load_buffer(text.data(), text.size(), pugi::parse_default);
        if (res.status == pugi::status_end_element_mismatch) src->fail_unclosed(res.offset);
        if (res.status == pugi::status_no_document_element)
            throw SceneError({display_path, 1, 1}, "the file has no root element (expected <scene version=\"3.0.0\">)");
        if (!res) throw SceneError(src->loc(res.offset), describe(res));
        pugi::xml_node root = doc.document_element();
        FileLoc root_loc = src->element_loc(root);
        if (std::string(root.name()) != "scene")
            throw SceneError(root_loc, "the root element must be <scene>, got <" + std::string(root.name()) + ">");
        XmlAttrs root_attrs = src->attributes(root);
        const XmlAttr *ver = nullptr;
        for (auto &a : root_attrs) {
            if (a.first == "version") ver = &a;
            else if (a.first.rfind("xmlns", 0) != 0)
                throw SceneError(a.loc.line > 0 ? a.loc : root_loc, "<scene> has an unknown attribute '" + a.first + "'");
        }
        if (!ver) throw SceneError(root_loc, "<scene> needs a version attribute, e.g. version=\"3.0.0\"");
        int major = -1;
        if (!ver->second.empty() && std::isdigit((unsigned char)ver->second[0])) major = std::atoi(ver->second.c_str());
        if (major < 0)
            throw SceneError(ver->loc, "scene version '" + ver->second + "' is not a version number (expected e.g. \"3.0.0\")");
        const bool legacy = is_legacy_version(major);
        if (legacy)
            m_notes.push_back("'" + fs::path(display_path).filename().string() + "' is in the Mitsuba " + ver->second +
                              " format: upgraded on load as Mitsuba 3 does (camelCase names to snake_case)");
        XmlNode out;
        out.tag = "scene";
        out.loc = root_loc;
        out.dir = dir;
        expand_children(root, *src, dir, out, depth, legacy);
        if (depth == 0) out.search_dirs = m_path_dirs, out.source_files = m_files, out.notes = m_notes;
        return out;
    }

    /// Push `path` on the stack of files being expanded; an include cycle is an error at `included_at`.
    fs::path enter_file(const fs::path &path, const FileLoc *included_at) {
        std::error_code ec;
        fs::path key = fs::weakly_canonical(path, ec);
        if (ec) key = fs::absolute(path);
        for (size_t i = 0; i < m_stack.size(); ++i)
            if (m_stack[i] == key) {
                std::string chain;
                for (size_t j = i; j < m_stack.size(); ++j) chain += m_stack[j].filename().string() + " -> ";
                throw SceneError(included_at ? *included_at : FileLoc{path.string(), 0, 0},
                                 "include cycle: " + chain + key.filename().string());
            }
        m_stack.push_back(key);
        m_files.push_back(key);
        return key;
    }
    void leave_file(const fs::path &key) {
        if (!m_stack.empty() && m_stack.back() == key) m_stack.pop_back();
    }

    /// Like Mitsuba: a caller's define that the scene never uses as $name is an error (a typo, usually).
    void check_defines_used(const std::string &display_path) const {
        for (const std::string &name : m_from_caller)
            if (!m_used.count(name))
                throw SceneError({display_path, 0, 0}, "the define " + name + "=" + m_vars.at(name) +
                                                           " is not used: the scene has no $" + name);
    }

private:
    void expand_children(const pugi::xml_node &parent, const SourceText &src, const fs::path &dir, XmlNode &out,
                         int depth, bool legacy) {
        for (pugi::xml_node c : parent.children()) {
            if (c.type() != pugi::node_element) {
                check_text(parent, c, src);
                continue;
            }
            std::string tag = c.name();
            FileLoc loc = src.element_loc(c);
            XmlAttrs attrs = src.attributes(c);
            for (auto &a : attrs) a.second = substitute(a.second, a.loc.line > 0 ? a.loc : loc);

            if (tag == "default") {
                check_attrs(attrs, {"name", "value"}, tag, loc);
                std::string name = required(attrs, "name", tag, loc), value = required(attrs, "value", tag, loc);
                // The first value of a name wins (the caller's, then the first <default>), as in
                // Mitsuba: an included file's defaults do not override its includer's.
                m_vars.emplace(name, value);
            } else if (tag == "path") {
                add_path(attrs, loc, dir);
            } else if (tag == "include") {
                include(attrs, loc, dir, out, depth);
            } else {
                XmlNode n;
                n.tag = tag;
                n.attrs = std::move(attrs);
                n.loc = loc;
                n.dir = dir;
                if (++m_nesting > 256) throw SceneError(loc, "elements nested more than 256 levels deep");
                expand_children(c, src, dir, n, depth, legacy);
                --m_nesting;
                if (legacy) upgrade_legacy_element(n, m_notes);
                if (is_rig_element(tag)) expand_rig(parent, n, dir, out);
                else out.children.push_back(std::move(n));
            }
        }
    }

    /// Text between elements: whitespace only, and no CDATA sections.
    static void check_text(const pugi::xml_node &parent, const pugi::xml_node &c, const SourceText &src) {
        if (c.type() == pugi::node_cdata) // (pugixml's offset is that of the content, after "<![CDATA[")
            throw SceneError(src.loc(std::max<ptrdiff_t>(0, c.offset_debug() - 9)),
                             "a CDATA section inside <" + std::string(parent.name()) +
                                 ">: scene files say everything with elements and attributes");
        if (c.type() == pugi::node_pcdata && std::string(c.value()).find_first_not_of(" \t\r\n") != std::string::npos)
            throw SceneError(src.loc(c.offset_debug()), "unexpected text inside <" + std::string(parent.name()) + ">");
    }

    /// <path value="..."/>: a directory searched for includes and files, before the others.
    void add_path(const XmlAttrs &attrs, const FileLoc &loc, const fs::path &dir) {
        check_attrs(attrs, {"value"}, "path", loc);
        fs::path p = required(attrs, "value", "path", loc);
        // Relative to the including file, else (Mitsuba's file resolver) to the scene's directory.
        fs::path full = p.is_absolute() ? p : dir / p;
        if (!p.is_absolute() && !fs::is_directory(full)) full = m_root_dir / p;
        if (!fs::is_directory(full)) throw SceneError(loc, "<path> directory '" + p.string() + "' not found");
        m_path_dirs.insert(m_path_dirs.begin(), fs::absolute(full).lexically_normal());
    }

    /// <include filename="..."/>: the file's elements in its place.
    void include(const XmlAttrs &attrs, const FileLoc &loc, const fs::path &dir, XmlNode &out, int depth) {
        check_attrs(attrs, {"filename"}, "include", loc);
        fs::path p = required(attrs, "filename", "include", loc);
        fs::path full = p.is_absolute() ? p : dir / p;
        for (auto &d : m_path_dirs)
            if (!fs::is_regular_file(full) && !p.is_absolute() && fs::is_regular_file(d / p)) full = d / p;
        if (!fs::is_regular_file(full)) throw SceneError(loc, "included file '" + p.string() + "' not found");
        std::ifstream f(full, std::ios::binary);
        std::stringstream ss;
        ss << f.rdbuf();
        fs::path key = enter_file(full, &loc);
        XmlNode inc = parse_text(ss.str(), full.string(), full.parent_path(), depth + 1);
        leave_file(key);
        for (auto &ic : inc.children) out.children.push_back(std::move(ic));
    }

    /// A camera rig becomes plain sensors here, before instantiation (rig_xml.cpp).
    void expand_rig(const pugi::xml_node &parent, XmlNode &rig, const fs::path &dir, XmlNode &out) {
        if (std::string(parent.name()) != "scene")
            throw SceneError(rig.loc, "<" + rig.tag + "> must be placed directly inside <scene>");
        std::vector<fs::path> dirs = {dir};
        dirs.insert(dirs.end(), m_path_dirs.begin(), m_path_dirs.end());
        dirs.push_back(m_root_dir);
        for (XmlNode &s : expand_rig_element(rig, out, dirs, &m_files)) out.children.push_back(std::move(s));
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
            if (it != m_vars.end()) m_used.insert(name);
            if (name.empty() || it == m_vars.end())
                throw SceneError(loc, "undefined variable '$" + name + "': add <default name=\"" + name +
                                          "\" value=\"...\"/> or pass -D " + name + "=...");
            r += it->second;
            if (r.size() > MaxSubstitution)
                throw SceneError(loc, "substituting $" + name + " makes a value longer than " +
                                          std::to_string(MaxSubstitution >> 20) + " MiB (defaults that double each other?)");
            i = j;
        }
        return r;
    }

    /// The longest value substitutions may make (chained defaults could grow without bound).
    static constexpr size_t MaxSubstitution = size_t(1) << 20;
    std::map<std::string, std::string> m_vars;
    std::set<std::string> m_from_caller;
    std::vector<fs::path> m_path_dirs;
    fs::path m_root_dir;
    std::vector<std::shared_ptr<SourceText>> m_sources;
    std::vector<fs::path> m_stack;   ///< files being expanded, outermost first
    std::vector<fs::path> m_files;   ///< every XML file read, in order
    std::vector<std::string> m_notes; ///< what upgrading Mitsuba 0.6 files changed
    mutable std::set<std::string> m_used; ///< variables substituted at least once
    int m_nesting = 0;
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
                    required(c.attrs, "type", c.tag, c.loc); // a <ref> may instantiate it before its turn
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
                auto in_progress = m_cache.find(it->second);
                if (in_progress != m_cache.end() && !in_progress->second)
                    throw SceneError(c.loc, "<ref id=\"" + id + "\"> refers to an object that contains it (declared at " +
                                                it->second->loc.str() + ")");
                m_referenced.insert(id);
                ChildObject co;
                co.kind = it->second->tag;
                co.type = *it->second->attr("type");
                co.name = c.attr("name") ? *c.attr("name") : "";
                co.id = id;
                co.loc = c.loc;
                co.object = instantiate_node(*it->second);
                add_child(props, std::move(co));
            } else {
                parse_value_node(c, props, context_for(c));
            }
        }
    }

    std::shared_ptr<Object> instantiate_node(const XmlNode &node) {
        auto cached = m_cache.find(&node);
        if (cached != m_cache.end()) {
            if (!cached->second) throw SceneError(node.loc, "object refers to itself through <ref>");
            return cached->second;
        }
        check_load_cancelled();
        m_cache[&node] = nullptr; // marks "in progress" for cycle detection
        const std::string &type = *node.attr("type");
        Properties props(node.tag, type, node.loc);
        if (auto *id = node.attr("id")) props.id = *id;
        fill_properties(node, props);
        const PluginFactory *f = PluginRegistry::find(node.tag, type);
        if (!f) {
            std::vector<std::string> types = PluginRegistry::types(node.tag);
            std::string known;
            for (auto &t : types) known += (known.empty() ? "" : ", ") + t;
            std::string hint = did_you_mean(type, types);
            throw SceneError(node.loc, "unknown " + node.tag + " type '" + type + "'" +
                                           (!hint.empty() ? hint : types.empty() ? " (mvpt has no " + node.tag + " plugins yet)"
                                                                                 : " (known: " + known + ")"));
        }
        std::shared_ptr<Object> obj = (*f)(props, context_for(node));
        props.check_all_queried();
        collect_mesh_attributes(node, props, *obj);
        m_cache[&node] = obj;
        return obj;
    }

    /// The mesh attributes read by the materials and textures inside `node` become those of
    /// `obj`; a shape must have every one (a mesh_attribute texture reads the shape it hits).
    static void collect_mesh_attributes(const XmlNode &node, const Properties &props, Object &obj) {
        for (const ChildObject &c : props.children())
            if (c.kind == "bsdf" || c.kind == "texture")
                for (const std::string &name : c.object->mesh_attributes)
                    if (std::find(obj.mesh_attributes.begin(), obj.mesh_attributes.end(), name) == obj.mesh_attributes.end())
                        obj.mesh_attributes.push_back(name);
        if (node.tag != "shape" || obj.mesh_attributes.empty()) return;
        const std::vector<std::string> has = static_cast<const Shape &>(obj).attribute_names();
        for (const std::string &name : obj.mesh_attributes)
            if (std::find(has.begin(), has.end(), name) == has.end()) {
                std::string list;
                for (const std::string &h : has) list += (list.empty() ? "" : ", ") + h;
                throw SceneError(node.loc, "this shape's material reads the mesh attribute '" + name +
                                               "', which the shape does not have (" +
                                               (has.empty() ? std::string("it has no attributes: they come from PLY files")
                                                            : "it has: " + list) + ")");
            }
    }

    bool referenced(const std::string &id) const { return m_referenced.count(id) != 0; }
    /// The data files the factories resolved, in order.
    const std::vector<fs::path> &files() const { return m_files; }
    /// The warnings the factories recorded, in order.
    const std::vector<std::string> &warnings() const { return m_warnings; }
    /// The notes the factories recorded, in order.
    const std::vector<std::string> &data_notes() const { return m_data_notes; }

private:
    /// Where files named by `node` are looked for: its file's directory, <path> dirs, the scene's.
    LoadContext context_for(const XmlNode &node) const {
        LoadContext ctx;
        ctx.search_dirs = {node.dir};
        for (auto &d : m_path_dirs) ctx.search_dirs.push_back(d);
        if (node.dir != m_scene_dir) ctx.search_dirs.push_back(m_scene_dir);
        ctx.files = &m_files;
        ctx.warnings = &m_warnings, ctx.notes = &m_data_notes;
        return ctx;
    }

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
    mutable std::vector<fs::path> m_files; ///< data files the factories resolved
    mutable std::vector<std::string> m_warnings, m_data_notes; ///< what the factories warned of, noted
};

} // namespace

XmlNode parse_scene_file(const fs::path &path, std::map<std::string, std::string> defines) {
    if (!fs::is_regular_file(path)) throw SceneError({path.string(), 0, 0}, "scene file not found");
    std::ifstream f(path, std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    if (!f && !f.eof()) throw SceneError({path.string(), 0, 0}, "cannot read scene file");
    Expander e(std::move(defines));
    fs::path key = e.enter_file(path, nullptr);
    XmlNode root = e.parse_text(ss.str(), path.string(), fs::absolute(path).parent_path(), 0);
    e.leave_file(key);
    e.check_defines_used(path.string());
    return root;
}

XmlNode parse_scene_string(const std::string &xml, const fs::path &base_dir, std::map<std::string, std::string> defines) {
    Expander e(std::move(defines));
    XmlNode root = e.parse_text(xml, "<string>", fs::absolute(base_dir), 0);
    e.check_defines_used("<string>");
    return root;
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
    tree.source_files = root.source_files;
    tree.notes = root.notes;
    tree.warnings = inst.warnings();
    tree.notes.insert(tree.notes.end(), inst.data_notes().begin(), inst.data_notes().end());
    for (const fs::path &f : inst.files())
        if (std::find(tree.source_files.begin(), tree.source_files.end(), f) == tree.source_files.end())
            tree.source_files.push_back(f);
    return tree;
}

} // namespace mvpt
