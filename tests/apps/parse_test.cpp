// The command line's own value parsers: --max-memory sizes and --size grids.
#include "parse.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>

TEST(ParseBytes, AcceptsPlainNumbersAndBinaryUnits) {
  const struct {
    const char* text;
    std::uint64_t bytes;
  } cases[] = {{"512", 512},
               {"7B", 7},
               {"1K", 1024},
               {"1KiB", 1024},
               {"512M", std::uint64_t(512) << 20},
               {"512MiB", std::uint64_t(512) << 20},
               {"8G", std::uint64_t(8) << 30},
               {"1.5GiB", std::uint64_t(3) << 29},
               {"0.5K", 512}};
  for (const auto& c : cases) {
    std::uint64_t bytes = 0;
    EXPECT_TRUE(parse_bytes(c.text, bytes)) << c.text;
    EXPECT_EQ(bytes, c.bytes) << c.text;
  }
}

TEST(ParseBytes, RefusesZeroNegativeUnknownUnitsAndOverflow) {
  for (const char* text : {"0", "0G", "-1M", "12X", "1g", "1 M", "M", "", "inf", "nan", "infG",
                           "1e30G", "18446744073709551616"}) {
    std::uint64_t bytes = 42;
    EXPECT_FALSE(parse_bytes(text, bytes)) << text;
    EXPECT_EQ(bytes, 42u) << text << ": a refused size leaves the value alone";
  }
}

TEST(ParseGridSize, AcceptsPositiveWidthByHeight) {
  int w = 0, h = 0;
  EXPECT_TRUE(parse_grid_size("256x256", w, h));
  EXPECT_EQ(w, 256);
  EXPECT_EQ(h, 256);
  EXPECT_TRUE(parse_grid_size("1x3", w, h));
  EXPECT_EQ(w, 1);
  EXPECT_EQ(h, 3);
  EXPECT_TRUE(parse_grid_size("640x48", w, h));
  EXPECT_EQ(w, 640);
  EXPECT_EQ(h, 48);
}

TEST(ParseGridSize, RefusesZeroSignsMissingPartsAndOverflow) {
  for (const char* text :
       {"0x5", "5x0", "-3x4", "3x-4", "+3x4", "3x+4", "3x", "x3", "x", "", "3x4x5", "3X4", "3*4",
        " 3x4", "3x4 ", "3 x4", "99999999999x2", "2x99999999999", "1.5x2"}) {
    int w = 0, h = 0;
    EXPECT_FALSE(parse_grid_size(text, w, h)) << text;
  }
}
