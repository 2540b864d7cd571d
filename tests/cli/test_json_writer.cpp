// The hand-written JSON writer: escaping, numbers (non-finite → null), structure and misuse.
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "json_writer.h"

namespace weft::json {
namespace {

TEST(JsonWriter, EscapesStrings) {
    EXPECT_EQ(json_string("plain"), "\"plain\"");
    EXPECT_EQ(json_string("a\"b\\c"), "\"a\\\"b\\\\c\"");
    EXPECT_EQ(json_string("line\nnext\ttab\rcr\b\f"), "\"line\\nnext\\ttab\\rcr\\b\\f\"");
    EXPECT_EQ(json_string(std::string_view("\x01\x1f", 2)), "\"\\u0001\\u001f\"");
    EXPECT_EQ(json_string(std::string_view("nul\0byte", 8)), "\"nul\\u0000byte\"");
    EXPECT_EQ(json_string("C:/path/é ×"), "\"C:/path/é ×\"");  // UTF-8 passes through
}

TEST(JsonWriter, Numbers) {
    EXPECT_EQ(json_number(0.1), "0.1");
    EXPECT_EQ(json_number(100.0), "100");
    EXPECT_EQ(json_number(-2.5e-7), "-2.5e-07");
    EXPECT_EQ(json_number(std::numeric_limits<double>::quiet_NaN()), "null");
    EXPECT_EQ(json_number(std::numeric_limits<double>::infinity()), "null");
    EXPECT_EQ(json_number(-std::numeric_limits<double>::infinity()), "null");
    // Shortest round-trip form: reading it back gives the same double.
    const double third = 1.0 / 3.0;
    EXPECT_EQ(std::stod(json_number(third)), third);
}

TEST(JsonWriter, Document) {
    std::ostringstream out;
    JsonWriter json(out);
    json.begin_object();
    json.field("name", "flag \"big\"");
    json.field("count", std::size_t{3});
    json.field("neg", -4);
    json.field("ok", true);
    json.field("nan", std::numeric_limits<double>::quiet_NaN());
    json.key("none").null();
    json.key("series").begin_array(true).value(1.5).value(2).end_array();
    json.key("empty").begin_array().end_array();
    json.key("nested").begin_object().field("u64", std::numeric_limits<std::uint64_t>::max()).end_object();
    json.key("list").begin_array().begin_object().end_object().value("x").end_array();
    json.end_object();
    EXPECT_TRUE(json.done());
    EXPECT_EQ(out.str(),
              "{\n"
              "  \"name\": \"flag \\\"big\\\"\",\n"
              "  \"count\": 3,\n"
              "  \"neg\": -4,\n"
              "  \"ok\": true,\n"
              "  \"nan\": null,\n"
              "  \"none\": null,\n"
              "  \"series\": [1.5, 2],\n"
              "  \"empty\": [],\n"
              "  \"nested\": {\n"
              "    \"u64\": 18446744073709551615\n"
              "  },\n"
              "  \"list\": [\n"
              "    {},\n"
              "    \"x\"\n"
              "  ]\n"
              "}\n");
}

TEST(JsonWriter, MisuseThrows) {
    std::ostringstream out;
    {
        JsonWriter json(out);
        json.begin_object();
        EXPECT_THROW(json.value(1), std::logic_error);  // value without key
        EXPECT_THROW(json.end_array(), std::logic_error);
        json.key("a");
        EXPECT_THROW(json.key("b"), std::logic_error);
        EXPECT_THROW(json.end_object(), std::logic_error);  // dangling key
    }
    {
        JsonWriter json(out);
        json.begin_array();
        EXPECT_THROW(json.key("k"), std::logic_error);
        json.end_array();
        EXPECT_THROW(json.value(2), std::logic_error);  // second root
    }
}

}  // namespace
}  // namespace weft::json
