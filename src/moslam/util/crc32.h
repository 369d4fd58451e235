// CRC-32 (ISO-HDLC: the polynomial 0x04C11DB7 reflected, zlib's and PNG's crc32), for integrity
// checks of files whose container does not verify its own data (net/model_file.cc).
#pragma once

#include <cstddef>
#include <cstdint>

namespace moslam {

// The CRC of `size` bytes at `data` continued from `crc` (0 to start): Crc32(b, n, Crc32(a, m))
// is the CRC of a followed by b. Crc32("123456789", 9) == 0xCBF43926.
uint32_t Crc32(const void* data, size_t size, uint32_t crc = 0);

}  // namespace moslam
