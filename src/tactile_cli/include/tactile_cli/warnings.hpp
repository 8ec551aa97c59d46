// Nothing silent: every repair, skip or drop a command makes on its input is
// one warning line on stderr ("tactile <command>: warning: ...", one line per
// kind with its count, not one per message) and one entry of the `warnings`
// list of its metrics.json ({"kind", "count", "message"}).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tactile_bag/bag.hpp"
#include "tactile_cli/host.hpp"

namespace tactile_cli {

class Warnings {
 public:
  struct Entry {
    std::string kind;
    uint64_t count = 0;
    std::string message;
  };

  /// Adds one warning (count 0 is ignored).
  void add(const std::string& kind, uint64_t count, const std::string& message);
  /// metadata.yaml missing, inconsistent or unreadable: the reader rebuilt it from the
  /// database ("metadata_rebuilt"); or data was lost (damaged mcap chunks skipped, a
  /// truncated tail: "bag_damaged", counted by the chunks skipped).
  void add_bag_metadata(const std::string& bag, const tactile_bag::Reader& reader);
  /// One warning per repair/drop counter of the host's nodes (whisker_driver:
  /// source errors, stamps repaired, duplicates, late samples, gaps, ...;
  /// every node's dropped_* counters), summed over the nodes, the message
  /// naming each node's share.
  void add_node_counters(const std::vector<NodeReport>& reports);

  const std::vector<Entry>& entries() const { return entries_; }
  bool empty() const { return entries_.empty(); }
  /// [{"kind", "count", "message"}, ...]
  nlohmann::json to_json() const;
  /// One line per entry on stderr: "tactile <command>: warning: <message>".
  void print(const std::string& command) const;

 private:
  std::vector<Entry> entries_;
};

}  // namespace tactile_cli
