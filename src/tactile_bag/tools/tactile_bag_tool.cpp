// tactile_bag_tool: inspect, dump and create rosbag2 (sqlite3, mcap) bags without ROS.
//
//   tactile_bag_tool info DIR           topics, types, counts, duration
//   tactile_bag_tool dump DIR [TOPIC..] one JSON object per message:
//                                       {"topic":..,"timestamp":..,"type":..,"data":"<hex>"}
//   tactile_bag_tool write-sample DIR [--version N]
//                                       a bag with known contents (see sample.hpp)
#include <cstdio>
#include <cstring>
#include <iostream>
#include <string>
#include <vector>

#include "sample.hpp"
#include "tactile_bag/bag.hpp"
#include "tactile_bag/distro.hpp"
#include "tactile_msgs/cdr/registry.hpp"

namespace {

std::string json_escape(const std::string& s) {
  std::string out;
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
          out.push_back(static_cast<char>(c));
        }
    }
  }
  return out;
}

// Every type of tactile_msgs' registry with the RIHS01 hash of its definition (what the writer
// stores for jazzy/kilted bags): "type hash" per line.
int hashes() {
  for (const auto& t : tactile_msgs::cdr::all_types()) {
    const std::string name(t.name);
    std::cout << name << " " << tactile_bag::rihs01_hash(name, std::string(t.definition)) << "\n";
  }
  return 0;
}

int usage() {
  std::cerr << "usage: tactile_bag_tool info DIR\n"
               "       tactile_bag_tool dump DIR [TOPIC...]\n"
               "       tactile_bag_tool hashes            # RIHS01 of every tactile_msgs type\n"
               "       tactile_bag_tool write-sample DIR [--version 5|8|9] [--storage sqlite3|mcap]\n"
               "                                    [--compression zstd|lz4] [--distro humble|iron|jazzy|kilted]\n";
  return 2;
}

int info(const std::string& dir) {
  tactile_bag::Reader r(dir);
  std::cout << "bag:          " << dir << "\n"
            << "storage:      " << r.storage_identifier()
            << (r.compression_mode().empty() ? "" : " (" + r.compression_format() + ", " + r.compression_mode() + " mode)")
            << "\n"
            << "ros_distro:   " << (r.ros_distro().empty() ? "(not stored)" : r.ros_distro()) << "\n"
            << "metadata:     "
            << (r.metadata_version() > 0 ? "version " + std::to_string(r.metadata_version())
                                         : std::string("missing"))
            << (r.metadata_complete() ? "" : " (incomplete: " + r.recovery_note() + ")") << "\n"
            << "files:        " << r.files().size() << "\n"
            << "messages:     " << r.message_count() << "\n"
            << "start:        " << r.start_time_ns() << " ns\n"
            << "duration:     " << r.duration_ns() << " ns ("
            << static_cast<double>(r.duration_ns()) * 1e-9 << " s)\n"
            << "topics:       " << r.topics().size() << "\n";
  for (const auto& t : r.topics()) {
    std::cout << "  " << t.name << " | " << t.type << " | " << t.serialization_format << " | "
              << r.message_count(t.name) << " msgs\n";
  }
  return 0;
}

int dump(const std::string& dir, const std::vector<std::string>& filter) {
  tactile_bag::Reader r(dir);
  if (!filter.empty()) r.set_topic_filter(filter);
  tactile_bag::SerializedMessage m;
  static const char* hex = "0123456789abcdef";
  std::string line;
  while (r.read_next(m)) {
    const auto* t = r.find_topic(m.topic);
    line = "{\"topic\":\"" + json_escape(m.topic) + "\",\"timestamp\":" +
           std::to_string(m.timestamp_ns) + ",\"type\":\"" +
           json_escape(t != nullptr ? t->type : "") + "\",\"data\":\"";
    for (uint8_t b : m.data) {
      line.push_back(hex[b >> 4]);
      line.push_back(hex[b & 15]);
    }
    line += "\"}\n";
    std::fwrite(line.data(), 1, line.size(), stdout);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 2 && std::strcmp(argv[1], "hashes") == 0) {
    try {
      return hashes();
    } catch (const std::exception& e) {
      std::cerr << "tactile_bag_tool: " << e.what() << "\n";
      return 1;
    }
  }
  if (argc < 3) return usage();
  const std::string cmd = argv[1];
  const std::string dir = argv[2];
  try {
    if (cmd == "info" && argc == 3) return info(dir);
    if (cmd == "dump") return dump(dir, std::vector<std::string>(argv + 3, argv + argc));
    if (cmd == "write-sample") {
      tactile_bag::WriterOptions opt;
      for (int i = 3; i < argc; ++i) {
        if (std::strcmp(argv[i], "--version") == 0 && i + 1 < argc) {
          opt.metadata_version = std::stoi(argv[++i]);
        } else if (std::strcmp(argv[i], "--storage") == 0 && i + 1 < argc) {
          opt.storage = argv[++i];
        } else if (std::strcmp(argv[i], "--compression") == 0 && i + 1 < argc) {
          opt.compression = argv[++i];
        } else if (std::strcmp(argv[i], "--distro") == 0 && i + 1 < argc) {
          opt.ros_distro = argv[++i];
        } else {
          return usage();
        }
      }
      tactile_bag::Writer w(opt);
      w.open(dir);
      const auto n = tactile_bag::sample::write_sample(w);
      w.close();
      std::cout << "wrote " << n << " messages to " << dir << "\n";
      return 0;
    }
  } catch (const std::exception& e) {
    std::cerr << "tactile_bag_tool: " << e.what() << "\n";
    return 1;
  }
  return usage();
}
