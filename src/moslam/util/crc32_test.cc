#include "moslam/util/crc32.h"

#include <string>

#include <gtest/gtest.h>

namespace moslam {
namespace {

TEST(Crc32, MatchesTheStandardCheckValue) {
  // The check value of CRC-32/ISO-HDLC (zlib's crc32) for "123456789".
  EXPECT_EQ(Crc32("123456789", 9), 0xCBF43926u);
  EXPECT_EQ(Crc32("", 0), 0u);
}

TEST(Crc32, ContinuesAcrossPieces) {
  const std::string text = "moslam model file payload";
  const uint32_t whole = Crc32(text.data(), text.size());
  EXPECT_EQ(Crc32(text.data() + 6, text.size() - 6, Crc32(text.data(), 6)), whole);
  std::string flipped = text;
  flipped[3] ^= 0x10;
  EXPECT_NE(Crc32(flipped.data(), flipped.size()), whole);
}

}  // namespace
}  // namespace moslam
