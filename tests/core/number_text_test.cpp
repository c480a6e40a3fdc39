// Numbers in text (voxd/encode/number_text.h): the one parser every flag,
// query, header and environment variable goes through, and the printer whose
// text reads back exactly.
#include <cstdint>
#include <limits>

#include <gtest/gtest.h>

#include "voxd/encode/number_text.h"

namespace voxd {
namespace {

TEST(ParseNumber, ReadsTheWholeTextAsDecimal) {
  EXPECT_EQ(parse_number<int>("1024"), 1024);
  EXPECT_EQ(parse_number<long long>("-17"), -17);
  EXPECT_EQ(parse_number<std::uint64_t>("18446744073709551615"), std::numeric_limits<std::uint64_t>::max());
  EXPECT_EQ(parse_number<double>("0.015625"), 0.015625);
  EXPECT_EQ(parse_number<double>("-2.5e-3"), -2.5e-3);
  EXPECT_EQ(parse_number<int>("ff", 16), 255);
}

TEST(ParseNumber, RefusesAnythingButOneNumber) {
  for (const char* text : {"", " 5", "5 ", "+5", "5x", "0x10", "1e3", "--1", "1.5"})
    EXPECT_FALSE(parse_number<long long>(text)) << "'" << text << "'";
  for (const char* text : {"", " 1", "1.5.2", "1,5", "0x1p3", "e5"})
    EXPECT_FALSE(parse_number<double>(text)) << "'" << text << "'";
}

TEST(ParseNumber, NeverWrapsANegativeOrOversizedValue) {
  EXPECT_FALSE(parse_number<std::uint64_t>("-1"));  // std::stoull would give 2^64 - 1
  EXPECT_FALSE(parse_number<std::uint64_t>("18446744073709551616"));
  EXPECT_FALSE(parse_number<int>("2147483648"));
  EXPECT_FALSE(parse_number<double>("1e400"));
}

TEST(NumberText, ReadsBackAsTheSameDouble) {
  for (double x : {0.1, 1.0 / 3.0, -1e-300, 6.02214076e23, 0.015625})
    EXPECT_EQ(parse_number<double>(number_text(x)), x) << number_text(x);
  EXPECT_EQ(number_text(0.5), "0.5");
  EXPECT_EQ(number_text(3), "3");
}

}  // namespace
}  // namespace voxd
