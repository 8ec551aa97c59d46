#include "tactile_cli/output_dir.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace tactile_cli {

namespace fs = std::filesystem;

namespace {

std::set<std::string> entries(const fs::path& dir) {
  std::set<std::string> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name != OutputDir::kRecord && name != OutputDir::kPrevious) out.insert(name);
  }
  return out;
}

std::string joined(const std::set<std::string>& names, size_t most = 8) {
  std::string s;
  size_t k = 0;
  for (const auto& n : names) {
    if (k++ == most) return s + ", ... (" + std::to_string(names.size()) + " in all)";
    s += (s.empty() ? "" : ", ") + n;
  }
  return s;
}

}  // namespace

OutputDir::OutputDir(std::string dir, std::string command) : dir_(std::move(dir)), command_(std::move(command)) {
  const fs::path d(dir_);
  std::error_code ec;
  if (fs::exists(d, ec) && !fs::is_directory(d, ec)) {
    throw std::runtime_error(dir_ + ": exists and is not a directory (--out names a directory)");
  }
  fs::create_directories(d);
  std::set<std::string> recorded;
  const fs::path rec = d / kRecord;
  if (fs::exists(rec, ec)) {
    try {
      std::ifstream in(rec);
      const auto j = nlohmann::json::parse(in);
      for (const auto& e : j.at("entries")) {
        const std::string name = e.get<std::string>();
        // Only plain names of this directory: a record never reaches outside it.
        if (!name.empty() && name != "." && name != ".." && name.find('/') == std::string::npos) {
          recorded.insert(name);
        }
      }
    } catch (const std::exception& e) {
      std::fprintf(stderr, "tactile: note: %s: unreadable (%s); nothing removed\n", rec.string().c_str(), e.what());
      recorded.clear();
    }
  }
  const fs::path previous = d / kPrevious;
  fs::remove_all(previous, ec);  // left by a run that was killed: older than the record
  for (const auto& name : entries(d)) {
    if (!recorded.count(name)) continue;
    fs::create_directories(previous);
    fs::rename(d / name, previous / name, ec);
    if (ec) throw std::runtime_error((d / name).string() + ": cannot set the previous run's output aside: " + ec.message());
    replaced_.insert(name);
  }
  if (!replaced_.empty()) {
    std::fprintf(stderr, "tactile %s: replacing the previous run's outputs in %s (%s)\n", command_.c_str(),
                 dir_.c_str(), joined(replaced_).c_str());
  }
  before_ = entries(d);
  foreign_ = before_;
  if (!foreign_.empty()) {
    std::fprintf(stderr, "tactile %s: note: %s holds entries no tactile run recorded, left as they are: %s\n",
                 command_.c_str(), dir_.c_str(), joined(foreign_).c_str());
  }
}

void OutputDir::finish() {
  const fs::path d(dir_), previous = d / kPrevious;
  std::set<std::string> created;
  for (const auto& name : entries(d)) {
    if (!before_.count(name)) created.insert(name);
  }
  std::error_code ec;
  if (created.empty() && !replaced_.empty()) {
    // This run wrote nothing: the previous outputs stay the outputs of this directory.
    for (const auto& name : replaced_) fs::rename(previous / name, d / name, ec);
    fs::remove_all(previous, ec);
    std::fprintf(stderr, "tactile %s: nothing written; the previous outputs in %s are kept\n", command_.c_str(),
                 dir_.c_str());
    return;  // the previous record still lists them
  }
  fs::remove_all(previous, ec);
  nlohmann::json j;
  j["command"] = command_;
  j["entries"] = created;
  std::ofstream out(d / kRecord);
  out << j.dump(2) << "\n";
}

OutputDir::~OutputDir() {
  try {
    finish();
  } catch (...) {
    // A destructor must not throw; the next run then finds the entries foreign and keeps them.
  }
}

}  // namespace tactile_cli
