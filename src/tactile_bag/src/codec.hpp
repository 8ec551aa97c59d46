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

/// Memory bounds of decompression (README "Bounded memory"). Nothing read from a file sizes
/// an allocation beyond what these allow.
///
/// Largest expansion of the formats: a zstd block is at most 128 KiB of output
/// (Block_Maximum_Size, RFC 8878 sec. 3.1.1.2.3) and takes at least 4 bytes (3-byte block
/// header + the 1 byte of an RLE block), so a zstd frame yields at most 32768 bytes per
/// input byte; an LZ4 sequence adds at most 255 bytes of match length per input byte
/// (LZ4 block format: each extra length byte adds up to 255), so LZ4 yields < 255 per byte.
inline constexpr uint64_t kZstdMaxExpansion = 32768;
inline constexpr uint64_t kLz4MaxExpansion = 255;
/// Absolute cap of one decompressed unit (an mcap chunk, a sqlite3 message blob): 1 GiB.
/// sqlite stores no blob over 1e9 bytes (SQLITE_MAX_LENGTH), and a rosbag2 mcap chunk
/// holds 768 KiB of records or one message larger than that; nothing in a tactile flight
/// comes near it, and a chunk declaring more is rejected before any allocation.
inline constexpr uint64_t kMaxDecompressedBytes = uint64_t{1} << 30;
/// `expected_size` when the container does not say (sqlite3 message-mode blobs).
inline constexpr uint64_t kUnknownSize = UINT64_MAX;

/// Largest output `format` can produce from `size` compressed bytes (the expansions above).
uint64_t max_expansion(const std::string& format, uint64_t size);

/// Decompress a zstd or lz4 frame into `out` (replaced). `expected_size` is the
/// uncompressed size the container declares (kUnknownSize: none): the frame's own declared
/// content size must equal it, and so must what it decompresses to. Neither declaration
/// sizes an allocation: a declared size above `max_size` or above max_expansion(size) is an
/// error before anything is allocated, and the output buffer grows with what the
/// decompressor actually produces (at most twice that), so a corrupt header costs nothing.
/// `where` prefixes errors (file and byte offset).
void decompress(const std::string& format, const uint8_t* data, size_t size,
                uint64_t expected_size, uint64_t max_size, std::vector<uint8_t>& out,
                const std::string& where);

/// Decompress a whole zstd file (rosbag2 file-mode compression) into `to_path`.
void decompress_zstd_file(const std::string& from_path, const std::string& to_path);

/// True for "zstd" and "lz4".
bool supported(const std::string& format);

}  // namespace tactile_bag::codec
