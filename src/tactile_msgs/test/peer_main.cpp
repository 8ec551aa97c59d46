// Test peer for test_rosbags_peer.py (built for the tests, never installed).
//
//   tactile_msgs_peer dump    one JSON object per line for every type:
//                             {"type", "definition", "hex"} where hex is the CDR of
//                             testing::make_filled<T>() (deterministic values)
//   tactile_msgs_peer check   reads lines "<type> <hex>" from stdin; for each, decodes the
//                             bytes and prints {"type", "ok", "equal", "hex", "error"}:
//                             equal = decoded message == make_filled<T>(), hex = re-encoded
#include <cstdint>
#include <cstdio>
#include <functional>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "tactile_msgs/cdr/serialization.hpp"
#include "tactile_msgs/cdr/testing.hpp"

namespace
{

std::string json_string(const std::string & s)
{
  std::string out = "\"";
  for (unsigned char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      default:
        if (c < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof(buf), "\\u%04x", c);
          out += buf;
        } else {
          out += static_cast<char>(c);
        }
    }
  }
  return out + "\"";
}

std::string to_hex(const std::vector<uint8_t> & bytes)
{
  static const char * digits = "0123456789abcdef";
  std::string out;
  out.reserve(bytes.size() * 2);
  for (uint8_t b : bytes) {
    out += digits[b >> 4];
    out += digits[b & 15];
  }
  return out;
}

bool from_hex(const std::string & hex, std::vector<uint8_t> & out)
{
  if (hex.size() % 2 != 0) {return false;}
  out.clear();
  for (std::size_t i = 0; i < hex.size(); i += 2) {
    unsigned v = 0;
    if (std::sscanf(hex.c_str() + i, "%2x", &v) != 1) {return false;}
    out.push_back(static_cast<uint8_t>(v));
  }
  return true;
}

struct Entry
{
  std::function<std::string()> dump;
  std::function<std::string(const std::vector<uint8_t> &)> check;
};

template<class T>
Entry make_entry()
{
  using tactile_msgs::cdr::MessageTraits;
  Entry e;
  e.dump = []() {
      const auto bytes = tactile_msgs::cdr::serialize(tactile_msgs::cdr::testing::make_filled<T>());
      return std::string("{\"type\": ") + json_string(MessageTraits<T>::type_name) +
             ", \"definition\": " + json_string(MessageTraits<T>::definition()) +
             ", \"hex\": " + json_string(to_hex(bytes)) + "}";
    };
  e.check = [](const std::vector<uint8_t> & bytes) {
      std::string head = std::string("{\"type\": ") + json_string(MessageTraits<T>::type_name);
      try {
        T msg{};
        tactile_msgs::cdr::deserialize(bytes.data(), bytes.size(), msg);
        const bool equal = msg == tactile_msgs::cdr::testing::make_filled<T>();
        return head + ", \"ok\": true, \"equal\": " + (equal ? "true" : "false") +
               ", \"hex\": " + json_string(to_hex(tactile_msgs::cdr::serialize(msg))) +
               ", \"error\": \"\"}";
      } catch (const tactile_msgs::cdr::DecodeError & err) {
        return head + ", \"ok\": false, \"equal\": false, \"hex\": \"\", \"error\": " +
               json_string(err.what()) + "}";
      }
    };
  return e;
}

template<class ... Ts>
std::map<std::string, Entry> make_table(std::tuple<Ts...> *)
{
  using tactile_msgs::cdr::MessageTraits;
  return {{MessageTraits<Ts>::type_name, make_entry<Ts>()}...};
}

}  // namespace

int main(int argc, char ** argv)
{
  const auto table = make_table(static_cast<tactile_msgs::cdr::testing::AllTypes *>(nullptr));
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "dump") {
    for (const auto & kv : table) {std::cout << kv.second.dump() << "\n";}
    return 0;
  }
  if (mode == "check") {
    std::string line;
    while (std::getline(std::cin, line)) {
      if (line.empty()) {continue;}
      std::istringstream in(line);
      std::string type, hex;
      in >> type >> hex;
      std::vector<uint8_t> bytes;
      const auto it = table.find(type);
      if (it == table.end() || !from_hex(hex, bytes)) {
        std::cout << "{\"type\": " << json_string(type) <<
          ", \"ok\": false, \"equal\": false, \"hex\": \"\", \"error\": \"bad request\"}\n";
        continue;
      }
      std::cout << it->second.check(bytes) << "\n";
    }
    return 0;
  }
  std::cerr << "usage: tactile_msgs_peer dump|check\n";
  return 2;
}
