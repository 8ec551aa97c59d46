// Compression (zstd, lz4 frame) and CRC-32 helpers of the bag storages, over the Debian
// libraries libzstd, liblz4 and zlib. Errors are BagError naming `where` and the reason.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace tactile_bag::codec {

/// CRC-32 (ISO-HDLC, as zlib and the MCAP specification), continuing from `crc`.
uint32_t crc32(uint32_t crc, const uint8_t* data, size_t size);

/// Compress `data` with "zstd" or "lz4" (LZ4 frame format) into `out` (replaced).
void compress(const std::string& format, const uint8_t* data, size_t size,
              std::vector<uint8_t>& out, int level = 1);

/// Decompress a zstd or lz4 frame. `expected_size` (0: unknown) is the uncompressed size
/// the container declares; a different size is an error. `where` prefixes errors.
void decompress(const std::string& format, const uint8_t* data, size_t size,
                size_t expected_size, std::vector<uint8_t>& out, const std::string& where);

/// Decompress a whole zstd file (rosbag2 file-mode compression) into `to_path`.
void decompress_zstd_file(const std::string& from_path, const std::string& to_path);

/// True for "zstd" and "lz4".
bool supported(const std::string& format);

}  // namespace tactile_bag::codec
