// zstd / lz4 / CRC-32 over the Debian libraries (libzstd, liblz4, zlib).
#include "codec.hpp"

#include <lz4frame.h>
#include <libdeflate.h>
#include <zstd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <memory>

#include "tactile_bag/bag.hpp"

namespace tactile_bag::codec {

uint32_t crc32(uint32_t crc, const uint8_t* data, size_t size) {
  // libdeflate's CRC-32 (the zlib/mcap polynomial) uses PCLMULQDQ/AVX where the CPU
  // has them, picked at run time: ~10x zlib 1.2's table-driven crc32 on this machine,
  // and the chunk CRCs are the recorder's largest per-byte cost.
  return libdeflate_crc32(crc, data, size);
}

bool supported(const std::string& format) { return format == "zstd" || format == "lz4"; }

void compress(const std::string& format, const uint8_t* data, size_t size,
              std::vector<uint8_t>& out, int level) {
  if (format == "zstd") {
    out.resize(ZSTD_compressBound(size));
    const size_t n = ZSTD_compress(out.data(), out.size(), data, size, level);
    if (ZSTD_isError(n)) throw BagError(std::string("zstd compression failed: ") + ZSTD_getErrorName(n));
    out.resize(n);
  } else if (format == "lz4") {
    LZ4F_preferences_t prefs{};
    prefs.frameInfo.contentSize = size;
    prefs.compressionLevel = level;
    out.resize(LZ4F_compressFrameBound(size, &prefs));
    const size_t n = LZ4F_compressFrame(out.data(), out.size(), data, size, &prefs);
    if (LZ4F_isError(n)) throw BagError(std::string("lz4 compression failed: ") + LZ4F_getErrorName(n));
    out.resize(n);
  } else {
    throw BagError("unknown compression '" + format + "' (supported: zstd, lz4)");
  }
}

void decompress(const std::string& format, const uint8_t* data, size_t size,
                size_t expected_size, std::vector<uint8_t>& out, const std::string& where) {
  if (format == "zstd") {
    // Allocate only what the frame itself declares (never trust a container's size alone:
    // a corrupt chunk could declare gigabytes).
    const unsigned long long c = ZSTD_getFrameContentSize(data, size);
    if (c == ZSTD_CONTENTSIZE_ERROR) throw BagError(where + ": not a zstd frame");
    if (c != ZSTD_CONTENTSIZE_UNKNOWN) {
      if (expected_size != 0 && c != expected_size) {
        throw BagError(where + ": zstd frame declares " + std::to_string(c) + " bytes, expected " +
                       std::to_string(expected_size));
      }
      if (c > (1ULL << 34)) throw BagError(where + ": zstd frame declares an implausible " + std::to_string(c) + " bytes");
      out.resize(static_cast<size_t>(c));
      const size_t n = ZSTD_decompress(out.data(), out.size(), data, size);
      if (ZSTD_isError(n)) {
        throw BagError(where + ": zstd decompression failed: " + ZSTD_getErrorName(n));
      }
      if (n != c) {
        throw BagError(where + ": zstd data decompresses to " + std::to_string(n) +
                       " bytes, expected " + std::to_string(c));
      }
      return;
    }
    // Size not in the frame (streamed): decompress in pieces, bounded by expected_size.
    std::unique_ptr<ZSTD_DCtx, size_t (*)(ZSTD_DCtx*)> ctx(ZSTD_createDCtx(), ZSTD_freeDCtx);
    out.clear();
    ZSTD_inBuffer in{data, size, 0};
    std::vector<uint8_t> buf(ZSTD_DStreamOutSize());
    size_t rc = 1;
    while (in.pos < in.size) {
      ZSTD_outBuffer o{buf.data(), buf.size(), 0};
      rc = ZSTD_decompressStream(ctx.get(), &o, &in);
      if (ZSTD_isError(rc)) throw BagError(where + ": zstd decompression failed: " + ZSTD_getErrorName(rc));
      out.insert(out.end(), buf.data(), buf.data() + o.pos);
      if (expected_size != 0 && out.size() > expected_size) {
        throw BagError(where + ": zstd data decompresses to more than the declared " +
                       std::to_string(expected_size) + " bytes");
      }
      if (o.pos == 0 && rc != 0 && in.pos == in.size) break;
    }
    if (rc != 0) throw BagError(where + ": zstd data is truncated (frame not complete)");
    if (expected_size != 0 && out.size() != expected_size) {
      throw BagError(where + ": zstd data decompresses to " + std::to_string(out.size()) +
                     " bytes, expected " + std::to_string(expected_size));
    }
  } else if (format == "lz4") {
    LZ4F_dctx* raw = nullptr;
    if (LZ4F_isError(LZ4F_createDecompressionContext(&raw, LZ4F_VERSION))) {
      throw BagError(where + ": lz4: cannot create a decompression context");
    }
    std::unique_ptr<LZ4F_dctx, size_t (*)(LZ4F_dctx*)> ctx(raw, LZ4F_freeDecompressionContext);
    // Grow from a size bounded by the input (doubling), never straight to a declared size.
    out.resize(std::min<size_t>(expected_size > 0 ? expected_size : SIZE_MAX, size * 4 + 64));
    size_t in_pos = 0, out_pos = 0, rc = 1;
    while (in_pos < size && rc != 0) {
      if (out_pos == out.size()) {
        if (expected_size > 0 && out.size() >= expected_size) {
          throw BagError(where + ": lz4 data decompresses to more than the declared " +
                         std::to_string(expected_size) + " bytes");
        }
        out.resize(expected_size > 0 ? std::min(out.size() * 2, expected_size) : out.size() * 2);
      }
      size_t dst = out.size() - out_pos, src = size - in_pos;
      rc = LZ4F_decompress(ctx.get(), out.data() + out_pos, &dst, data + in_pos, &src, nullptr);
      if (LZ4F_isError(rc)) throw BagError(where + ": lz4 decompression failed: " + LZ4F_getErrorName(rc));
      in_pos += src;
      out_pos += dst;
      if (src == 0 && dst == 0) break;
    }
    if (rc != 0) throw BagError(where + ": lz4 data is truncated (frame not complete)");
    if (expected_size > 0 && out_pos != expected_size) {
      throw BagError(where + ": lz4 data decompresses to " + std::to_string(out_pos) +
                     " bytes, expected " + std::to_string(expected_size));
    }
    out.resize(out_pos);
  } else {
    throw BagError(where + ": unknown compression '" + format + "' (supported: zstd, lz4)");
  }
}

void decompress_zstd_file(const std::string& from_path, const std::string& to_path) {
  std::ifstream in(from_path, std::ios::binary);
  if (!in) throw BagError(from_path + ": cannot open compressed file");
  std::ofstream out(to_path, std::ios::binary | std::ios::trunc);
  if (!out) throw BagError(to_path + ": cannot create the decompressed copy");
  std::unique_ptr<ZSTD_DCtx, size_t (*)(ZSTD_DCtx*)> ctx(ZSTD_createDCtx(), ZSTD_freeDCtx);
  std::vector<char> ibuf(ZSTD_DStreamInSize()), obuf(ZSTD_DStreamOutSize());
  size_t rc = 0;
  uint64_t offset = 0;
  bool any = false;
  while (in) {
    in.read(ibuf.data(), static_cast<std::streamsize>(ibuf.size()));
    const size_t got = static_cast<size_t>(in.gcount());
    if (got == 0) break;
    any = true;
    ZSTD_inBuffer ib{ibuf.data(), got, 0};
    while (ib.pos < ib.size) {
      ZSTD_outBuffer ob{obuf.data(), obuf.size(), 0};
      rc = ZSTD_decompressStream(ctx.get(), &ob, &ib);
      if (ZSTD_isError(rc)) {
        throw BagError(from_path + ": byte " + std::to_string(offset + ib.pos) +
                       ": zstd decompression failed: " + ZSTD_getErrorName(rc));
      }
      out.write(obuf.data(), static_cast<std::streamsize>(ob.pos));
    }
    offset += got;
  }
  if (!any) throw BagError(from_path + ": compressed file is empty (0 bytes)");
  if (rc != 0) throw BagError(from_path + ": zstd file is truncated (frame not complete after " + std::to_string(offset) + " bytes)");
  out.flush();
  if (!out) throw BagError(to_path + ": cannot write the decompressed copy");
}

}  // namespace tactile_bag::codec
