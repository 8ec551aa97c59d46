// CDR (XCDR1, little endian) writer and reader used by the generated serialization code,
// plus the public serialize() / deserialize() entry points.
//
// Rules (OMG DDS-XTypes 1.3, 7.4.1 "XCDR version 1"; what rosbag2 stores):
//   - 4-byte encapsulation header 00 01 00 00 (CDR_LE), then the payload;
//   - every primitive is aligned to its own size (max 8), counted from the start of
//     the payload, i.e. after the encapsulation header; padding bytes are zero;
//   - bool is one byte (0 / 1);
//   - string: uint32 length including the terminating NUL, the bytes, the NUL;
//   - sequence (T[] and T[<=N]): uint32 element count, then the elements;
//   - fixed array (T[N]): the N elements, no count.
#ifndef TACTILE_MSGS__CDR__CDR_STREAM_HPP_
#define TACTILE_MSGS__CDR__CDR_STREAM_HPP_

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#if defined(__BYTE_ORDER__) && defined(__ORDER_LITTLE_ENDIAN__)
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
  "tactile_msgs CDR serialization assumes a little-endian host");
#endif

namespace tactile_msgs
{
namespace cdr
{

/// Size of the encapsulation header in front of every serialized message.
constexpr std::size_t kEncapsulationSize = 4;

/// Raised by deserialize() on truncated or malformed input.
class DecodeError : public std::runtime_error
{
public:
  DecodeError(std::string type_name, std::string field, std::size_t offset, const std::string & reason)
  : std::runtime_error(type_name + ": field '" + (field.empty() ? std::string("<message>") : field) +
      "' at byte offset " + std::to_string(offset) + ": " + reason),
    type_name_(std::move(type_name)), field_(std::move(field)), offset_(offset) {}

  /// Type being decoded, e.g. "tactile_msgs/msg/WhiskerPressure".
  const std::string & type_name() const noexcept {return type_name_;}
  /// Dotted field path with sequence indices, e.g. "header.frame_id" or "poses[3].position.x".
  const std::string & field() const noexcept {return field_;}
  /// Byte offset in the input buffer (encapsulation header included) where decoding failed.
  std::size_t offset() const noexcept {return offset_;}

private:
  std::string type_name_;
  std::string field_;
  std::size_t offset_;
};

/// Specialised by the generated code for every message type:
///   static constexpr const char* type_name;           // "pkg/msg/Type"
///   static constexpr std::size_t min_serialized_size; // lower bound of the CDR size
///   static const std::string& definition();           // ros2msg definition text
///   static void write(CdrWriter&, const T&);
///   static void read(CdrReader&, T&);
template<class T>
struct MessageTraits;

/// Appends CDR data to a byte buffer that starts with the encapsulation header.
///
/// The buffer is kept at its capacity and written through a position (`pos_`): a
/// resize per field (zero-filling the new bytes out of line) was the largest cost of
/// serializing a 700-byte Odometry. Padding bytes are written as zeros explicitly, so
/// a reused buffer's old contents never leak into a message.
class CdrWriter
{
public:
  CdrWriter() {buf_.resize(64); put_header();}
  /// Writes into `reuse`'s storage (its contents are discarded, its capacity kept):
  /// a recorder serializing every message of a run allocates once per topic, not per message.
  explicit CdrWriter(std::vector<uint8_t> && reuse)
  : buf_(std::move(reuse))
  {
    buf_.resize(std::max<std::size_t>(buf_.capacity(), 64));
    put_header();
  }

  void align(std::size_t n)
  {
    const std::size_t pos = pos_ - kEncapsulationSize;
    const std::size_t pad = (n - pos % n) % n;
    if (pad != 0) {std::memset(grow(pad), 0, pad);}
  }

  template<class T>
  void write(T v)
  {
    static_assert(std::is_arithmetic<T>::value, "CdrWriter::write takes primitives");
    if constexpr (std::is_same<T, bool>::value) {
      *grow(1) = v ? 1 : 0;
    } else {
      align(sizeof(T));
      std::memcpy(grow(sizeof(T)), &v, sizeof(T));
    }
  }

  /// string or string<=bound (bound 0 = unbounded).
  void write_string(const std::string & s, std::size_t bound)
  {
    if (bound != 0 && s.size() > bound) {
      throw std::length_error("tactile_msgs::cdr: string of " + std::to_string(s.size()) +
              " characters exceeds its bound " + std::to_string(bound));
    }
    write_u32_count(s.size() + 1);
    uint8_t * p = grow(s.size() + 1);
    if (!s.empty()) {std::memcpy(p, s.data(), s.size());}
    p[s.size()] = 0;
  }

  /// Element count of a sequence (bound 0 = unbounded).
  void write_count(std::size_t n, std::size_t bound)
  {
    if (bound != 0 && n > bound) {
      throw std::length_error("tactile_msgs::cdr: sequence of " + std::to_string(n) +
              " elements exceeds its bound " + std::to_string(bound));
    }
    write_u32_count(n);
  }

  /// Fixed array of primitives.
  template<class T>
  void write_array(const T * p, std::size_t n)
  {
    static_assert(std::is_arithmetic<T>::value, "write_array takes primitives");
    if constexpr (std::is_same<T, bool>::value) {
      uint8_t * q = grow(n);
      for (std::size_t i = 0; i < n; ++i) {q[i] = p[i] ? 1 : 0;}
    } else {
      if (n == 0) {return;}
      align(sizeof(T));
      std::memcpy(grow(n * sizeof(T)), p, n * sizeof(T));
    }
  }

  /// Sequence of primitives (std::vector or rosidl's BoundedVector).
  template<class V>
  void write_sequence(const V & v, std::size_t bound)
  {
    using T = typename V::value_type;
    write_count(v.size(), bound);
    if constexpr (std::is_same<T, bool>::value) {
      uint8_t * q = grow(v.size());
      std::size_t i = 0;
      for (bool b : v) {q[i++] = b ? 1 : 0;}
    } else {
      write_array(v.data(), v.size());
    }
  }

  /// The serialized bytes (encapsulation header included).
  std::vector<uint8_t> take() noexcept
  {
    buf_.resize(pos_);
    pos_ = 0;
    return std::move(buf_);
  }

private:
  void put_header()
  {
    static constexpr uint8_t kHeader[kEncapsulationSize] = {0x00, 0x01, 0x00, 0x00};
    std::memcpy(buf_.data(), kHeader, kEncapsulationSize);
    pos_ = kEncapsulationSize;
  }

  /// `n` more bytes at the write position (contents unspecified until written).
  uint8_t * grow(std::size_t n)
  {
    if (pos_ + n > buf_.size()) {buf_.resize(std::max(2 * buf_.size(), pos_ + n));}
    uint8_t * p = buf_.data() + pos_;
    pos_ += n;
    return p;
  }

  void write_u32_count(std::size_t n)
  {
    if (n > 0xFFFFFFFFu) {
      throw std::length_error("tactile_msgs::cdr: length does not fit in uint32");
    }
    write(static_cast<uint32_t>(n));
  }

  std::vector<uint8_t> buf_;
  std::size_t pos_ = 0;
};

/// Reads CDR data; every failure throws DecodeError with the current field path.
class CdrReader
{
public:
  /// `data` points at the encapsulation header; `type_name` is used in error messages.
  CdrReader(const uint8_t * data, std::size_t size, const char * type_name)
  : data_(data), size_(size), type_name_(type_name)
  {
    if (data_ == nullptr && size_ != 0) {fail("null data pointer");}
    if (size_ < kEncapsulationSize) {
      fail("input of " + std::to_string(size_) + " bytes is shorter than the 4-byte encapsulation header");
    }
    if (data_[0] != 0x00 || data_[1] != 0x01) {
      fail("unsupported encapsulation " + hex2(data_[0], data_[1]) +
        " (only CDR_LE 00 01 is supported)");
    }
    pos_ = kEncapsulationSize;
  }

  std::size_t position() const noexcept {return pos_;}
  std::size_t remaining() const noexcept {return size_ - pos_;}

  void align(std::size_t n)
  {
    const std::size_t rel = pos_ - kEncapsulationSize;
    const std::size_t pad = (n - rel % n) % n;
    if (pad > remaining()) {fail("truncated input (alignment padding past the end)");}
    pos_ += pad;
  }

  template<class T>
  void read(T & v)
  {
    static_assert(std::is_arithmetic<T>::value, "CdrReader::read takes primitives");
    if constexpr (std::is_same<T, bool>::value) {
      need(1, "bool");
      v = data_[pos_++] != 0;
    } else {
      align(sizeof(T));
      need(sizeof(T), "primitive");
      std::memcpy(&v, data_ + pos_, sizeof(T));
      pos_ += sizeof(T);
    }
  }

  void read_string(std::string & s, std::size_t bound)
  {
    uint32_t len = 0;
    read(len);
    const std::size_t at = pos_ - sizeof(uint32_t);  // errors point at the length field
    if (len > remaining()) {
      fail_at(at, "string length " + std::to_string(len) + " exceeds the remaining " +
        std::to_string(remaining()) + " bytes");
    }
    if (len == 0) {  // tolerated: some writers encode "" as length 0
      s.clear();
      return;
    }
    if (data_[pos_ + len - 1] != 0) {fail_at(at, "string is missing its NUL terminator");}
    if (bound != 0 && len - 1 > bound) {
      fail_at(at, "string of " + std::to_string(len - 1) + " characters exceeds its bound " +
        std::to_string(bound));
    }
    s.assign(reinterpret_cast<const char *>(data_ + pos_), len - 1);
    pos_ += len;
  }

  /// Reads a sequence count and checks it against the bytes left (each element needs
  /// at least `min_element_size` bytes) and the bound (0 = unbounded), so a corrupt
  /// count never causes a huge allocation.
  std::size_t read_count(std::size_t min_element_size, std::size_t bound)
  {
    uint32_t n = 0;
    read(n);
    const std::size_t at = pos_ - sizeof(uint32_t);  // errors point at the count field
    if (bound != 0 && n > bound) {
      fail_at(at, "sequence count " + std::to_string(n) + " exceeds its bound " +
        std::to_string(bound));
    }
    const std::size_t per = min_element_size == 0 ? 1 : min_element_size;
    if (n > remaining() / per) {
      fail_at(at, "sequence count " + std::to_string(n) + " larger than the remaining " +
        std::to_string(remaining()) + " bytes allow");
    }
    return n;
  }

  template<class T>
  void read_array(T * p, std::size_t n)
  {
    static_assert(std::is_arithmetic<T>::value, "read_array takes primitives");
    if constexpr (std::is_same<T, bool>::value) {
      need(n, "bool array");
      for (std::size_t i = 0; i < n; ++i) {p[i] = data_[pos_ + i] != 0;}
      pos_ += n;
    } else {
      if (n == 0) {return;}
      align(sizeof(T));
      if (n > remaining() / sizeof(T)) {fail("truncated input (array past the end)");}
      std::memcpy(p, data_ + pos_, n * sizeof(T));
      pos_ += n * sizeof(T);
    }
  }

  template<class V>
  void read_sequence(V & v, std::size_t bound)
  {
    using T = typename V::value_type;
    const std::size_t n = read_count(sizeof(T), bound);
    v.resize(n);
    if constexpr (std::is_same<T, bool>::value) {
      need(n, "bool sequence");
      for (std::size_t i = 0; i < n; ++i) {v[i] = data_[pos_ + i] != 0;}
      pos_ += n;
    } else {
      read_array(v.data(), n);
    }
  }

  // Field path bookkeeping for error messages (called by the generated code).
  void enter(const char * field) {path_.push_back(Segment{field, 0, false});}
  void leave() {path_.pop_back();}
  void index(std::size_t i)
  {
    path_.back().index = i;
    path_.back().indexed = true;
  }

  std::string field_path() const
  {
    std::string out;
    for (const auto & s : path_) {
      if (!out.empty()) {out += '.';}
      out += s.name;
      if (s.indexed) {out += '[' + std::to_string(s.index) + ']';}
    }
    return out;
  }

  [[noreturn]] void fail(const std::string & reason) const {fail_at(pos_, reason);}

  [[noreturn]] void fail_at(std::size_t offset, const std::string & reason) const
  {
    throw DecodeError(type_name_, field_path(), offset, reason);
  }

private:
  struct Segment
  {
    const char * name;
    std::size_t index;
    bool indexed;
  };

  void need(std::size_t n, const char * what) const
  {
    if (n > remaining()) {
      fail(std::string("truncated input (") + what + " needs " + std::to_string(n) +
        " bytes, " + std::to_string(remaining()) + " left)");
    }
  }

  static std::string hex2(uint8_t a, uint8_t b)
  {
    static const char * digits = "0123456789abcdef";
    std::string s = "00 00";
    s[0] = digits[a >> 4]; s[1] = digits[a & 15]; s[3] = digits[b >> 4]; s[4] = digits[b & 15];
    return s;
  }

  const uint8_t * data_;
  std::size_t size_;
  std::size_t pos_ = 0;
  const char * type_name_;
  std::vector<Segment> path_;
};

/// Serializes `msg` as rosbag2 stores it: encapsulation header 00 01 00 00, then XCDR1 LE.
template<class T>
std::vector<uint8_t> serialize(const T & msg)
{
  CdrWriter w;
  MessageTraits<T>::write(w, msg);
  return w.take();
}

/// serialize(), written into `out` (replaced; its capacity is reused).
template<class T>
void serialize_into(const T & msg, std::vector<uint8_t> & out)
{
  CdrWriter w(std::move(out));
  MessageTraits<T>::write(w, msg);
  out = w.take();
}

/// Decodes `size` bytes at `data` (starting with the encapsulation header) into `out`.
/// Trailing bytes after the message (padding some writers add) are ignored.
/// Throws DecodeError naming the type, the field and the byte offset on bad input.
template<class T>
void deserialize(const uint8_t * data, std::size_t size, T & out)
{
  CdrReader r(data, size, MessageTraits<T>::type_name);
  MessageTraits<T>::read(r, out);
}

/// Convenience overloads.
template<class T>
void deserialize(const std::vector<uint8_t> & data, T & out)
{
  deserialize(data.data(), data.size(), out);
}

template<class T>
T deserialize_as(const uint8_t * data, std::size_t size)
{
  T out{};
  deserialize(data, size, out);
  return out;
}

}  // namespace cdr
}  // namespace tactile_msgs

#endif  // TACTILE_MSGS__CDR__CDR_STREAM_HPP_
