#include "legacy_upgrade.h"

#include <algorithm>
#include <cctype>
#include <set>

namespace mvpt {

namespace {

/// Mitsuba 3's rule, scanned as it does: a lower-case letter followed by a capital gets an
/// underscore, and the run of capitals after it is lowered ("toWorld" -> "to_world",
/// "intIOR" -> "int_ior"); the letter after such a run starts the next scan step.
std::string snake_case(std::string name) {
    for (size_t i = 0; i + 1 < name.size(); ++i) {
        if (!std::islower((unsigned char)name[i]) || !std::isupper((unsigned char)name[i + 1])) continue;
        name.insert(i + 1, 1, '_');
        for (i += 2; i < name.size() && std::isupper((unsigned char)name[i]); ++i)
            name[i] = char(std::tolower((unsigned char)name[i]));
    }
    return name;
}

XmlAttr *find_attr(XmlNode &n, const std::string &name) {
    for (auto &a : n.attrs)
        if (a.first == name) return &a;
    return nullptr;
}

/// The child value element named `name`, or null.
XmlNode *child_named(XmlNode &n, const std::string &name) {
    for (auto &c : n.children)
        if (const std::string *v = c.attr("name"); v && *v == name) return &c;
    return nullptr;
}

/// Remove the children named in `names`; returns the names removed, comma-separated.
std::string drop_children(XmlNode &n, std::initializer_list<const char *> names) {
    std::string dropped;
    for (const char *name : names)
        if (XmlNode *c = child_named(n, name)) {
            dropped += (dropped.empty() ? "" : ", ") + std::string(name);
            n.children.erase(n.children.begin() + (c - n.children.data()));
        }
    return dropped;
}

/// Add `text` (with where it first applies) unless a note of that text is there already.
void note(std::vector<std::string> &notes, const std::string &text, const FileLoc &where) {
    for (const std::string &n : notes)
        if (n.compare(0, text.size(), text) == 0) return;
    notes.push_back(text + " (first at " + where.str() + ")");
}

const std::set<std::string> kLegacyIntegrators = {"bdpt", "mlt", "pssmlt", "erpt", "ppm", "sppm",
                                                  "photonmapper", "ptracer", "vpl"};

void upgrade_object(XmlNode &n, XmlAttr &type, std::vector<std::string> &notes) {
    if (n.tag == "bsdf" && type.second == "diffuse") {
        if (XmlNode *c = child_named(n, "diffuse_reflectance")) find_attr(*c, "name")->second = "reflectance";
    } else if (n.tag == "bsdf" && type.second == "roughdiffuse") {
        type.second = "diffuse";
        drop_children(n, {"alpha", "use_fast_approx"});
        note(notes, "Mitsuba 0.6's roughdiffuse (Oren-Nayar) is rendered as diffuse (Lambertian), its alpha ignored", n.loc);
    } else if ((n.tag == "bsdf" && (type.second == "conductor" || type.second == "roughconductor"))) {
        if (XmlNode *c = child_named(n, "ext_eta"); c && c->attr("value") && *c->attr("value") == "1")
            drop_children(n, {"ext_eta"}); // eta relative to vacuum already; any other value stays an error
    } else if (n.tag == "texture" && type.second == "bitmap") {
        XmlNode *c = child_named(n, "filter_type");
        const std::string *v = c ? c->attr("value") : nullptr;
        if (v && (*v == "trilinear" || *v == "ewa")) {
            note(notes, "Mitsuba 0.6's " + *v + " texture filter is read as bilinear (no MIP maps)", n.loc);
            find_attr(*c, "value")->second = "bilinear";
        }
    } else if (n.tag == "film" && (type.second == "hdrfilm" || type.second == "ldrfilm")) {
        std::string dropped = drop_children(n, {"gamma", "banner", "attach_log", "high_quality_edges", "tonemap_method",
                                                "exposure", "key", "burn"});
        if (type.second == "ldrfilm") type.second = "hdrfilm", dropped += dropped.empty() ? "ldrfilm" : ", ldrfilm";
        if (!dropped.empty())
            note(notes, "the film's Mitsuba 0.6 display settings (" + dropped +
                            ") are ignored: mvpt writes linear EXR images", n.loc);
    } else if (n.tag == "integrator" && kLegacyIntegrators.count(type.second)) {
        std::string was = type.second;
        type.second = "path";
        auto keep = [](const XmlNode &c) {
            const std::string *name = c.attr("name");
            return name && (*name == "max_depth" || *name == "rr_depth" || *name == "hide_emitters");
        };
        n.children.erase(std::remove_if(n.children.begin(), n.children.end(), [&](const XmlNode &c) { return !keep(c); }),
                         n.children.end());
        note(notes, "Mitsuba 0.6's '" + was + "' integrator is rendered with 'path' (same image in the limit; its "
                    "depths kept, its other settings ignored)", n.loc);
    } else if (n.tag == "integrator" && type.second == "volpath_simple") {
        type.second = "volpath";
    }
}

} // namespace

bool is_legacy_version(int major) { return major < 2; }

void upgrade_legacy_element(XmlNode &n, std::vector<std::string> &notes) {
    if (n.tag == "lookAt") n.tag = "lookat";
    if (XmlAttr *name = find_attr(n, "name")) name->second = snake_case(name->second);
    if (XmlAttr *type = find_attr(n, "type")) upgrade_object(n, *type, notes);
}

} // namespace mvpt
