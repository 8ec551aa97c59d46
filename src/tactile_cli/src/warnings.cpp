#include "tactile_cli/warnings.hpp"

#include <algorithm>
#include <cstdio>
#include <map>

namespace tactile_cli {

namespace {

/// Counters that mean a repair or a drop, and what they say. Counters named
/// dropped_* that are not listed get a generic text. Not listed on purpose:
/// tdorc_filter's dropped_out_of_order (the sum of its dropped_duplicate and
/// dropped_late), gaps_bridged and samples_missing (the driver reports the
/// same gaps as samples_missing), and the driver's sequence_gaps (the same
/// missing samples counted by sequence) and gaps.
struct Kind {
  const char* counter;
  const char* text;
};
constexpr Kind kKinds[] = {
    {"source_errors", "messages dropped by the source (did not decode, or non-finite / out-of-range values)"},
    {"stamps_repaired_ahead",
     "header stamps far ahead of both the sequence and the receive time replaced (samples kept)"},
    {"stamps_repaired_behind",
     "header stamps behind or not advancing replaced (samples kept)"},
    {"clock_steps", "persistent stamp offsets taken as a new time base"},
    {"dropped_duplicate", "duplicate samples dropped (same sequence, stamp not advancing)"},
    {"dropped_late", "late samples dropped (sequence behind a sample already used, e.g. two swapped)"},
    {"sequence_restarts", "sequence restarts (samples kept)"},
    {"samples_missing", "sample periods without a sample (gaps; TDORC extrapolates its drift line across them)"},
    {"resets_on_gap", "filter resets after a gap longer than max_sample_gap_s (drift window refilled)"},
    {"dropped_nonfinite", "messages with non-finite values dropped"},
    {"dropped_wrong_whisker", "messages of an unknown or another whisker dropped"},
};

}  // namespace

void Warnings::add(const std::string& kind, uint64_t count, const std::string& message) {
  if (count == 0) return;
  entries_.push_back({kind, count, message});
}

void Warnings::add_bag_metadata(const std::string& bag, const tactile_bag::Reader& reader) {
  if (reader.metadata_complete()) return;
  // Data lost (damaged chunks skipped, a truncated tail): counted by the chunks skipped
  // (1 for a tail); a damaged bag with nothing recovered never gets here (the Reader
  // refuses it). Otherwise only metadata.yaml was missing, stale or unreadable.
  if (reader.damaged()) {
    add("bag_damaged", std::max<uint64_t>(reader.chunks_skipped(), 1),
        bag + ": damaged bag, using what was recovered: " + reader.recovery_note());
    return;
  }
  add("metadata_rebuilt", 1, bag + ": " + reader.recovery_note());
}

void Warnings::add_node_counters(const std::vector<NodeReport>& reports) {
  // counter -> (sum, "node: n, ...") in first-seen order
  std::vector<std::string> order;
  std::map<std::string, std::pair<uint64_t, std::string>> acc;
  for (const auto& r : reports) {
    for (const auto& [name, n] : r.counters) {
      if (n == 0) continue;
      bool listed = false;
      for (const auto& k : kKinds) listed = listed || name == k.counter;
      const bool tdorc = r.name.find("tdorc_filter") != std::string::npos;
      if ((tdorc && name == "dropped_out_of_order") || !(listed || name.rfind("dropped_", 0) == 0)) continue;
      if (name == "samples_missing" && r.name.find("whisker_driver") == std::string::npos) continue;
      auto [it, fresh] = acc.try_emplace(name, 0, "");
      if (fresh) order.push_back(name);
      it->second.first += n;
      it->second.second += (it->second.second.empty() ? "" : ", ") + r.name + ": " + std::to_string(n);
    }
  }
  for (const auto& name : order) {
    std::string text = name;
    for (const auto& k : kKinds) {
      if (name == k.counter) text = k.text;
    }
    const auto& [count, who] = acc[name];
    add(name, count, std::to_string(count) + " " + text + " (" + who + ")");
  }
}

nlohmann::json Warnings::to_json() const {
  nlohmann::json j = nlohmann::json::array();
  for (const auto& e : entries_) j.push_back({{"kind", e.kind}, {"count", e.count}, {"message", e.message}});
  return j;
}

void Warnings::print(const std::string& command) const {
  for (const auto& e : entries_) std::fprintf(stderr, "tactile %s: warning: %s\n", command.c_str(), e.message.c_str());
  std::fflush(stderr);
}

}  // namespace tactile_cli
