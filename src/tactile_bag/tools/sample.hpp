// The sample bag of `tactile_bag_tool write-sample`: known contents for peer tests
// (test/test_rosbags_peer.py recomputes every value independently).
//
// Topics (timestamps in ns, i = message index):
//   /whisker/left/pressure   tactile_msgs/msg/WhiskerPressure  5 msgs, t = 1e9 + i*20e6
//       stamp = t, frame_id "whisker_left", whisker_id 0,
//       pressure[k] = 101325 + 10 i + k, temperature[k] = 25 + 0.5 k, sequence = i
//   /whisker/right/pressure  tactile_msgs/msg/WhiskerPressure  5 msgs, t = 1e9 + i*20e6 + 10e6
//       frame_id "whisker_right", whisker_id 1, pressure[k] = 100000 - 7 i - k,
//       temperature NaN, sequence = 100 + i
//   /chatter                 std_msgs/msg/String               3 msgs, t = 1e9 + i*30e6 + 5e6
//       data = "hello <i>"
//   /vector                  geometry_msgs/msg/Vector3         2 msgs, t = 1e9 + i*50e6 + 1e6
//       x = i + 0.25, y = -i, z = 1e-3 i
//   /silent                  std_msgs/msg/String               0 msgs
//
// The CDR here is written by hand (XCDR1, little endian, encapsulation 00 01 00 00)
// and independently of tactile_msgs, so the peer test checks both.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "tactile_bag/bag.hpp"

namespace tactile_bag::sample {

class Cdr {
 public:
  Cdr() : buf_{0x00, 0x01, 0x00, 0x00} {}
  template <class T>
  void put(T v) {
    align(sizeof(T));
    uint8_t b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));  // little-endian host (x86-64, aarch64)
    buf_.insert(buf_.end(), b, b + sizeof(T));
  }
  void put_string(const std::string& s) {
    put<uint32_t>(static_cast<uint32_t>(s.size() + 1));
    buf_.insert(buf_.end(), s.begin(), s.end());
    buf_.push_back(0);
  }
  const std::vector<uint8_t>& bytes() const { return buf_; }

 private:
  void align(size_t n) {
    while ((buf_.size() - 4) % n != 0) buf_.push_back(0);
  }
  std::vector<uint8_t> buf_;
};

inline const char* kWhiskerPressureDef =
    "uint8 WHISKER_LEFT = 0\n"
    "uint8 WHISKER_RIGHT = 1\n"
    "std_msgs/Header header\n"
    "uint8 whisker_id\n"
    "float64[3] pressure\n"
    "float64[3] temperature\n"
    "uint32 sequence\n"
    "\n"
    "================================================================================\n"
    "MSG: std_msgs/Header\n"
    "builtin_interfaces/Time stamp\n"
    "string frame_id\n"
    "\n"
    "================================================================================\n"
    "MSG: builtin_interfaces/Time\n"
    "int32 sec\n"
    "uint32 nanosec\n";

inline const char* kStringDef = "string data\n";
inline const char* kVector3Def = "float64 x\nfloat64 y\nfloat64 z\n";

inline std::vector<uint8_t> whisker_pressure(int64_t stamp_ns, const std::string& frame,
                                             uint8_t id, const double p[3], const double t[3],
                                             uint32_t seq) {
  Cdr c;
  c.put<int32_t>(static_cast<int32_t>(stamp_ns / 1000000000));
  c.put<uint32_t>(static_cast<uint32_t>(stamp_ns % 1000000000));
  c.put_string(frame);
  c.put<uint8_t>(id);
  for (int k = 0; k < 3; ++k) c.put<double>(p[k]);
  for (int k = 0; k < 3; ++k) c.put<double>(t[k]);
  c.put<uint32_t>(seq);
  return c.bytes();
}

/// Writes the sample into an open writer; returns the number of messages.
inline uint64_t write_sample(Writer& w) {
  TopicInfo wp;
  wp.type = "tactile_msgs/msg/WhiskerPressure";
  wp.type_definition = kWhiskerPressureDef;
  wp.name = "/whisker/left/pressure";
  w.create_topic(wp);
  wp.name = "/whisker/right/pressure";
  w.create_topic(wp);
  TopicInfo s;
  s.type = "std_msgs/msg/String";
  s.type_definition = kStringDef;
  s.name = "/chatter";
  w.create_topic(s);
  s.name = "/silent";
  w.create_topic(s);
  TopicInfo v;
  v.name = "/vector";
  v.type = "geometry_msgs/msg/Vector3";
  v.type_definition = kVector3Def;
  w.create_topic(v);

  uint64_t n = 0;
  const int64_t t0 = 1000000000;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // Written in topic order, not time order: the reader must sort by timestamp.
  for (int i = 0; i < 5; ++i) {
    const int64_t t = t0 + i * 20000000LL;
    const double p[3] = {101325.0 + 10 * i, 101325.0 + 10 * i + 1, 101325.0 + 10 * i + 2};
    const double temp[3] = {25.0, 25.5, 26.0};
    w.write("/whisker/left/pressure", t,
            whisker_pressure(t, "whisker_left", 0, p, temp, static_cast<uint32_t>(i)));
    ++n;
  }
  for (int i = 0; i < 5; ++i) {
    const int64_t t = t0 + i * 20000000LL + 10000000LL;
    const double p[3] = {100000.0 - 7 * i, 100000.0 - 7 * i - 1, 100000.0 - 7 * i - 2};
    const double temp[3] = {nan, nan, nan};
    w.write("/whisker/right/pressure", t,
            whisker_pressure(t, "whisker_right", 1, p, temp, static_cast<uint32_t>(100 + i)));
    ++n;
  }
  for (int i = 0; i < 3; ++i) {
    Cdr c;
    c.put_string("hello " + std::to_string(i));
    w.write("/chatter", t0 + i * 30000000LL + 5000000LL, c.bytes());
    ++n;
  }
  for (int i = 0; i < 2; ++i) {
    Cdr c;
    c.put<double>(i + 0.25);
    c.put<double>(-static_cast<double>(i));
    c.put<double>(1e-3 * i);
    w.write("/vector", t0 + i * 50000000LL + 1000000LL, c.bytes());
    ++n;
  }
  return n;
}

}  // namespace tactile_bag::sample
