// Value elements of scene files (<float>, <rgb>, <transform>, ...) -> Properties.
#pragma once

#include "../core/plugin.h"
#include "../core/properties.h"
#include "xml_parser.h"

#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

namespace mvpt {

/// Error (at the offending attribute) unless every attribute is one of `allowed`.
void check_attrs(const XmlAttrs &attrs, std::initializer_list<const char *> allowed, const std::string &tag,
                 const FileLoc &loc);
/// The value of attribute `name`, or an error naming the tag.
std::string required(const XmlAttrs &attrs, const std::string &name, const std::string &tag, const FileLoc &loc);

/// Parse a finite float; errors name `what` and the location.
double parse_float(const std::string &s, const FileLoc &loc, const std::string &what);
int64_t parse_int(const std::string &s, const FileLoc &loc, const std::string &what);
/// Comma- and/or space-separated list of finite floats.
std::vector<double> parse_float_list(const std::string &s, const FileLoc &loc, const std::string &what);

/// Compose the operations inside a <transform> element; each one applies after the previous.
Transform parse_transform_ops(const XmlNode &node);

/// Parse one value element (not an object) and store it in `props`; `ctx` resolves
/// file names (`<spectrum filename="...">`).
void parse_value_node(const XmlNode &node, Properties &props, const LoadContext &ctx);

} // namespace mvpt
