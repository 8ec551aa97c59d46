#include "tactile_common/parameters.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <tuple>

namespace tactile_common {

namespace {

struct TypeNamer {
  std::string operator()(bool) const { return "bool"; }
  std::string operator()(int64_t) const { return "integer"; }
  std::string operator()(double) const { return "double"; }
  std::string operator()(const std::string&) const { return "string"; }
  std::string operator()(const std::vector<bool>&) const { return "bool array"; }
  std::string operator()(const std::vector<int64_t>&) const { return "integer array"; }
  std::string operator()(const std::vector<double>&) const { return "double array"; }
  std::string operator()(const std::vector<std::string>&) const { return "string array"; }
};

// Is `incoming` acceptable where `declared` is the default's type? Integers are
// accepted for doubles (YAML writes 1 for 1.0), and an empty array for any array.
bool compatible(const ParamValue& declared, const ParamValue& incoming) {
  if (declared.index() == incoming.index()) return true;
  if (std::holds_alternative<double>(declared) && std::holds_alternative<int64_t>(incoming)) {
    return true;
  }
  if (std::holds_alternative<std::vector<double>>(declared) &&
      std::holds_alternative<std::vector<int64_t>>(incoming)) {
    return true;
  }
  return false;
}

ParamValue coerce(const ParamValue& declared, const ParamValue& incoming) {
  if (std::holds_alternative<double>(declared) && std::holds_alternative<int64_t>(incoming)) {
    return static_cast<double>(std::get<int64_t>(incoming));
  }
  if (std::holds_alternative<std::vector<double>>(declared) &&
      std::holds_alternative<std::vector<int64_t>>(incoming)) {
    const auto& in = std::get<std::vector<int64_t>>(incoming);
    return std::vector<double>(in.begin(), in.end());
  }
  return incoming;
}

// Scalar YAML -> ParamValue, by the YAML 1.2 core schema as ROS 2 reads it:
// true/false, integers, floats, everything else a string.
ParamValue scalar_value(const YAML::Node& n) {
  const std::string& s = n.Scalar();
  if (n.Tag() == "!") return s;  // quoted: always a string
  if (s == "true" || s == "True" || s == "TRUE") return true;
  if (s == "false" || s == "False" || s == "FALSE") return false;
  {
    std::istringstream is(s);
    long long v = 0;
    is >> v;
    if (!is.fail() && is.eof()) return static_cast<int64_t>(v);
  }
  {
    const std::string lower = [&] {
      std::string t = s;
      for (auto& c : t) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      return t;
    }();
    if (lower == ".nan") return std::nan("");
    if (lower == ".inf" || lower == "+.inf") return HUGE_VAL;
    if (lower == "-.inf") return -HUGE_VAL;
    std::istringstream is(s);
    double v = 0;
    is >> v;
    if (!is.fail() && is.eof()) return v;
  }
  return s;
}

ParamValue yaml_value(const YAML::Node& n, const std::string& where) {
  if (n.IsScalar()) return scalar_value(n);
  if (n.IsSequence()) {
    if (n.size() == 0) return std::vector<double>{};
    std::vector<ParamValue> items;
    for (const auto& item : n) {
      if (!item.IsScalar()) throw ParamError(where + ": arrays must hold scalars");
      items.push_back(scalar_value(item));
    }
    bool all_bool = true, all_int = true, all_num = true, all_str = true;
    for (const auto& v : items) {
      all_bool &= std::holds_alternative<bool>(v);
      all_int &= std::holds_alternative<int64_t>(v);
      all_num &= std::holds_alternative<int64_t>(v) || std::holds_alternative<double>(v);
      all_str &= std::holds_alternative<std::string>(v);
    }
    if (all_bool) {
      std::vector<bool> out;
      for (const auto& v : items) out.push_back(std::get<bool>(v));
      return out;
    }
    if (all_int) {
      std::vector<int64_t> out;
      for (const auto& v : items) out.push_back(std::get<int64_t>(v));
      return out;
    }
    if (all_num) {
      std::vector<double> out;
      for (const auto& v : items) {
        out.push_back(std::holds_alternative<double>(v) ? std::get<double>(v)
                                                        : static_cast<double>(std::get<int64_t>(v)));
      }
      return out;
    }
    if (all_str) {
      std::vector<std::string> out;
      for (const auto& v : items) out.push_back(std::get<std::string>(v));
      return out;
    }
    throw ParamError(where + ": array mixes types");
  }
  if (n.IsNull()) throw ParamError(where + ": has no value");
  throw ParamError(where + ": unsupported YAML node");
}

/// A map key as text: a key that is itself a map or list (YAML's `? [a, b]`) is a ParamError,
/// not a yaml-cpp conversion exception escaping the loader (found by fuzz_scenario).
std::string key_text(const YAML::Node& key, const std::string& where) {
  if (!key.IsScalar()) throw ParamError(where + ": a key must be a plain name, not a map or list");
  return key.Scalar();
}

void flatten(const YAML::Node& map, const std::string& prefix, const std::string& where,
             ParamMap& out) {
  for (const auto& kv : map) {
    const std::string key = prefix + key_text(kv.first, where + (prefix.empty() ? "" : "." + prefix.substr(0, prefix.size() - 1)));
    const std::string here = where + "." + key;
    if (kv.second.IsMap()) {
      flatten(kv.second, key + ".", where, out);
    } else {
      out.set(key, yaml_value(kv.second, here));
    }
  }
}

std::vector<std::string> split_tokens(const std::string& name) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : name) {
    if (c == '/') {
      if (!cur.empty()) out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (!cur.empty()) out.push_back(cur);
  return out;
}

std::string fully_qualified(const std::string& name) {
  return name.empty() || name.front() != '/' ? "/" + name : name;
}

// Glob match of name tokens: '*' one token, '**' zero or more tokens.
bool tokens_match(const std::vector<std::string>& pat, size_t i, const std::vector<std::string>& name,
                  size_t j) {
  if (i == pat.size()) return j == name.size();
  if (pat[i] == "**") {
    for (size_t k = j; k <= name.size(); ++k) {
      if (tokens_match(pat, i + 1, name, k)) return true;
    }
    return false;
  }
  if (j == name.size()) return false;
  return (pat[i] == "*" || pat[i] == name[j]) && tokens_match(pat, i + 1, name, j + 1);
}

bool name_matches(const std::string& pattern, const std::string& fqn) {
  return tokens_match(split_tokens(pattern), 0, split_tokens(fqn), 0);
}

// 0: "/**"; 1: other patterns with wildcards; 2: an exact name.
int specificity(const std::string& name) {
  const auto tokens = split_tokens(name);
  if (tokens.size() == 1 && tokens[0] == "**") return 0;
  for (const auto& t : tokens) {
    if (t == "*" || t == "**") return 1;
  }
  return 2;
}

}  // namespace

std::string type_name(const ParamValue& value) { return std::visit(TypeNamer{}, value); }

ParamMap::ParamMap(std::string node, std::string source)
    : node_(std::move(node)), source_(std::move(source)) {}

void ParamMap::set(const std::string& key, ParamValue value) { values_[key] = std::move(value); }

void ParamMap::set(const std::string& key, ParamValue value, ParamInfo info) {
  if (info.range && !(info.range->lo <= info.range->hi)) {
    throw std::logic_error("ParamMap::set(\"" + key + "\"): empty range " + info.range->text());
  }
  values_[key] = std::move(value);
  info_[key] = std::move(info);
}

const ParamInfo* ParamMap::info(const std::string& key) const {
  const auto it = info_.find(key);
  return it == info_.end() ? nullptr : &it->second;
}

namespace {

std::string bound_text(double v) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  // An integer-valued bound (a count, INT_MAX, an integer key's get_int() range) prints as
  // the integer: the stream's six significant digits would show INT_MAX as "2.14748e+09",
  // a bound no integer has. [-2^63, 2^63) is what int64_t holds (an IntegerRange); a larger
  // one (INT64_MAX rounds to 2^63 as a double) prints with the 17 digits that read it back.
  if (v == std::trunc(v)) {
    if (v >= -0x1p63 && v < 0x1p63) return std::to_string(static_cast<int64_t>(v));
    std::ostringstream out;
    out << std::setprecision(std::numeric_limits<double>::max_digits10) << v;
    return out.str();
  }
  std::ostringstream out;
  out << v;
  return out.str();
}

}  // namespace

const char* to_string(ParamSource s) {
  switch (s) {
    case ParamSource::kPaper: return "paper";
    case ParamSource::kChoice: return "choice";
    case ParamSource::kTuned: return "tuned";
    case ParamSource::kUnset: break;
  }
  return "unset";
}

std::string ParamOrigin::text() const {
  if (kind == ParamSource::kUnset) return "";
  return std::string(to_string(kind)) + (evidence.empty() ? "" : ": " + evidence);
}

std::string ParamRange::text() const {
  return std::string(open_lo ? "(" : "[") + bound_text(lo) + ", " + bound_text(hi) + (open_hi ? ")" : "]");
}

bool ParamRange::contains(double v) const {
  return (open_lo ? v > lo : v >= lo) && (open_hi ? v < hi : v <= hi);
}

bool ParamMap::has(const std::string& key) const { return values_.count(key) != 0; }

const std::string& ParamMap::origin(const std::string& key) const {
  auto it = origin_.find(key);
  return it == origin_.end() ? source_ : it->second;
}

ParamError ParamMap::error(const std::string& key, const std::string& reason) const {
  return ParamError(origin(key) + ": " + node_ + ".ros__parameters." + key + ": " + reason);
}

ParamError ParamMap::error_from(const std::invalid_argument& e) const {
  const std::string what = e.what();
  const auto dot = what.find('.');
  const auto end = what.find_first_of(":[", dot);
  const auto colon = what.find(": ");
  return error(what.substr(dot + 1, end - dot - 1), colon == std::string::npos ? what : what.substr(colon + 2));
}

const ParamValue& ParamMap::at(const std::string& key) const {
  auto it = values_.find(key);
  if (it == values_.end()) throw error(key, "missing (not declared by the node)");
  return it->second;
}

void ParamMap::wrong_type(const std::string& key, const char* wanted) const {
  throw error(key, std::string("expected ") + wanted + ", got " + type_name(at(key)));
}

bool ParamMap::get_bool(const std::string& key) const {
  const auto& v = at(key);
  if (auto p = std::get_if<bool>(&v)) return *p;
  wrong_type(key, "bool");
}

int64_t ParamMap::raw_int(const std::string& key) const {
  const auto& v = at(key);
  if (auto p = std::get_if<int64_t>(&v)) return *p;
  wrong_type(key, "integer");
}

int64_t ParamMap::get_int(const std::string& key) const { return raw_int(key); }

void ParamMap::out_of_range(const std::string& key, const std::string& lo, const std::string& hi,
                            int64_t value) const {
  throw error(key, "must be in [" + lo + ", " + hi + "], got " + std::to_string(value));
}

double ParamMap::get_double(const std::string& key) const {
  const auto& v = at(key);
  if (auto p = std::get_if<double>(&v)) return *p;
  if (auto p = std::get_if<int64_t>(&v)) return static_cast<double>(*p);
  wrong_type(key, "double");
}

std::string ParamMap::get_string(const std::string& key) const {
  const auto& v = at(key);
  if (auto p = std::get_if<std::string>(&v)) return *p;
  wrong_type(key, "string");
}

std::vector<bool> ParamMap::get_bool_array(const std::string& key) const {
  const auto& v = at(key);
  if (auto p = std::get_if<std::vector<bool>>(&v)) return *p;
  wrong_type(key, "bool array");
}

std::vector<int64_t> ParamMap::get_int_array(const std::string& key) const {
  const auto& v = at(key);
  if (auto p = std::get_if<std::vector<int64_t>>(&v)) return *p;
  wrong_type(key, "integer array");
}

std::vector<double> ParamMap::get_double_array(const std::string& key) const {
  const auto& v = at(key);
  if (auto p = std::get_if<std::vector<double>>(&v)) return *p;
  if (auto p = std::get_if<std::vector<int64_t>>(&v)) return {p->begin(), p->end()};
  wrong_type(key, "double array");
}

std::vector<std::string> ParamMap::get_string_array(const std::string& key) const {
  const auto& v = at(key);
  if (auto p = std::get_if<std::vector<std::string>>(&v)) return *p;
  wrong_type(key, "string array");
}

void ParamMap::merge_from(const ParamMap& other) {
  for (const auto& [key, value] : other.values()) {
    auto it = values_.find(key);
    if (it == values_.end()) {
      throw other.error(key, "unknown parameter of node '" + node_ + "'");
    }
    // An empty YAML list is read as an empty double array; accept it for any array.
    const bool empty_array = std::holds_alternative<std::vector<double>>(value) &&
                             std::get<std::vector<double>>(value).empty();
    const bool declared_array = !(std::holds_alternative<bool>(it->second) ||
                                  std::holds_alternative<int64_t>(it->second) ||
                                  std::holds_alternative<double>(it->second) ||
                                  std::holds_alternative<std::string>(it->second));
    if (empty_array && declared_array) {
      it->second = std::visit([](const auto& d) -> ParamValue { return std::decay_t<decltype(d)>{}; },
                              it->second);
      origin_[key] = other.source();
      continue;
    }
    if (!compatible(it->second, value)) {
      throw other.error(key, "expected " + type_name(it->second) + ", got " + type_name(value));
    }
    it->second = coerce(it->second, value);
    origin_[key] = other.source();
  }
}

namespace {

// load_node_parameters_from_string, and with require_section false the profile overlay
// (load_profile_overlay): a file without a section naming the node is no error then.
ParamMap load_sections(const std::string& yaml, const std::string& source, const std::string& node_name,
                       const ParamMap& defaults, bool require_section) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml);
  } catch (const YAML::Exception& e) {
    throw ParamError(source + ": YAML syntax error at line " + std::to_string(e.mark.line + 1) +
                     ", column " + std::to_string(e.mark.column + 1) + ": " + e.msg);
  }
  const std::string fqn = fully_qualified(node_name);
  const std::string base = fqn.substr(fqn.rfind('/') + 1);
  ParamMap result(base, source);
  for (const auto& [k, v] : defaults.values()) result.set(k, v);
  // A node's parameter file must say something about the node: an empty file
  // (or one of comments only) or one without the node's section would
  // otherwise run the node on its compiled defaults without a word (issue 32:
  // a tdorc_filter.yaml emptied or with a misspelt section turned the
  // three-baffle course from a success into a collision).
  const std::string expected = "expected a '" + base + ":' (or '/**/" + base + ":') section with 'ros__parameters'";
  if (root.IsNull()) throw ParamError(source + ": empty parameter file: " + expected);
  if (!root.IsMap()) throw ParamError(source + ": top level must be a map of node names");

  // Sections apply when their key matches the node's fully qualified name as
  // in ROS 2 parameter files: "/ns/node" (leading '/' optional), with '*'
  // matching one name token and '**' any number of tokens ("/**" = every
  // node, "/**/tdorc_filter" = tdorc_filter in any namespace). Less specific
  // sections are applied first, so an exact name wins over a wildcard.
  std::vector<std::tuple<int, size_t, std::string, YAML::Node>> sections;
  size_t order = 0;
  bool named = false;  // a section for this node, not only the catch-all '/**'
  std::string found;
  for (const auto& kv : root) {
    const std::string name = key_text(kv.first, source);
    ++order;
    found += (found.empty() ? "" : ", ") + name;
    if (!name_matches(fully_qualified(name), fqn)) continue;
    named = named || specificity(name) > 0;
    if (!kv.second.IsMap() || !kv.second["ros__parameters"]) {
      throw ParamError(source + ": " + name + ": expected a map with key 'ros__parameters'");
    }
    sections.emplace_back(specificity(name), order, name, kv.second["ros__parameters"]);
  }
  std::sort(sections.begin(), sections.end(), [](const auto& a, const auto& b) {
    return std::tie(std::get<0>(a), std::get<1>(a)) < std::tie(std::get<0>(b), std::get<1>(b));
  });
  if (!named && require_section) {
    throw ParamError(source + ": no section for node " + fqn + ": " + expected + "; sections in the file: " +
                     (found.empty() ? "none" : found));
  }
  for (const auto& [spec, ord, name, params] : sections) {
    (void)ord;
    if (params.IsNull()) continue;
    if (!params.IsMap()) throw ParamError(source + ": " + name + ".ros__parameters: must be a map");
    ParamMap overlay(base, source);
    flatten(params, "", source + ": " + name + ".ros__parameters", overlay);
    if (name == "/**" || name == "**") {
      // The catch-all section may carry parameters of other nodes: apply only
      // the ones this node declares (ROS 2 ignores undeclared ones too).
      ParamMap known(base, source);
      for (const auto& [k, v] : overlay.values()) {
        if (result.has(k)) known.set(k, v);
      }
      result.merge_from(known);
    } else {
      result.merge_from(overlay);
    }
  }
  return result;
}

}  // namespace

ParamMap load_node_parameters_from_string(const std::string& yaml, const std::string& source,
                                          const std::string& node_name, const ParamMap& defaults) {
  return load_sections(yaml, source, node_name, defaults, true);
}

namespace {

// The text of a parameter file or profile: missing, a directory (which std::ifstream opens
// and reads as empty) or another non-file is an error naming the path, `what` it is and the
// reason, never an empty text.
std::string read_parameter_text(const std::string& path, const std::string& what) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(status)) throw ParamError(path + ": " + what + " missing (no such file)");
  if (!std::filesystem::is_regular_file(status)) {
    throw ParamError(path + ": " + what + " is not a file (" +
                     (std::filesystem::is_directory(status) ? "a directory" : "not a regular file") + ")");
  }
  std::ifstream in(path);
  if (!in) throw ParamError(path + ": cannot open " + what);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

ParamMap load_node_parameters(const std::string& path, const std::string& node_name,
                              const ParamMap& defaults) {
  const std::string text = read_parameter_text(path, "parameter file of node " + fully_qualified(node_name));
  return load_node_parameters_from_string(text, path, node_name, defaults);
}

ParamMap load_profile_overlay(const std::string& path, const std::string& node_name, const ParamMap& params) {
  const std::string text = read_parameter_text(path, "parameter profile");
  const ParamMap merged = load_sections(text, path, node_name, params, false);
  const std::string fqn = fully_qualified(node_name);
  ParamMap overlay(fqn.substr(fqn.rfind('/') + 1), path);
  // The keys the profile changes (a key it sets to the value the node has already changes nothing).
  for (const auto& [k, v] : merged.values()) {
    if (!(params.values().at(k) == v)) overlay.set(k, v);
  }
  return overlay;
}

}  // namespace tactile_common
