// Incremental parsers of the whisker deck's serial protocols (115200 baud text).
//
// - Text protocol (whisker 1): one value per line, "P1:<v>", "P2:<v>", "P3:<v>",
//   "T1:<v>", "T2:<v>", "T3:<v>" (pressures Pa, temperatures degC). A frame starts
//   at P1 and is complete at T3, or at the next P1 when P1-P3 have arrived
//   (temperatures that did not arrive are NaN).
// - CSV protocol (whisker 2): one frame per line, "p1,p2,p3" (Pa); temperatures NaN.
//
// Lines end with LF or CRLF. Bytes may arrive in any split. Lines longer than
// max_line_length are dropped up to the next newline. Every dropped line and
// frame is counted by reason in ParseStats; emitted frames always hold three
// finite pressures in the BMP390 range and finite temperatures or NaN.
//
// Core layer: no ROS, no message types.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace whisker_driver {

/// BMP390 operating range (datasheet): 300-1250 hPa, -40..85 degC.
constexpr double kMinPressurePa = 30000.0;
constexpr double kMaxPressurePa = 125000.0;
constexpr double kMinTemperatureC = -40.0;
constexpr double kMaxTemperatureC = 85.0;

/// One complete barometer frame of a whisker.
struct WhiskerFrame {
  std::array<double, 3> pressure{};     ///< [Pa], always finite and in range
  std::array<double, 3> temperature{};  ///< [degC], NaN where not reported
  uint32_t sequence = 0;                ///< frames started by the parser so far (gaps = dropped frames)
};

/// Counters of the parser. Every dropped line is counted in exactly one of the
/// *_lines / *_values / out_of_order_fields counters; every dropped frame in
/// incomplete_frames or invalid_frames.
struct ParseStats {
  uint64_t bytes = 0;               ///< bytes fed
  uint64_t lines = 0;               ///< complete, non-empty lines (oversized ones excluded)
  uint64_t frames = 0;              ///< frames emitted
  uint64_t empty_lines = 0;         ///< blank lines (ignored, not an error)
  uint64_t oversized_lines = 0;     ///< lines longer than max_line_length (dropped to next newline)
  uint64_t malformed_lines = 0;     ///< unknown key, missing ':' or fields, non-numeric value, control bytes
  uint64_t non_finite_values = 0;   ///< NaN / inf (or overflowing) values
  uint64_t out_of_range_values = 0; ///< outside the BMP390 range
  uint64_t out_of_order_fields = 0; ///< text: field without a started frame, or repeated in a frame
  uint64_t incomplete_frames = 0;   ///< text: new P1 (or a repeated field) before P1-P3 were complete
  uint64_t invalid_frames = 0;      ///< frames dropped because one of their values was invalid

  /// Lines dropped for any reason.
  uint64_t dropped_lines() const {
    return oversized_lines + malformed_lines + non_finite_values + out_of_range_values +
           out_of_order_fields;
  }
  /// Frames dropped for any reason.
  uint64_t dropped_frames() const { return incomplete_frames + invalid_frames; }
};

enum class Protocol { kText, kCsv };

/// "text" or "csv"; throws std::invalid_argument otherwise.
Protocol protocol_from_string(const std::string& name);

/// Base: splits the byte stream into lines and hands them to parse_line().
class FrameParser {
 public:
  static constexpr size_t kDefaultMaxLineLength = 64;

  explicit FrameParser(size_t max_line_length = kDefaultMaxLineLength);
  virtual ~FrameParser() = default;

  /// Consumes n bytes, appends every frame completed by them to `out` and
  /// returns how many were appended. Never throws on any input.
  size_t feed(const char* data, size_t n, std::vector<WhiskerFrame>& out);

  const ParseStats& stats() const { return stats_; }
  /// Forgets the partial line and frame (e.g. after a port reopen); keeps stats.
  virtual void reset();

 protected:
  /// A complete line without its terminator (at most max_line_length chars).
  virtual void parse_line(const char* line, size_t len, std::vector<WhiskerFrame>& out) = 0;

  enum class Value { kOk, kMalformed, kNonFinite, kOutOfRange };
  /// Parses a decimal number (optional sign, digits, '.', exponent; surrounding
  /// blanks allowed), locale-independent, and checks [lo, hi].
  static Value parse_value(const char* s, size_t len, double lo, double hi, double& out);
  /// Counts a bad value by reason.
  void count(Value v);

  ParseStats stats_;

 private:
  std::vector<char> line_;
  size_t max_line_;
  bool discarding_ = false;
};

/// Whisker 1: "P1:<v>" ... "T3:<v>", one value per line.
class TextFrameParser : public FrameParser {
 public:
  using FrameParser::FrameParser;
  void reset() override;

 protected:
  void parse_line(const char* line, size_t len, std::vector<WhiskerFrame>& out) override;

 private:
  void finish_frame(std::vector<WhiskerFrame>& out);

  bool open_ = false;      // a frame has started (P1 seen)
  bool bad_ = false;       // one of its values was invalid
  unsigned have_ = 0;      // bit i: field i (P1,P2,P3,T1,T2,T3) arrived
  WhiskerFrame frame_{};
  uint32_t started_ = 0;
};

/// Whisker 2: "p1,p2,p3" per line.
class CsvFrameParser : public FrameParser {
 public:
  using FrameParser::FrameParser;
  void reset() override;

 protected:
  void parse_line(const char* line, size_t len, std::vector<WhiskerFrame>& out) override;

 private:
  uint32_t started_ = 0;
};

std::unique_ptr<FrameParser> make_parser(Protocol protocol,
                                         size_t max_line_length = FrameParser::kDefaultMaxLineLength);

}  // namespace whisker_driver
