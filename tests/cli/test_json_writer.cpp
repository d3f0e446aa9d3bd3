#include "cli/json_writer.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <optional>
#include <random>
#include <regex>
#include <stdexcept>
#include <string>
#include <vector>

namespace hopper::cli {
namespace {

// The number grammar of RFC 8259, section 6.
bool is_json_number(const std::string& s) {
    static const std::regex grammar(R"(-?(0|[1-9][0-9]*)(\.[0-9]+)?([eE][+-]?[0-9]+)?)");
    return std::regex_match(s, grammar);
}

TEST(JsonQuote, EscapesQuotesAndBackslashes) {
    EXPECT_EQ(json_quote(R"(say "hi")"), R"("say \"hi\"")");
    EXPECT_EQ(json_quote(R"(C:\dir\file)"), R"("C:\\dir\\file")");
    EXPECT_EQ(json_quote(""), R"("")");
    EXPECT_EQ(json_quote("/"), R"("/")");  // solidus need not be escaped
}

TEST(JsonQuote, EscapesEveryControlCharacter) {
    EXPECT_EQ(json_quote("a\nb\tc\rd\be\ff"), R"("a\nb\tc\rd\be\ff")");
    EXPECT_EQ(json_quote(std::string("\x01\x1f", 2)), R"("\u0001\u001f")");
    EXPECT_EQ(json_quote(std::string("x\0y", 3)), R"("x\u0000y")");
    // No raw byte below 0x20 may survive.
    std::string all;
    for (int c = 0; c < 0x20; ++c)
        all += static_cast<char>(c);
    const std::string q = json_quote(all);
    for (char c : q)
        EXPECT_GE(static_cast<unsigned char>(c), 0x20u);
    EXPECT_EQ(json_quote("\x7f"), "\"\x7f\"");  // DEL is allowed raw in JSON
}

TEST(JsonQuote, PassesValidUtf8Through) {
    const std::string s = "\xc3\xa9t\xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80 \xce\xb8=60\xc2\xb0";
    EXPECT_EQ(json_quote(s), "\"" + s + "\"");
}

TEST(JsonQuote, ReplacesInvalidUtf8) {
    EXPECT_EQ(json_quote("a\xff"
                         "b"),
              R"("a\ufffdb")");                                        // never valid
    EXPECT_EQ(json_quote("\xe2\x82"), R"("\ufffd\ufffd")");            // truncated 3-byte sequence
    EXPECT_EQ(json_quote("\xc0\xaf"), R"("\ufffd\ufffd")");            // overlong '/'
    EXPECT_EQ(json_quote("\xed\xa0\x80"), R"("\ufffd\ufffd\ufffd")");  // UTF-16 surrogate
    EXPECT_EQ(json_quote("\xf4\x90\x80\x80"), R"("\ufffd\ufffd\ufffd\ufffd")");  // > U+10FFFF
    EXPECT_EQ(json_quote("\x80"), R"("\ufffd")");  // lone continuation byte
}

TEST(JsonNumber, RoundTripsExactly) {
    std::vector<double> values = {0.0,     1.0,      -1.0,   0.1,           1.0 / 3.0,
                                  2.0 / 3, 1e-5,     1e-300, 5e-324,        DBL_MIN,
                                  DBL_MAX, -DBL_MAX, 1e21,   123456789.125, 8.0e-4,
                                  9.81,    1149.0,   1e100,  -2.5e-7,       0.30000000000000004};
    std::mt19937_64 gen(12345);
    for (int i = 0; i < 2000; ++i) {
        const double d = std::bit_cast<double>(gen());
        if (std::isfinite(d)) values.push_back(d);
    }
    for (double v : values) {
        const std::string s = json_number(v);
        EXPECT_TRUE(is_json_number(s)) << s;
        const double back = std::strtod(s.c_str(), nullptr);
        EXPECT_EQ(std::bit_cast<std::uint64_t>(back), std::bit_cast<std::uint64_t>(v))
            << v << " -> " << s;
    }
    EXPECT_EQ(json_number(0.1), "0.1");
    EXPECT_EQ(json_number(20.0), "20");
    EXPECT_EQ(json_number(-0.0), "-0");
}

TEST(JsonNumber, NonFiniteIsNull) {
    EXPECT_EQ(json_number(std::numeric_limits<double>::quiet_NaN()), "null");
    EXPECT_EQ(json_number(std::numeric_limits<double>::infinity()), "null");
    EXPECT_EQ(json_number(-std::numeric_limits<double>::infinity()), "null");
}

TEST(JsonWriter, NonFiniteDoublesAreNullAndCounted) {
    JsonWriter w;
    w.begin_array_inline();
    w.value(1.5);
    w.value(std::numeric_limits<double>::quiet_NaN());
    w.value(-std::numeric_limits<double>::infinity());
    w.end_array();
    EXPECT_EQ(w.str(), "[1.5, null, null]");
    EXPECT_EQ(w.nonfinite_count(), 2);
    EXPECT_EQ(w.str().find("nan"), std::string::npos);
    EXPECT_EQ(w.str().find("inf"), std::string::npos);
}

TEST(JsonWriter, OptionalsAreNullWhenEmpty) {
    JsonWriter w;
    w.begin_object_inline();
    w.field("empty_time", std::optional<double>{});
    w.field("rate", std::optional<double>{2.5});
    w.field("count", std::optional<int>{});
    w.end_object();
    EXPECT_EQ(w.str(), R"({"empty_time": null, "rate": 2.5, "count": null})");
    EXPECT_EQ(w.nonfinite_count(), 0);
}

TEST(JsonWriter, ScalarTypes) {
    JsonWriter w;
    w.begin_object_inline();
    w.field("t", true);
    w.field("f", false);
    w.field("i", -42);
    w.field("u64", std::uint64_t{18446744073709551615ull});
    w.field("i64", std::int64_t{-9223372036854775807LL - 1});
    w.field("s", "text");
    w.field("str", std::string("a\"b"));
    w.key("n").null();
    w.end_object();
    EXPECT_EQ(w.str(), R"({"t": true, "f": false, "i": -42, "u64": 18446744073709551615, )"
                       R"("i64": -9223372036854775808, "s": "text", "str": "a\"b", "n": null})");
    EXPECT_TRUE(w.complete());
}

TEST(JsonWriter, NestedLayoutOneKeyPerLineArraysInline) {
    JsonWriter w;
    w.begin_object();
    w.field("status", "complete");
    w.field_array("times", std::vector<double>{0.5, 1.25});
    w.field_array("censored", std::vector<bool>{false, true});
    w.field_array("empty", std::vector<int>{});
    w.key("curve").begin_object();
    w.field_array("in_hopper", std::vector<int>{3, 2, 0});
    w.end_object();
    w.key("events").begin_array();
    w.begin_object_inline().field("kind", "jam").field("time", 1.0).end_object();
    w.begin_object_inline().field("kind", "stop").field("time", 2.0).end_object();
    w.end_array();
    w.key("nothing").begin_object().end_object();
    w.end_object();
    const std::string expected = R"({
  "status": "complete",
  "times": [0.5, 1.25],
  "censored": [false, true],
  "empty": [],
  "curve": {
    "in_hopper": [3, 2, 0]
  },
  "events": [
    {"kind": "jam", "time": 1},
    {"kind": "stop", "time": 2}
  ],
  "nothing": {}
})";
    EXPECT_EQ(w.str(), expected);
    EXPECT_TRUE(w.complete());
}

TEST(JsonWriter, ContainersInsideInlineStayInline) {
    JsonWriter w;
    w.begin_array_inline();
    w.begin_object().field("a", 1).end_object();
    w.begin_array().value(2).value(3).end_array();
    w.end_array();
    EXPECT_EQ(w.str(), R"([{"a": 1}, [2, 3]])");
}

TEST(JsonWriter, EscapesKeys) {
    JsonWriter w;
    w.begin_object_inline().field("a\"b\n", 1).end_object();
    EXPECT_EQ(w.str(), R"({"a\"b\n": 1})");
}

TEST(JsonWriter, MisuseThrows) {
    {
        JsonWriter w;
        w.begin_object();
        EXPECT_THROW(w.value(1), std::logic_error);  // no key
    }
    {
        JsonWriter w;
        w.begin_array();
        EXPECT_THROW(w.key("k"), std::logic_error);  // key in an array
    }
    {
        JsonWriter w;
        w.begin_object();
        EXPECT_THROW(w.end_array(), std::logic_error);  // unbalanced
    }
    {
        JsonWriter w;
        w.begin_object().key("k");
        EXPECT_THROW(w.end_object(), std::logic_error);  // key without value
    }
    {
        JsonWriter w;
        w.value(1);
        EXPECT_THROW(w.value(2), std::logic_error);  // second top-level value
    }
    {
        JsonWriter w;
        EXPECT_THROW(w.end_object(), std::logic_error);
    }
}

TEST(FieldsSummary, CompactOneLineWithoutPerNodeArrays) {
    engine::FieldGrid g;
    g.x0 = -0.1;
    g.y0 = -0.0308;
    g.cell = 0.0154;
    g.nx = 3;
    g.ny = 2;
    engine::FieldMoments m = engine::FieldMoments::zero(g);
    m.windows = {0, 4, 1, 0, 2, 7};
    const int speed = static_cast<int>(engine::Field::speed);
    const int pressure = static_cast<int>(engine::Field::pressure);
    m.mean[speed] = {9.0, 0.5, 0.25, 8.0, 0.75, 0.125};  // nodes without windows do not count
    m.mean[pressure] = {99.0, 3.0, 12.5, 0.0, 1.0, 2.0};
    m.samples = 120;
    m.total_windows = 12;
    m.t_first = 0.001;
    m.t_last = 0.12;
    const FieldsSummary s = summarize_fields(m);
    EXPECT_EQ(s.cells_with_data, 4);
    EXPECT_EQ(s.max_mean_speed, 0.75);
    EXPECT_EQ(s.max_mean_pressure, 12.5);

    JsonWriter w;
    w.begin_object();
    w.field("status", "complete");
    w.key("fields").begin_object_inline();
    write_fields_summary(w, m);
    w.end_object();
    w.end_object();
    EXPECT_EQ(
        w.str(),
        "{\n  \"status\": \"complete\",\n  \"fields\": {\"kernel\": \"cell\", \"cell_m\": "
        "0.0154, \"x0_m\": -0.1, \"y0_m\": -0.0308, \"nx\": 3, \"ny\": 2, \"samples\": 120, "
        "\"total_windows\": 12, \"t_first\": 0.001, \"t_last\": 0.12, \"cells_with_data\": 4, "
        "\"max_mean_speed\": 0.75, \"max_mean_pressure\": 12.5}\n}");

    m.grid.kernel = engine::FieldKernel::gaussian;
    m.grid.kernel_width = 0.0077;
    m.windows.assign(6, 0);
    JsonWriter g2;
    g2.begin_object_inline();
    write_fields_summary(g2, m);
    g2.end_object();
    EXPECT_NE(g2.str().find("\"kernel\": \"gaussian\", \"kernel_width_m\": 0.0077"),
              std::string::npos)
        << g2.str();
    EXPECT_NE(g2.str().find("\"cells_with_data\": 0, \"max_mean_speed\": 0, "
                            "\"max_mean_pressure\": 0"),
              std::string::npos)
        << g2.str();
}

}  // namespace
}  // namespace hopper::cli
