#include "io/json_reader.hpp"

#include "test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <string>

namespace vox::io {
namespace {

using nlohmann::json;
using vox::test::error_of;

const JsonContext k_context{"doc.json", "/data"};

TEST(JsonReader, UnknownKeyIsRefusedWithItsPathAndTheKnownKeys)
{
    const json doc = json::parse(R"({"solver": {"dt_s": 0.5, "dt": 0.25}})");
    JsonReader root(JsonNode(doc, "", k_context));
    JsonReader solver(root.required_node("solver"));
    EXPECT_EQ(solver.optional("dt_s", 1.0), 0.5);
    EXPECT_FALSE(solver.optional_node("cg_tolerance")); // asked for, so known, though absent
    EXPECT_EQ(error_of([&] { solver.finish(); }),
              "doc.json: solver.dt: unknown key (known keys: dt_s, cg_tolerance)");
    EXPECT_EQ(error_of([&] { solver.finish("for a dbg solver"); }),
              "doc.json: solver.dt: unknown key for a dbg solver (known keys: dt_s, cg_tolerance)");
    EXPECT_NO_THROW(root.finish());
    EXPECT_EQ(error_of([&] { static_cast<void>(root.required_node("object")); }),
              "doc.json: object: required key is missing");
}

TEST(JsonReader, KeyPathsQuoteOddKeys)
{
    EXPECT_EQ(join_key("", "tools"), "tools");
    EXPECT_EQ(join_key(join_index("tools", 1), "size_mm-2"), "tools[1].size_mm-2");
    EXPECT_EQ(join_key("solver", "dt s"), "solver[\"dt s\"]");
    EXPECT_EQ(join_key("labels", ""), "labels[\"\"]");
}

TEST(JsonReader, BoundsSayWhatIsAllowed)
{
    const json doc = json::parse(R"({"a": -0.5, "b": 7, "c": 0.5, "d": 0, "v": [1, 0, 2]})");
    JsonReader r(JsonNode(doc, "", k_context));
    EXPECT_EQ(error_of([&] { static_cast<void>(r.required<double>("a", greater_than(0.0))); }),
              "doc.json: a: must be > 0, got -0.5");
    EXPECT_EQ(error_of([&] { static_cast<void>(r.required<int>("b", closed_range(0, 6))); }),
              "doc.json: b: must be in [0, 6], got 7");
    EXPECT_EQ(error_of([&] { static_cast<void>(r.required<double>("c", open_range(-1.0, 0.5))); }),
              "doc.json: c: must be in (-1, 0.5), got 0.5");
    EXPECT_EQ(error_of([&] { static_cast<void>(r.required<int>("d", at_least(1))); }),
              "doc.json: d: must be >= 1, got 0");
    EXPECT_EQ(error_of([&] { static_cast<void>(r.required<Eigen::Vector3d>("v", greater_than(0.0))); }),
              "doc.json: v[1]: must be > 0, got 0");
    // Closed ends are allowed.
    EXPECT_EQ(r.required<int>("b", closed_range(0, 7)), 7);
    EXPECT_EQ(r.required<double>("d", at_least(0.0)), 0.0);
}

TEST(JsonReader, TypeErrorsShowWhatWasWritten)
{
    const json doc = json::parse(
        R"({"n": "ten", "i": 2.5, "big": 3000000000, "s": 3, "v": [0, 0], "o": [1], "e": "fem"})");
    JsonReader r(JsonNode(doc, "", k_context));
    EXPECT_EQ(error_of([&] { static_cast<void>(r.required<double>("n")); }),
              "doc.json: n: expected a number, got \"ten\"");
    EXPECT_EQ(error_of([&] { static_cast<void>(r.required<int>("i")); }), "doc.json: i: expected an integer, got 2.5");
    EXPECT_EQ(error_of([&] { static_cast<void>(r.required<int>("big")); }),
              "doc.json: big: integer 3000000000 is out of range");
    EXPECT_EQ(error_of([&] { static_cast<void>(r.required<std::string>("s")); }),
              "doc.json: s: expected a string, got 3");
    EXPECT_EQ(error_of([&] { static_cast<void>(r.required<Eigen::Vector3d>("v")); }),
              "doc.json: v: expected an array of 3 numbers, got [0,0]");
    EXPECT_EQ(error_of([&] { static_cast<void>(JsonReader(r.required_node("o"))); }),
              "doc.json: o: expected an object, got [1]");
    EXPECT_EQ(error_of([&] { static_cast<void>(choose(r.required_node("e"), {"dbg", "isxfem"})); }),
              "doc.json: e: expected one of \"dbg\", \"isxfem\", got \"fem\"");
}

TEST(JsonReader, DuplicateKeysAreRefusedWithTheirPath)
{
    EXPECT_EQ(error_of([] { static_cast<void>(parse_json(R"({"a": 1, "a": 2})", "dup.json")); }),
              "dup.json: a: key given twice");
    // Elements are counted across values, objects and arrays alike.
    EXPECT_EQ(error_of([] {
                  static_cast<void>(parse_json(R"({"list": [{"k": 1}, [0, {"k": 1, "k": 2}]]})", "dup.json"));
              }),
              "dup.json: list[1][1].k: key given twice");
    EXPECT_NO_THROW(static_cast<void>(parse_json(R"({"a": {"k": 1}, "b": {"k": 1}})", "ok.json")));
}

TEST(JsonReader, SyntaxErrorsGiveLineAndColumnAndCommentsAreAllowed)
{
    const std::string message = error_of([] { static_cast<void>(parse_json("{\"a\": 1,\n}", "bad.json")); });
    EXPECT_EQ(message.rfind("bad.json: line 2 column 1: syntax error", 0), 0u) << message;
    EXPECT_EQ(parse_json("{\"a\": /* one */ 1 // done\n}", "c.json"), json({{"a", 1}}));
}

} // namespace
} // namespace vox::io
