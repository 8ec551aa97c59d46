// The output directory of a command (`--out DIR`), reused from one run to the next.
//
// A run of a command writes a record of the top-level entries it created,
// DIR/.tactile_outputs.json. The next run into the same DIR sets exactly those entries
// aside first (DIR/.tactile_previous/) and says so on stderr, so a rerun with fewer trials
// or environments leaves no stale trial_K/, runs/<name>/ or generated files beside its own.
// When the run ends, the previous outputs are deleted; if it wrote nothing (a bad scenario
// file, a bag that cannot be read) they are put back as they were. Entries no run recorded
// (the user's files, or a run killed before it wrote its record) are never touched: they are
// named on stderr and left as they are.
#pragma once

#include <set>
#include <string>

namespace tactile_cli {

class OutputDir {
 public:
  static constexpr const char* kRecord = ".tactile_outputs.json";
  static constexpr const char* kPrevious = ".tactile_previous";

  /// Creates `dir` if needed and sets aside what the previous run recorded. Throws
  /// std::runtime_error when `dir` exists and is not a directory, or an entry cannot be moved.
  OutputDir(std::string dir, std::string command);
  /// Records the entries created since the constructor (also when the run failed or was
  /// interrupted: what it left is its own) and deletes the previous outputs; if the run
  /// created nothing, puts the previous outputs and their record back instead.
  ~OutputDir();
  OutputDir(const OutputDir&) = delete;
  OutputDir& operator=(const OutputDir&) = delete;

  /// Entries of the previous run the constructor set aside (for tests and the note).
  const std::set<std::string>& replaced() const { return replaced_; }
  /// Entries present that no run recorded (left as they are).
  const std::set<std::string>& foreign() const { return foreign_; }
 private:
  void finish();
  std::string dir_, command_;
  std::set<std::string> before_, replaced_, foreign_;
};

}  // namespace tactile_cli
