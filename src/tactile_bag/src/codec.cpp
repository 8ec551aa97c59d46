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
#include <new>

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

uint64_t max_expansion(const std::string& format, uint64_t size) {
  const uint64_t k = format == "lz4" ? kLz4MaxExpansion : kZstdMaxExpansion;
  return size > UINT64_MAX / k ? UINT64_MAX : size * k;
}

namespace {

std::string bytes(uint64_t n) { return std::to_string(n) + " bytes"; }

// Grow `out` to hold at least `need` bytes (doubling, at most `limit`).
void grow(std::vector<uint8_t>& out, size_t used, uint64_t limit) {
  const uint64_t next = std::min<uint64_t>(limit, std::max<uint64_t>(used * 2, 64 * 1024));
  out.resize(static_cast<size_t>(next));
}

}  // namespace

void decompress(const std::string& format, const uint8_t* data, size_t size,
                uint64_t expected_size, uint64_t max_size, std::vector<uint8_t>& out,
                const std::string& where) {
  if (!supported(format)) {
    throw BagError(where + ": unknown compression '" + format + "' (supported: zstd, lz4)");
  }
  const bool known = expected_size != kUnknownSize;
  uint64_t declared = expected_size;  // what the container (or else the frame) declares
  if (format == "zstd") {
    const unsigned long long c = ZSTD_getFrameContentSize(data, size);
    if (c == ZSTD_CONTENTSIZE_ERROR) throw BagError(where + ": not a zstd frame (bad frame header)");
    if (c != ZSTD_CONTENTSIZE_UNKNOWN) {
      if (known && c != expected_size) {
        throw BagError(where + ": zstd frame header declares a content size of " + bytes(c) +
                       " but the container declares " + bytes(expected_size) + " (file corrupt)");
      }
      declared = c;
    }
  }
  // The bound of the output: the declared size, else the caps; a declaration over a cap is
  // refused before anything is allocated.
  const uint64_t expansion = max_expansion(format, size);
  if (declared != kUnknownSize) {
    if (declared > max_size) {
      throw BagError(where + ": declared uncompressed size of " + bytes(declared) + " exceeds the cap of " +
                     bytes(max_size) + " (file corrupt?)");
    }
    if (declared > expansion) {
      throw BagError(where + ": declared uncompressed size of " + bytes(declared) + " cannot come from " +
                     bytes(size) + " of " + format + " data (at most " + bytes(expansion) + "; file corrupt)");
    }
  }
  const uint64_t limit = declared != kUnknownSize ? declared : std::min(max_size, expansion);
  // One byte over the limit is room enough to see the data run past it.
  const uint64_t room = limit + 1;
  size_t used = 0;
  try {
    out.clear();
    out.resize(static_cast<size_t>(std::min<uint64_t>(room, std::max<uint64_t>(uint64_t{4} * size, 64 * 1024))));
    if (format == "zstd" && declared != kUnknownSize && declared < out.size()) {
      // Declared size within 4x the compressed bytes (the usual case, one buffer already
      // big enough): decompress in one call, straight into it (no window buffer, no copy).
      const size_t n = ZSTD_decompress(out.data(), out.size(), data, size);
      if (ZSTD_isError(n)) throw BagError(where + ": zstd decompression failed: " + ZSTD_getErrorName(n));
      used = n;
      if (used > limit) {
        throw BagError(where + ": zstd data decompresses to more than the declared " + bytes(limit) +
                       " (file corrupt)");
      }
    } else if (format == "zstd") {
      std::unique_ptr<ZSTD_DCtx, size_t (*)(ZSTD_DCtx*)> ctx(ZSTD_createDCtx(), ZSTD_freeDCtx);
      if (!ctx) throw BagError(where + ": zstd: cannot create a decompression context");
      ZSTD_inBuffer in{data, size, 0};
      size_t rc = 1;
      while (in.pos < in.size || (rc != 0 && used == out.size())) {
        if (used == out.size()) {
          if (out.size() >= room) break;
          grow(out, used, room);
        }
        ZSTD_outBuffer o{out.data(), out.size(), used};
        const size_t before_in = in.pos;
        rc = ZSTD_decompressStream(ctx.get(), &o, &in);
        if (ZSTD_isError(rc)) throw BagError(where + ": zstd decompression failed: " + ZSTD_getErrorName(rc));
        const bool progress = o.pos != used || in.pos != before_in;
        used = o.pos;
        if (!progress && used < out.size()) break;
      }
      if (used > limit) {
        throw BagError(where + ": zstd data decompresses to more than the " +
                       (declared != kUnknownSize ? "declared " : "cap of ") + bytes(limit) + " (file corrupt)");
      }
      if (rc != 0) throw BagError(where + ": zstd data is truncated (frame not complete)");
    } else {
      LZ4F_dctx* raw = nullptr;
      if (LZ4F_isError(LZ4F_createDecompressionContext(&raw, LZ4F_VERSION))) {
        throw BagError(where + ": lz4: cannot create a decompression context");
      }
      std::unique_ptr<LZ4F_dctx, size_t (*)(LZ4F_dctx*)> ctx(raw, LZ4F_freeDecompressionContext);
      size_t in_pos = 0, rc = 1;
      // Until the frame ends: input left, or output pending in the context (buffer full).
      while (rc != 0 && (in_pos < size || used == out.size())) {
        if (used == out.size()) {
          if (out.size() >= room) break;
          grow(out, used, room);
        }
        size_t dst = out.size() - used, src = size - in_pos;
        rc = LZ4F_decompress(ctx.get(), out.data() + used, &dst, data + in_pos, &src, nullptr);
        if (LZ4F_isError(rc)) throw BagError(where + ": lz4 decompression failed: " + LZ4F_getErrorName(rc));
        in_pos += src;
        used += dst;
        if (src == 0 && dst == 0) break;
      }
      if (used > limit) {
        throw BagError(where + ": lz4 data decompresses to more than the " +
                       (declared != kUnknownSize ? "declared " : "cap of ") + bytes(limit) + " (file corrupt)");
      }
      if (rc != 0) throw BagError(where + ": lz4 data is truncated (frame not complete)");
    }
  } catch (const std::bad_alloc&) {
    out.clear();
    out.shrink_to_fit();
    throw BagError(where + ": out of memory decompressing " + format + " data (" + bytes(used) +
                   " produced so far, bound " + bytes(limit) + ")");
  }
  if (known && used != expected_size) {
    throw BagError(where + ": " + format + " data decompresses to " + bytes(used) + ", but the container declares " +
                   bytes(expected_size) + " (file corrupt)");
  }
  out.resize(used);
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
