#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "whisker_driver/frame_parser.hpp"

using namespace whisker_driver;

namespace {

std::vector<WhiskerFrame> feed_all(FrameParser& p, const std::string& s) {
  std::vector<WhiskerFrame> out;
  p.feed(s.data(), s.size(), out);
  return out;
}

// Two text frames with temperatures, values chosen by hand.
const char* kText =
    "P1:101325.5\nP2:101400\nP3:99000.25\nT1:25.5\nT2:26\nT3:-3.5\n"
    "P1:101330\nP2:101401.5\nP3:99001\nT1:25.6\nT2:26.1\nT3:-3.4\n";

void expect_text_frames(const std::vector<WhiskerFrame>& f, uint32_t first_sequence = 0) {
  ASSERT_EQ(f.size(), 2u);
  EXPECT_DOUBLE_EQ(f[0].pressure[0], 101325.5);
  EXPECT_DOUBLE_EQ(f[0].pressure[1], 101400.0);
  EXPECT_DOUBLE_EQ(f[0].pressure[2], 99000.25);
  EXPECT_DOUBLE_EQ(f[0].temperature[0], 25.5);
  EXPECT_DOUBLE_EQ(f[0].temperature[1], 26.0);
  EXPECT_DOUBLE_EQ(f[0].temperature[2], -3.5);
  EXPECT_DOUBLE_EQ(f[1].pressure[1], 101401.5);
  EXPECT_DOUBLE_EQ(f[1].temperature[2], -3.4);
  EXPECT_EQ(f[0].sequence, first_sequence);
  EXPECT_EQ(f[1].sequence, first_sequence + 1);
}

}  // namespace

TEST(TextFrameParser, ValidStreamSplitAtEveryByteBoundary) {
  const std::string s = kText;
  for (size_t cut = 0; cut <= s.size(); ++cut) {
    TextFrameParser p;
    std::vector<WhiskerFrame> out;
    p.feed(s.data(), cut, out);
    p.feed(s.data() + cut, s.size() - cut, out);
    expect_text_frames(out);
    EXPECT_EQ(p.stats().lines, 12u);
    EXPECT_EQ(p.stats().frames, 2u);
    EXPECT_EQ(p.stats().dropped_lines(), 0u);
    EXPECT_EQ(p.stats().dropped_frames(), 0u);
    EXPECT_EQ(p.stats().bytes, s.size());
  }
  // Byte by byte.
  TextFrameParser p;
  std::vector<WhiskerFrame> out;
  for (char c : s) p.feed(&c, 1, out);
  expect_text_frames(out);
}

TEST(TextFrameParser, CrLfAndBlankLines) {
  std::string s = kText;
  std::string crlf;
  for (char c : s) {
    if (c == '\n') crlf += "\r\n"; else crlf += c;
  }
  crlf = "\r\n\n" + crlf;  // blank lines are ignored
  for (size_t cut = 0; cut <= crlf.size(); ++cut) {
    TextFrameParser p;
    std::vector<WhiskerFrame> out;
    p.feed(crlf.data(), cut, out);
    p.feed(crlf.data() + cut, crlf.size() - cut, out);
    expect_text_frames(out);
    EXPECT_EQ(p.stats().empty_lines, 2u);
    EXPECT_EQ(p.stats().dropped_lines(), 0u);
  }
}

TEST(TextFrameParser, FrameWithoutTemperaturesCompletesAtNextP1) {
  TextFrameParser p;
  auto out = feed_all(p, "P1:100000\nP2:100001\nP3:100002\n");
  EXPECT_TRUE(out.empty());  // could still get temperatures
  out = feed_all(p, "P1:100010\n");
  ASSERT_EQ(out.size(), 1u);
  EXPECT_DOUBLE_EQ(out[0].pressure[2], 100002.0);
  for (double t : out[0].temperature) EXPECT_TRUE(std::isnan(t));
  // Partial temperatures: the ones that arrived are kept.
  out = feed_all(p, "P2:100011\nP3:100012\nT2:30.5\nP1:100020\n");
  ASSERT_EQ(out.size(), 1u);
  EXPECT_TRUE(std::isnan(out[0].temperature[0]));
  EXPECT_DOUBLE_EQ(out[0].temperature[1], 30.5);
  EXPECT_TRUE(std::isnan(out[0].temperature[2]));
  EXPECT_EQ(p.stats().dropped_frames(), 0u);
}

TEST(TextFrameParser, NewP1BeforeCompleteFrameDropsIt) {
  TextFrameParser p;
  auto out = feed_all(p, "P1:100000\nP2:100001\nP1:100100\nP2:100101\nP3:100102\nT1:1\nT2:2\nT3:3\n");
  ASSERT_EQ(out.size(), 1u);
  EXPECT_DOUBLE_EQ(out[0].pressure[0], 100100.0);
  EXPECT_EQ(out[0].sequence, 1u);  // frame 0 was dropped: a gap
  EXPECT_EQ(p.stats().incomplete_frames, 1u);
  EXPECT_EQ(p.stats().frames, 1u);
}

TEST(TextFrameParser, OutOfOrderAndRepeatedFields) {
  TextFrameParser p;
  // P2 before any P1; then a frame with P2 twice (dropped); then a good frame.
  auto out = feed_all(p,
                      "P2:100000\nT1:20\n"
                      "P1:100000\nP2:100001\nP2:100001\nP3:100002\nT1:1\nT2:2\nT3:3\n"
                      "P1:100000\nP2:100001\nP3:100002\nT1:1\nT2:2\nT3:3\n");
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].sequence, 1u);
  // 2 orphans + the repeated P2 + the fields after the dropped frame (P3, T1..T3).
  EXPECT_EQ(p.stats().out_of_order_fields, 3u + 4u);
  EXPECT_EQ(p.stats().incomplete_frames, 1u);
}

TEST(TextFrameParser, GarbageLinesAreCountedAndSkipped) {
  TextFrameParser p;
  const std::string garbage =
      "hello\nP4:100000\nX1:5\nP1=100000\n:\nP\nP1:\nP1:abc\nP1:0x1p16\nP1:1,5\nP1:--5\nP1:1e\n";
  auto out = feed_all(p, garbage + kText);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_DOUBLE_EQ(out[0].pressure[0], 101325.5);
  EXPECT_DOUBLE_EQ(out[1].temperature[2], -3.4);
  // hello P4 X1 P1= : P P1: -> malformed line (no frame started);
  // P1:abc, 0x1p16, 1,5, --5, 1e start frames with a malformed value.
  EXPECT_EQ(p.stats().malformed_lines, 12u);
  // The five bad P1 frames are dropped as incomplete (the next P1 comes before P2/P3).
  EXPECT_EQ(p.stats().incomplete_frames, 5u);
  EXPECT_EQ(out[0].sequence, 5u);
}

TEST(TextFrameParser, NonFiniteAndOutOfRangeValuesDropTheFrame) {
  const std::vector<std::string> non_finite = {"nan", "NaN", "inf", "-inf", "infinity", "1e999", "-1e400"};
  for (const auto& v : non_finite) {
    TextFrameParser p;
    auto out = feed_all(p, "P1:100000\nP2:" + v + "\nP3:100002\nT1:1\nT2:2\nT3:3\n" + kText);
    ASSERT_EQ(out.size(), 2u) << v;
    EXPECT_EQ(p.stats().non_finite_values, 1u) << v;
    EXPECT_EQ(p.stats().invalid_frames, 1u) << v;
  }
  const std::vector<std::string> out_of_range = {"P2:29999.9", "P2:125000.1", "P2:0", "P2:-100000",
                                                 "T2:85.01", "T2:-40.5"};
  for (const auto& bad : out_of_range) {
    // A complete frame whose field bad[0..1] is replaced by the bad line.
    std::string frame;
    for (const char* f : {"P1:100000", "P2:100001", "P3:100002", "T1:1", "T2:2", "T3:3"}) {
      frame += (std::string(f).substr(0, 2) == bad.substr(0, 2) ? bad : std::string(f)) + "\n";
    }
    TextFrameParser p;
    auto out = feed_all(p, frame + kText);
    expect_text_frames(out, 1);
    EXPECT_EQ(out.size(), 2u) << bad;
    EXPECT_EQ(p.stats().out_of_range_values, 1u) << bad;
    EXPECT_EQ(p.stats().invalid_frames, 1u) << bad;
  }
  // Boundaries are inclusive.
  TextFrameParser p;
  auto out = feed_all(p, "P1:30000\nP2:125000\nP3:+1.0e5\nT1:-40\nT2:85\nT3:0\n");
  ASSERT_EQ(out.size(), 1u);
  EXPECT_DOUBLE_EQ(out[0].pressure[2], 100000.0);
}

TEST(TextFrameParser, OversizedLinesAreDroppedToTheNextNewline) {
  TextFrameParser p;  // 64 bytes max
  const std::string longline(200, 'P');
  // The oversized line arrives in pieces, the newline in a later read.
  std::vector<WhiskerFrame> out;
  p.feed(longline.data(), 100, out);
  p.feed(longline.data() + 100, 100, out);
  p.feed("\n", 1, out);
  const std::string s = kText;
  p.feed(s.data(), s.size(), out);
  expect_text_frames(out);
  EXPECT_EQ(p.stats().oversized_lines, 1u);
  EXPECT_EQ(p.stats().lines, 12u);

  // Exactly 64 characters (padded value) is accepted, also with CRLF; 65 is not.
  const std::string v64 = "P1:100000" + std::string(64 - 9, ' ');
  ASSERT_EQ(v64.size(), 64u);
  TextFrameParser q;
  feed_all(q, v64 + "\nP2:1e5\nP3:1e5\nT1:1\nT2:1\nT3:1\n");
  EXPECT_EQ(q.stats().frames, 1u);
  feed_all(q, v64 + "\r\nP2:1e5\nP3:1e5\nT1:1\nT2:1\nT3:1\n");
  EXPECT_EQ(q.stats().frames, 2u);
  feed_all(q, v64 + " \nP2:1e5\nP3:1e5\nT1:1\nT2:1\nT3:1\n");
  EXPECT_EQ(q.stats().frames, 2u);
  EXPECT_EQ(q.stats().oversized_lines, 1u);
  // And the orphaned fields after it are counted, not emitted.
  EXPECT_EQ(q.stats().out_of_order_fields, 5u);
}

TEST(CsvFrameParser, ValidStreamSplitAtEveryByteBoundary) {
  const std::string s = "101325.5,101400,99000.25\r\n100000,100001,100002\n";
  for (size_t cut = 0; cut <= s.size(); ++cut) {
    CsvFrameParser p;
    std::vector<WhiskerFrame> out;
    p.feed(s.data(), cut, out);
    p.feed(s.data() + cut, s.size() - cut, out);
    ASSERT_EQ(out.size(), 2u) << cut;
    EXPECT_DOUBLE_EQ(out[0].pressure[0], 101325.5);
    EXPECT_DOUBLE_EQ(out[0].pressure[1], 101400.0);
    EXPECT_DOUBLE_EQ(out[0].pressure[2], 99000.25);
    EXPECT_DOUBLE_EQ(out[1].pressure[2], 100002.0);
    for (double t : out[0].temperature) EXPECT_TRUE(std::isnan(t));
    EXPECT_EQ(out[1].sequence, 1u);
    EXPECT_EQ(p.stats().dropped_lines(), 0u);
  }
}

TEST(CsvFrameParser, BadLinesAreCountedByReason) {
  CsvFrameParser p;
  const std::string s =
      "100000,100001\n"              // missing field -> malformed
      "100000,100001,100002,5\n"     // extra field -> malformed
      "100000,,100002\n"             // empty field -> malformed
      "100000,abc,100002\n"          // non-numeric -> malformed
      "100000,nan,100002\n"          // non-finite
      "inf,100001,100002\n"          // non-finite
      "100000,100001,2000\n"         // out of range
      "P1:100000\n"                  // wrong protocol -> malformed
      " 100000 , 100001 ,\t100002 \n"  // blanks around values are fine
      + std::string(70, '1') + "\n"  // oversized
      "100000,100001,100002\n";
  auto out = feed_all(p, s);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_DOUBLE_EQ(out[0].pressure[1], 100001.0);
  EXPECT_EQ(out[0].sequence, 8u);
  EXPECT_EQ(out[1].sequence, 9u);  // the oversized line never became a line
  const auto& st = p.stats();
  EXPECT_EQ(st.malformed_lines, 5u);
  EXPECT_EQ(st.non_finite_values, 2u);
  EXPECT_EQ(st.out_of_range_values, 1u);
  EXPECT_EQ(st.oversized_lines, 1u);
  EXPECT_EQ(st.invalid_frames, 8u);
  EXPECT_EQ(st.lines, 10u);
  EXPECT_EQ(st.lines, st.frames + st.malformed_lines + st.non_finite_values + st.out_of_range_values);
}

TEST(FrameParser, ProtocolFromString) {
  EXPECT_EQ(protocol_from_string("text"), Protocol::kText);
  EXPECT_EQ(protocol_from_string("csv"), Protocol::kCsv);
  EXPECT_THROW(protocol_from_string("CSV"), std::invalid_argument);
  EXPECT_NE(dynamic_cast<CsvFrameParser*>(make_parser(Protocol::kCsv).get()), nullptr);
}

// Seeded fuzz loop: 1e5 random buffers per parser, biased towards protocol
// bytes. Never crash, never emit a non-finite or out-of-range pressure, and the
// CSV line accounting adds up.
TEST(FrameParser, RandomBytesNeverCrashOrEmitBadValues) {
  std::mt19937_64 rng(12345);
  const std::string alphabet = "PT123:,.-+eE0123456789\r\n naif";
  std::uniform_int_distribution<int> len_d(0, 200), byte_d(0, 255), pick(0, 3);
  std::uniform_int_distribution<size_t> alpha_d(0, alphabet.size() - 1);
  TextFrameParser text;
  CsvFrameParser csv;
  std::vector<WhiskerFrame> out;
  std::string buf;
  uint64_t emitted = 0;
  for (int iter = 0; iter < 100000; ++iter) {
    buf.clear();
    const int n = len_d(rng);
    for (int i = 0; i < n; ++i) {
      buf.push_back(pick(rng) == 0 ? static_cast<char>(byte_d(rng)) : alphabet[alpha_d(rng)]);
    }
    // Occasionally a valid line, so that frames do get through.
    if (iter % 7 == 0) buf += "\nP1:100000\nP2:100001\nP3:100002\nT1:20\nT2:21\nT3:22\n100000,1e5,100000\n";
    out.clear();
    text.feed(buf.data(), buf.size(), out);
    csv.feed(buf.data(), buf.size(), out);
    for (const auto& f : out) {
      for (int c = 0; c < 3; ++c) {
        ASSERT_TRUE(std::isfinite(f.pressure[c]));
        ASSERT_GE(f.pressure[c], kMinPressurePa);
        ASSERT_LE(f.pressure[c], kMaxPressurePa);
        ASSERT_FALSE(std::isinf(f.temperature[c]));
        if (!std::isnan(f.temperature[c])) {
          ASSERT_GE(f.temperature[c], kMinTemperatureC);
          ASSERT_LE(f.temperature[c], kMaxTemperatureC);
        }
      }
    }
    emitted += out.size();
  }
  EXPECT_GT(text.stats().frames, 1000u);
  EXPECT_GT(csv.stats().frames, 1000u);
  EXPECT_EQ(emitted, text.stats().frames + csv.stats().frames);
  const auto& st = csv.stats();
  EXPECT_EQ(st.lines, st.frames + st.malformed_lines + st.non_finite_values + st.out_of_range_values);
  EXPECT_GT(text.stats().dropped_lines(), 0u);
}
