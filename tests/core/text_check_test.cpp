#include "overtake/core/text_check.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace overtake::core {
namespace {

std::string nested(int levels, char open = '[', char close = ']') {
  return std::string(static_cast<std::size_t>(levels), open) +
         std::string(static_cast<std::size_t>(levels), close);
}

TEST(JsonDepth, CountsArraysAndObjectsAndNotBracketsInStrings) {
  EXPECT_FALSE(json_too_deep_at(nested(64)).has_value());
  ASSERT_TRUE(json_too_deep_at(nested(65)).has_value());
  EXPECT_EQ(*json_too_deep_at(nested(65)), 64U);
  EXPECT_EQ(json_too_deep_at(R"({"a":{"b":[1]}})", 2), std::optional<std::size_t>(10));
  EXPECT_FALSE(json_too_deep_at(R"({"a":{"b":[1]}})", 3).has_value());
  // Brackets inside strings, escaped quotes included, are text.
  EXPECT_FALSE(json_too_deep_at(R"(["[[[[", "\"[[[[", "\\"])", 1).has_value());
  EXPECT_TRUE(json_too_deep_at(R"(["\\", [[]]])", 2).has_value());
  // Depth goes back down: many shallow siblings are fine.
  std::string wide = "[";
  for (int i = 0; i < 1000; ++i) wide += nested(3) + ",";
  wide += "1]";
  EXPECT_FALSE(json_too_deep_at(wide, 4).has_value());
}

TEST(JsonDepth, RequireNamesTheSourceAndTheByte) {
  try {
    require_json_depth("{\"x\": " + nested(100000) + "}", "scenario.json");
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "scenario.json: JSON nested deeper than 64 levels (at byte 69)");
  }
  EXPECT_NO_THROW(require_json_depth(R"({"a": [1, 2, {"b": null}]})", "x"));
}

TEST(Utf8, ValidTextIsKept) {
  for (const std::string& s : {std::string(), std::string("plain"), std::string("caf\xC3\xA9"),
                               std::string("\xE2\x82\xAC 5"), std::string("\xF0\x9F\x9A\x97"),
                               std::string("\xEF\xBF\xBD")}) {
    EXPECT_TRUE(is_valid_utf8(s)) << s;
    EXPECT_EQ(valid_utf8(s), s);
  }
}

TEST(Utf8, InvalidBytesAreReplacedOneByOne) {
  const std::string fffd = "\xEF\xBF\xBD";
  // Latin-1 "é" alone, and "é" (2 bytes) cut after its first byte at the end.
  EXPECT_FALSE(is_valid_utf8("caf\xE9"));
  EXPECT_EQ(valid_utf8("caf\xE9"), "caf" + fffd);
  EXPECT_EQ(valid_utf8("ab\xC3"), "ab" + fffd);
  // Overlong "/" (C0 AF), a surrogate (ED A0 80), past U+10FFFF (F4 90 80 80), a lone
  // continuation byte: each byte that starts no valid sequence becomes one U+FFFD.
  EXPECT_EQ(valid_utf8("\xC0\xAF"), fffd + fffd);
  EXPECT_EQ(valid_utf8("\xED\xA0\x80"), fffd + fffd + fffd);
  EXPECT_EQ(valid_utf8("\xF4\x90\x80\x80"), fffd + fffd + fffd + fffd);
  EXPECT_EQ(valid_utf8("a\x80z"), "a" + fffd + "z");
  // A valid sequence after an invalid byte is kept.
  EXPECT_EQ(valid_utf8("\xFF\xC3\xA9"), fffd + "\xC3\xA9");
  EXPECT_TRUE(is_valid_utf8(valid_utf8("\xE9\xE9\xC3")));
}

TEST(Utf8, AReasonCutMidCharacterIsMadeValid) {
  // 600 "é" cut at 1,023 bytes, as snprintf into a 1,024-byte buffer does.
  std::string reason;
  for (int i = 0; i < 600; ++i) reason += "\xC3\xA9";
  reason.resize(1023);
  EXPECT_FALSE(is_valid_utf8(reason));
  const std::string fixed = valid_utf8(reason);
  EXPECT_TRUE(is_valid_utf8(fixed));
  EXPECT_EQ(fixed.substr(0, 1022), reason.substr(0, 1022));
  EXPECT_EQ(fixed.substr(1022), "\xEF\xBF\xBD");
}

}  // namespace
}  // namespace overtake::core
