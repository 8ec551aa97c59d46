// Distro layouts and RIHS01 type hashes (REP-2011; the algorithm of rosidl's type
// description generator: sha256 over the JSON of the TypeDescription message without
// default values, referenced type descriptions sorted by type name).
#include "tactile_bag/distro.hpp"

#include <openssl/evp.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <set>
#include <sstream>

#include "tactile_bag/bag.hpp"

namespace tactile_bag {
namespace {

const std::string kSeparator(80, '=');

struct FieldDesc {
  std::string name;
  int type_id = 0;
  uint64_t capacity = 0, string_capacity = 0;
  std::string nested;
};

// FieldType ids of type_description_interfaces/msg/FieldType.
int base_type_id(const std::string& base) {
  static const std::map<std::string, int> ids = {
      {"int8", 2}, {"uint8", 3}, {"char", 3}, {"int16", 4}, {"uint16", 5}, {"int32", 6},
      {"uint32", 7}, {"int64", 8}, {"uint64", 9}, {"float32", 10}, {"float64", 11},
      {"bool", 15}, {"byte", 16}, {"string", 17}, {"wstring", 18}};
  auto it = ids.find(base);
  return it == ids.end() ? 0 : it->second;
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

std::string full_name(std::string t, const std::string& own_pkg) {
  // "pkg/Type", "pkg/msg/Type" or "Type" (same package) -> "pkg/msg/Type"
  const auto first = t.find('/');
  if (first == std::string::npos) return own_pkg + "/msg/" + t;
  if (t.find('/', first + 1) != std::string::npos) return t;
  return t.substr(0, first) + "/msg/" + t.substr(first + 1);
}

// Sections of a full definition: type name -> text.
std::map<std::string, std::string> split_sections(const std::string& type_name,
                                                  const std::string& definition) {
  std::map<std::string, std::string> out;
  std::string current = type_name, text;
  std::istringstream in(definition);
  std::string line;
  bool expect_msg = false;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line == kSeparator) {
      out[current] = text;
      text.clear();
      expect_msg = true;
      continue;
    }
    if (expect_msg) {
      expect_msg = false;
      if (line.rfind("MSG: ", 0) == 0) {
        current = full_name(trim(line.substr(5)), "");
        continue;
      }
    }
    text += line + "\n";
  }
  out[current] = text;
  return out;
}

std::vector<FieldDesc> parse_fields(const std::string& type_name, const std::string& text) {
  const std::string pkg = type_name.substr(0, type_name.find('/'));
  std::vector<FieldDesc> fields;
  std::istringstream in(text);
  std::string raw;
  int lineno = 0;
  while (std::getline(in, raw)) {
    ++lineno;
    std::string line = raw;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line = line.substr(0, hash);
    line = trim(line);
    if (line.empty()) continue;
    std::istringstream ls(line);
    std::string type, name;
    ls >> type >> name;
    const auto where = [&] {
      return type_name + " definition line " + std::to_string(lineno) + " '" + trim(raw) + "'";
    };
    if (name.empty()) throw BagError(where() + ": expected '<type> <name>'");
    if (name.find('=') != std::string::npos) continue;  // constant NAME=value
    {
      std::string rest;
      std::getline(ls, rest);
      rest = trim(rest);
      if (!rest.empty() && rest[0] == '=') continue;   // constant NAME = value
    }
    FieldDesc f;
    f.name = name;
    // array suffix
    int array_offset = 0;
    const auto br = type.find('[');
    if (br != std::string::npos) {
      const auto close = type.find(']', br);
      if (close == std::string::npos) throw BagError(where() + ": unterminated array");
      std::string inner = type.substr(br + 1, close - br - 1);
      type = type.substr(0, br);
      if (inner.empty()) {
        array_offset = 144;
      } else if (inner.rfind("<=", 0) == 0) {
        array_offset = 96;
        f.capacity = std::stoull(inner.substr(2));
      } else {
        array_offset = 48;
        f.capacity = std::stoull(inner);
      }
    }
    const auto le = type.find("<=");
    if (le != std::string::npos) {
      f.string_capacity = std::stoull(type.substr(le + 2));
      type = type.substr(0, le);
    }
    int id = base_type_id(type);
    if (id == 17 && f.string_capacity > 0) id = 21;
    if (id == 18 && f.string_capacity > 0) id = 22;
    if (id == 0) {
      id = 1;
      f.nested = full_name(type, pkg);
    }
    f.type_id = id + array_offset;
    fields.push_back(f);
  }
  if (fields.empty()) {  // rosidl gives empty structures one uint8 member
    FieldDesc f;
    f.name = "structure_needs_at_least_one_member";
    f.type_id = 3;
    fields.push_back(f);
  }
  return fields;
}

void append_type(std::string& out, const std::string& name, const std::vector<FieldDesc>& fields) {
  out += "{\"type_name\": \"" + name + "\", \"fields\": [";
  for (size_t i = 0; i < fields.size(); ++i) {
    const auto& f = fields[i];
    if (i > 0) out += ", ";
    out += "{\"name\": \"" + f.name + "\", \"type\": {\"type_id\": " + std::to_string(f.type_id) +
           ", \"capacity\": " + std::to_string(f.capacity) +
           ", \"string_capacity\": " + std::to_string(f.string_capacity) +
           ", \"nested_type_name\": \"" + f.nested + "\"}}";
  }
  out += "]}";
}

}  // namespace

void check_distro(const std::string& distro, const std::string& context) {
  const auto& d = known_distros();
  if (std::find(d.begin(), d.end(), distro) == d.end()) {
    throw BagError(context + ": unknown ROS 2 distro '" + distro + "' (humble, iron, jazzy, kilted)");
  }
}

int metadata_version_for_distro(const std::string& distro) {
  if (distro == "humble") return 5;
  if (distro == "iron") return 8;
  return 9;
}

bool distro_has_type_hashes(const std::string& distro) { return distro != "humble"; }

bool distro_range_without_variance(const std::string& distro) {
  return distro == "humble" || distro == "iron";
}

std::string type_description_json(const std::string& type_name, const std::string& definition) {
  const auto sections = split_sections(type_name, definition);
  std::map<std::string, std::vector<FieldDesc>> parsed;
  std::vector<std::string> queue = {type_name};
  std::set<std::string> referenced;
  while (!queue.empty()) {
    const std::string t = queue.back();
    queue.pop_back();
    if (parsed.count(t) != 0) continue;
    auto it = sections.find(t);
    if (it == sections.end()) {
      throw BagError(type_name + " definition: no section for nested type '" + t +
                     "' (the definition text must include every dependency)");
    }
    parsed[t] = parse_fields(t, it->second);
    for (const auto& f : parsed[t]) {
      if (!f.nested.empty()) {
        referenced.insert(f.nested);
        queue.push_back(f.nested);
      }
    }
  }
  std::string out = "{\"type_description\": ";
  append_type(out, type_name, parsed[type_name]);
  out += ", \"referenced_type_descriptions\": [";
  bool first = true;
  for (const auto& r : referenced) {  // std::set: sorted by name
    if (!first) out += ", ";
    first = false;
    append_type(out, r, parsed[r]);
  }
  out += "]}";
  return out;
}

std::string rihs01_hash(const std::string& type_name, const std::string& definition) {
  const std::string json = type_description_json(type_name, definition);
  unsigned char md[EVP_MAX_MD_SIZE];
  unsigned int n = 0;
  if (EVP_Digest(json.data(), json.size(), md, &n, EVP_sha256(), nullptr) != 1 || n != 32) {
    throw BagError(type_name + ": sha256 failed");
  }
  static const char* hex = "0123456789abcdef";
  std::string out = "RIHS01_";
  for (unsigned int i = 0; i < n; ++i) {
    out += hex[md[i] >> 4];
    out += hex[md[i] & 15];
  }
  return out;
}

namespace {
// Apply `fn(line)` (keep the line?) to the lines of `of_type`'s section of the definition.
template <class Fn>
std::string map_lines(const std::string& definition, const std::string& top_type,
                      const std::string& of_type, Fn fn) {
  std::istringstream in(definition);
  std::string line, out;
  bool in_type = top_type == of_type, expect_msg = false;
  while (std::getline(in, line)) {
    bool keep = true;
    if (line == kSeparator) {
      in_type = false;
      expect_msg = true;
    } else if (expect_msg) {
      expect_msg = false;
      if (line.rfind("MSG: ", 0) == 0) in_type = full_name(trim(line.substr(5)), "") == of_type;
    } else if (in_type) {
      keep = fn(line);
    }
    if (keep) out += line + "\n";
  }
  if (!definition.empty() && definition.back() != '\n' && !out.empty()) out.pop_back();
  return out;
}

bool declares(const std::string& line, const std::string& field) {
  std::string l = line;
  const auto hash = l.find('#');
  if (hash != std::string::npos) l = l.substr(0, hash);
  std::istringstream ls(l);
  std::string type, name;
  ls >> type >> name;
  return name == field;
}
}  // namespace

std::string remove_field_from_definition(const std::string& definition, const std::string& top_type,
                                         const std::string& of_type, const std::string& field) {
  return map_lines(definition, top_type, of_type, [&](const std::string& line) { return !declares(line, field); });
}

bool definition_has_field(const std::string& definition, const std::string& top_type,
                          const std::string& of_type, const std::string& field, bool* found_type) {
  bool has = false, any = false;
  map_lines(definition, top_type, of_type, [&](const std::string& line) {
    any = true;
    if (declares(line, field)) has = true;
    return true;
  });
  if (found_type != nullptr) *found_type = any;
  return has;
}

size_t range_payload_size_without_variance(const uint8_t* data, size_t size) {
  // encapsulation(4) | header.stamp sec(4) nanosec(4) | frame_id len(4) + bytes |
  // radiation_type(1) | pad to 4 | field_of_view, min_range, max_range, range (4 each).
  // Alignment is relative to the end of the encapsulation header.
  if (size < 16) return 0;
  uint32_t len;
  std::memcpy(&len, data + 12, 4);
  if (data[1] == 0x00) {  // big-endian CDR
    len = __builtin_bswap32(len);
  }
  size_t pos = 16 - 4 + static_cast<size_t>(len);  // relative to the CDR body
  pos += 1;                                          // radiation_type
  pos = (pos + 3) & ~size_t{3};
  pos += 16;
  return 4 + pos <= size ? 4 + pos : 0;
}

}  // namespace tactile_bag
