#include "whisker_driver/frame_parser.hpp"

#include <charconv>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace whisker_driver {

Protocol protocol_from_string(const std::string& name) {
  if (name == "text") return Protocol::kText;
  if (name == "csv") return Protocol::kCsv;
  throw std::invalid_argument("protocol: must be \"text\" or \"csv\", got \"" + name + "\"");
}

std::unique_ptr<FrameParser> make_parser(Protocol protocol, size_t max_line_length) {
  if (protocol == Protocol::kCsv) return std::make_unique<CsvFrameParser>(max_line_length);
  return std::make_unique<TextFrameParser>(max_line_length);
}

FrameParser::FrameParser(size_t max_line_length) : max_line_(max_line_length) {
  if (max_line_length == 0) throw std::invalid_argument("FrameParser: max_line_length must be > 0");
  line_.reserve(max_line_length);
}

void FrameParser::reset() {
  line_.clear();
  discarding_ = false;
}

size_t FrameParser::feed(const char* data, size_t n, std::vector<WhiskerFrame>& out) {
  const size_t before = out.size();
  stats_.bytes += n;
  for (size_t i = 0; i < n; ++i) {
    const char c = data[i];
    if (c == '\n') {
      if (discarding_) {
        discarding_ = false;  // the oversized line ends here; already counted
      } else {
        size_t len = line_.size();
        if (len > 0 && line_[len - 1] == '\r') --len;  // CRLF
        if (len == 0) {
          ++stats_.empty_lines;
        } else {
          ++stats_.lines;
          parse_line(line_.data(), len, out);
        }
      }
      line_.clear();
      continue;
    }
    if (discarding_) continue;
    // At most max_line_ characters, plus the '\r' of a CRLF terminator.
    if (line_.size() >= max_line_ && !(line_.size() == max_line_ && c == '\r')) {
      ++stats_.oversized_lines;
      discarding_ = true;
      line_.clear();
      continue;
    }
    line_.push_back(c);
  }
  return out.size() - before;
}

FrameParser::Value FrameParser::parse_value(const char* s, size_t len, double lo, double hi,
                                            double& out) {
  size_t b = 0, e = len;
  while (b < e && (s[b] == ' ' || s[b] == '\t')) ++b;
  while (e > b && (s[e - 1] == ' ' || s[e - 1] == '\t')) --e;
  if (b == e) return Value::kMalformed;
  // Named non-finite values and overflow are reported as non-finite.
  bool negative = false;
  size_t p = b;
  if (s[p] == '+' || s[p] == '-') {
    negative = s[p] == '-';
    ++p;
  }
  if (p == e) return Value::kMalformed;
  // Only a plain decimal grammar: digits, one '.', exponent. No hex, no "nan"/"inf".
  const char first = s[p];
  if (first == 'n' || first == 'N' || first == 'i' || first == 'I') {
    double v = 0.0;
    const auto r = std::from_chars(s + p, s + e, v);
    return (r.ec == std::errc() && r.ptr == s + e) ? Value::kNonFinite : Value::kMalformed;
  }
  for (size_t k = p; k < e; ++k) {
    const char c = s[k];
    if (!((c >= '0' && c <= '9') || c == '.' || c == 'e' || c == 'E' || c == '+' || c == '-')) {
      return Value::kMalformed;
    }
  }
  if (s[p] == '+' || s[p] == '-') return Value::kMalformed;  // a second sign
  double v = 0.0;
  const auto r = std::from_chars(s + p, s + e, v, std::chars_format::general);
  if (r.ptr != s + e) return Value::kMalformed;
  if (r.ec == std::errc::result_out_of_range) {
    // The value is left unspecified: decide by the sign of the exponent.
    bool negative_exponent = false;
    for (size_t k = p; k + 1 < e; ++k) {
      if ((s[k] == 'e' || s[k] == 'E') && s[k + 1] == '-') negative_exponent = true;
    }
    if (!negative_exponent) return Value::kNonFinite;  // overflow: +-inf
    v = 0.0;                                           // underflow
  } else if (r.ec != std::errc()) {
    return Value::kMalformed;
  }
  if (negative) v = -v;
  if (!std::isfinite(v)) return Value::kNonFinite;
  if (v < lo || v > hi) return Value::kOutOfRange;
  out = v;
  return Value::kOk;
}

void FrameParser::count(Value v) {
  switch (v) {
    case Value::kMalformed: ++stats_.malformed_lines; break;
    case Value::kNonFinite: ++stats_.non_finite_values; break;
    case Value::kOutOfRange: ++stats_.out_of_range_values; break;
    case Value::kOk: break;
  }
}

// ---------------------------------------------------------------- text protocol

void TextFrameParser::reset() {
  FrameParser::reset();
  open_ = false;
  bad_ = false;
  have_ = 0;
}

void TextFrameParser::finish_frame(std::vector<WhiskerFrame>& out) {
  if (!open_) return;
  if ((have_ & 0x7u) != 0x7u) {
    ++stats_.incomplete_frames;
  } else if (bad_) {
    ++stats_.invalid_frames;
  } else {
    for (int i = 0; i < 3; ++i) {
      if (!(have_ & (1u << (3 + i)))) frame_.temperature[i] = std::numeric_limits<double>::quiet_NaN();
    }
    out.push_back(frame_);
    ++stats_.frames;
  }
  open_ = false;
  bad_ = false;
  have_ = 0;
}

void TextFrameParser::parse_line(const char* line, size_t len, std::vector<WhiskerFrame>& out) {
  // "<K><n>:<value>", K in {P, T}, n in {1, 2, 3}.
  if (len < 4 || line[2] != ':' || (line[0] != 'P' && line[0] != 'T') || line[1] < '1' ||
      line[1] > '3') {
    ++stats_.malformed_lines;
    return;
  }
  const bool is_pressure = line[0] == 'P';
  const int ch = line[1] - '1';
  const unsigned field = static_cast<unsigned>(is_pressure ? ch : 3 + ch);
  double v = 0.0;
  const Value r = is_pressure
                      ? parse_value(line + 3, len - 3, kMinPressurePa, kMaxPressurePa, v)
                      : parse_value(line + 3, len - 3, kMinTemperatureC, kMaxTemperatureC, v);

  if (field == 0) {
    // P1 starts a frame; an open frame ends here (complete without all temperatures,
    // or incomplete).
    finish_frame(out);
    open_ = true;
    bad_ = false;
    have_ = 0;
    frame_ = WhiskerFrame{};
    frame_.sequence = started_++;
  } else if (!open_) {
    if (r == Value::kOk) {
      ++stats_.out_of_order_fields;
    } else {
      count(r);
    }
    return;
  } else if (have_ & (1u << field)) {
    // A repeated field: the frame is inconsistent. Drop it; the line too.
    ++stats_.out_of_order_fields;
    have_ &= 0x38u;  // make it count as incomplete
    finish_frame(out);
    return;
  }

  if (r != Value::kOk) {
    count(r);
    bad_ = true;
    have_ |= 1u << field;  // the field arrived, but its value is unusable
    if (field == 5) finish_frame(out);
    return;
  }
  have_ |= 1u << field;
  if (is_pressure) {
    frame_.pressure[ch] = v;
  } else {
    frame_.temperature[ch] = v;
  }
  if (field == 5) finish_frame(out);  // T3 completes the frame
}

// ----------------------------------------------------------------- CSV protocol

void CsvFrameParser::reset() { FrameParser::reset(); }

void CsvFrameParser::parse_line(const char* line, size_t len, std::vector<WhiskerFrame>& out) {
  WhiskerFrame f{};
  f.sequence = started_++;
  f.temperature.fill(std::numeric_limits<double>::quiet_NaN());
  size_t start = 0;
  int field = 0;
  Value worst = Value::kOk;
  for (size_t i = 0; i <= len; ++i) {
    if (i < len && line[i] != ',') continue;
    if (field >= 3) {
      ++stats_.malformed_lines;  // too many fields
      ++stats_.invalid_frames;
      return;
    }
    double v = 0.0;
    const Value r = parse_value(line + start, i - start, kMinPressurePa, kMaxPressurePa, v);
    if (r != Value::kOk && worst == Value::kOk) worst = r;
    f.pressure[field++] = v;
    start = i + 1;
  }
  if (field != 3) {
    ++stats_.malformed_lines;  // missing fields
    ++stats_.invalid_frames;
    return;
  }
  if (worst != Value::kOk) {
    count(worst);
    ++stats_.invalid_frames;
    return;
  }
  out.push_back(f);
  ++stats_.frames;
}

}  // namespace whisker_driver
