// The XML front end reports errors at the right file:line:col (the '<' of an element, or
// the name of the offending attribute) without needing the Python layer.
#include "mvpt/core/suggest.h"
#include "mvpt/loader/xml_parser.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

using namespace mvpt;
namespace fs = std::filesystem;

namespace {

/// The SceneError of parsing `xml` (fails the test if there is none).
SceneError parse_error(const std::string &xml, std::map<std::string, std::string> defines = {}) {
    try {
        parse_scene_string(xml, ".", std::move(defines));
    } catch (const SceneError &e) {
        return e;
    }
    ADD_FAILURE() << "no error for: " << xml;
    return SceneError({}, "");
}

} // namespace

TEST(ParserErrors, ElementsAndAttributesAreLocated) {
    XmlNode root = parse_scene_string("<scene version=\"3.0.0\">\n  <shape type=\"cube\"   id=\"a\"/>\n</scene>", ".", {});
    ASSERT_EQ(root.children.size(), 1u);
    const XmlNode &shape = root.children[0];
    EXPECT_EQ(shape.loc.line, 2);
    EXPECT_EQ(shape.loc.col, 3); // the '<'
    EXPECT_EQ(shape.attr_loc("type").col, 10);
    EXPECT_EQ(shape.attr_loc("id").col, 24);
    EXPECT_EQ(shape.attr_loc("absent").col, 3); // falls back to the element
}

TEST(ParserErrors, UnclosedElementIsNamed) {
    SceneError e = parse_error("<scene version=\"3.0.0\">\n  <shape type=\"cube\">\n    <bsdf type=\"diffuse\">\n  </shape>\n</scene>");
    EXPECT_EQ(e.loc().line, 3);
    EXPECT_EQ(e.loc().col, 5);
    EXPECT_NE(e.message().find("<bsdf> is not closed"), std::string::npos) << e.what();
    SceneError eof = parse_error("<scene version=\"3.0.0\">\n  <!-- <shape> in a comment -->\n  <shape type=\"cube\">\n");
    EXPECT_EQ(eof.loc().line, 3);
    EXPECT_NE(eof.message().find("before the end of the file"), std::string::npos) << eof.what();
}

TEST(ParserErrors, AttributeValueErrorsPointAtTheAttribute) {
    SceneError e = parse_error("<scene version=\"3.0.0\">\n<shape type=\"cube\" id=\"$missing\"/></scene>");
    EXPECT_EQ(e.loc().line, 2);
    EXPECT_EQ(e.loc().col, 20);
    EXPECT_NE(e.message().find("undefined variable '$missing'"), std::string::npos) << e.what();
    SceneError v = parse_error("<scene version=\"x.5.0\"/>");
    EXPECT_EQ(v.loc().col, 8);
}

TEST(ParserErrors, UnusedDefineIsAnError) {
    EXPECT_NO_THROW(parse_scene_string("<scene version=\"3.0.0\"><default name=\"a\" value=\"1\"/>"
                                       "<shape type=\"$a\"/></scene>", ".", {{"a", "cube"}}));
    SceneError e = parse_error("<scene version=\"3.0.0\"/>", {{"spp", "4"}});
    EXPECT_NE(e.message().find("spp=4 is not used"), std::string::npos) << e.what();
}

TEST(ParserErrors, IncludeCycleNamesTheChain) {
    fs::path dir = fs::temp_directory_path() / ("mvpt_parser_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
    fs::create_directories(dir);
    std::ofstream(dir / "a.xml") << "<scene version=\"3.0.0\">\n  <include filename=\"b.xml\"/>\n</scene>\n";
    std::ofstream(dir / "b.xml") << "<scene version=\"3.0.0\">\n\n  <include filename=\"a.xml\"/>\n</scene>\n";
    try {
        parse_scene_file(dir / "a.xml", {});
        ADD_FAILURE() << "no error for an include cycle";
    } catch (const SceneError &e) {
        EXPECT_EQ(fs::path(e.loc().file).filename(), "b.xml");
        EXPECT_EQ(e.loc().line, 3);
        EXPECT_EQ(e.message(), "include cycle: a.xml -> b.xml -> a.xml");
    }
    fs::remove_all(dir);
}

TEST(ParserErrors, DidYouMean) {
    EXPECT_EQ(edit_distance("flaot", "float"), 1u); // a swap is one edit
    EXPECT_EQ(edit_distance("radiuss", "radius"), 1u);
    EXPECT_EQ(edit_distance("", "abc"), 3u);
    EXPECT_EQ(did_you_mean("radiuss", {"center", "radius", "to_world"}), " (did you mean 'radius'?)");
    EXPECT_EQ(did_you_mean("spheroid", {"sphere", "cube"}), ""); // too far: no guess
    EXPECT_EQ(did_you_mean("x", {"x"}), "");                  // never the name itself
}
