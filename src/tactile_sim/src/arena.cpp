#include "tactile_sim/arena.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <sstream>

namespace tactile_sim {

const std::vector<Material>& builtin_materials() {
  // Choices (the papers give no contact constants); see docs/physics.md.
  // Stiffness/damping keep a 44 g Crazyflie (f ~ 40 Hz) and a 1.12 kg
  // XPLORER stable at a 1 kHz physics step; penetration at 1 N is 0.3-0.5 mm
  // for hard surfaces, 3 mm on textile.
  static const std::vector<Material> kBuiltin = {
      // name, mu, noise scale, k [N/m], c [N s/m]
      {"rigid", 0.5, 1.0, 3000.0, 6.0},    // whiteboard / wooden board / acrylic panel
      {"glass", 0.25, 0.8, 2000.0, 5.0},   // glass or acrylic baffle: smooth, slightly compliant stand
      {"textile", 0.9, 2.0, 300.0, 3.0},   // soft textile (000 Fig. 6c): soft, high friction, rough
  };
  return kBuiltin;
}

Arena::Arena() : materials_(builtin_materials()) {}

int Arena::add_material(const Material& m) {
  const int existing = find_material(m.name);
  if (existing >= 0) {
    materials_[existing] = m;
    return existing;
  }
  materials_.push_back(m);
  return static_cast<int>(materials_.size()) - 1;
}

int Arena::find_material(const std::string& name) const {
  for (size_t i = 0; i < materials_.size(); ++i) {
    if (materials_[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

int Arena::add_obstacle(const std::string& name) {
  obstacles_.push_back(name);
  return static_cast<int>(obstacles_.size()) - 1;
}

namespace {
void update_bbox(Wall& w) {
  w.lo = w.a.cwiseMin(w.b);
  w.hi = w.a.cwiseMax(w.b);
}
}  // namespace

void Arena::add_wall(const Vec2& a, const Vec2& b, int material, int obstacle_id) {
  if (material < 0 || material >= static_cast<int>(materials_.size())) {
    throw std::invalid_argument("Arena::add_wall: material index out of range");
  }
  Wall w;
  w.a = a;
  w.b = b;
  w.material = material;
  w.obstacle_id = obstacle_id;
  update_bbox(w);
  walls_.push_back(w);
}

void Arena::add_cylinder(const Vec2& center, double radius, int material, int obstacle_id) {
  if (material < 0 || material >= static_cast<int>(materials_.size())) {
    throw std::invalid_argument("Arena::add_cylinder: material index out of range");
  }
  if (!(radius > 0.0)) throw std::invalid_argument("Arena::add_cylinder: radius must be > 0");
  cylinders_.push_back({center, radius, material, obstacle_id});
}

void Arena::transform(double dx, double dy, double yaw_rad) {
  const Eigen::Rotation2Dd rot(yaw_rad);
  const Vec2 t(dx, dy);
  for (Wall& w : walls_) {
    w.a = rot * w.a + t;
    w.b = rot * w.b + t;
    update_bbox(w);
  }
  for (Cylinder& c : cylinders_) c.center = rot * c.center + t;
}

Hit Arena::wall_hit(const Wall& w, const Vec2& p) {
  Hit h;
  h.hit = true;
  h.point = geom::closest_point_on_segment(p, w.a, w.b);
  const Vec2 d = p - h.point;
  h.distance = d.norm();
  if (h.distance > 1e-12) {
    h.normal = d / h.distance;
  } else {
    const Vec2 s = (w.b - w.a).normalized();
    h.normal = Vec2(-s.y(), s.x());  // on the wall: its left normal
  }
  h.material = w.material;
  h.obstacle_id = w.obstacle_id;
  return h;
}

Hit Arena::cylinder_hit(const Cylinder& c, const Vec2& p) {
  Hit h;
  h.hit = true;
  const Vec2 v = p - c.center;
  const double n = v.norm();
  h.normal = n > 1e-12 ? Vec2(v / n) : Vec2(1.0, 0.0);
  h.distance = n - c.radius;
  h.point = c.center + c.radius * h.normal;
  h.material = c.material;
  h.obstacle_id = c.obstacle_id;
  return h;
}

Hit Arena::closest(const Vec2& p, double max_dist) const {
  Hit best;
  for_each_within(p, max_dist, [&](const Hit& h) {
    if (h.distance < best.distance) best = h;
  });
  if (!best.hit) best = Hit{};
  return best;
}

Hit Arena::raycast(const Vec2& origin, const Vec2& dir, double max_range) const {
  Hit best;
  if (!(max_range >= 0.0)) return best;
  const Vec2 end = origin + max_range * dir;
  const Vec2 lo = origin.cwiseMin(end), hi = origin.cwiseMax(end);
  for (const Wall& w : walls_) {
    if (hi.x() < w.lo.x() || lo.x() > w.hi.x() || hi.y() < w.lo.y() || lo.y() > w.hi.y()) continue;
    const geom::RayHit r = geom::ray_segment(origin, dir, w.a, w.b, max_range);
    if (!r.hit || r.t >= best.distance) continue;
    best.hit = true;
    best.distance = r.t;
    best.point = r.point;
    const Vec2 s = (w.b - w.a).normalized();
    Vec2 n(-s.y(), s.x());
    if (n.dot(dir) > 0.0) n = -n;  // face the ray origin
    best.normal = n;
    best.material = w.material;
    best.obstacle_id = w.obstacle_id;
  }
  for (const Cylinder& c : cylinders_) {
    const geom::RayHit r = geom::ray_circle(origin, dir, c.center, c.radius, max_range);
    if (!r.hit || r.t >= best.distance) continue;
    best.hit = true;
    best.distance = r.t;
    best.point = r.point;
    const Vec2 v = r.point - c.center;
    const double n = v.norm();
    best.normal = n > 1e-12 ? Vec2(v / n) : Vec2(-dir);
    best.material = c.material;
    best.obstacle_id = c.obstacle_id;
  }
  return best;
}

Hit Arena::first_hit(const Vec2& a, const Vec2& b) const {
  const Vec2 d = b - a;
  const double len = d.norm();
  if (!(len > 0.0)) return Hit{};
  return raycast(a, d / len, len);
}

Bounds Arena::bounds() const {
  Bounds b;
  auto add = [&](const Vec2& lo, const Vec2& hi) {
    if (b.empty) {
      b.min = lo;
      b.max = hi;
      b.empty = false;
    } else {
      b.min = b.min.cwiseMin(lo);
      b.max = b.max.cwiseMax(hi);
    }
  };
  for (const Wall& w : walls_) add(w.lo, w.hi);
  for (const Cylinder& c : cylinders_) {
    add(c.center - Vec2(c.radius, c.radius), c.center + Vec2(c.radius, c.radius));
  }
  return b;
}

// ---------------------------------------------------------------------------
// YAML loading and validation.

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kMinLength = 1e-6;  // [m] shorter segments count as zero-length

std::string fmt(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

class Parser {
 public:
  Parser(std::string source, std::string prefix)
      : source_(std::move(source)), prefix_(std::move(prefix)) {}

  [[noreturn]] void fail(const std::string& path, const std::string& reason) const {
    std::string where = prefix_ + path;
    if (!where.empty() && where.back() == '.') where.pop_back();
    throw ArenaError(source_ + ": " + (where.empty() ? std::string("<root>") : where) + ": " +
                     reason);
  }

  void require_map(const YAML::Node& n, const std::string& path) const {
    if (!n.IsMap()) fail(path, "expected a map");
  }

  void check_keys(const YAML::Node& n, const std::string& path,
                  std::initializer_list<const char*> allowed) const {
    require_map(n, path);
    for (const auto& kv : n) {
      if (!kv.first.IsScalar()) fail(path, "keys must be strings");
      const std::string key = kv.first.Scalar();
      bool ok = false;
      for (const char* a : allowed) ok = ok || key == a;
      if (!ok) {
        std::string list;
        for (const char* a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
        fail(join(path, key), "unknown key (allowed: " + list + ")");
      }
    }
  }

  static std::string join(const std::string& path, const std::string& key) {
    return path.empty() ? key : path + "." + key;
  }
  static std::string index(const std::string& path, size_t i) {
    return path + "[" + std::to_string(i) + "]";
  }

  double number(const YAML::Node& n, const std::string& path) const {
    if (!n.IsScalar()) fail(path, "expected a number");
    double v = 0.0;
    try {
      v = n.as<double>();
    } catch (const YAML::Exception&) {
      fail(path, "expected a number, got '" + n.Scalar() + "'");
    }
    if (!std::isfinite(v)) fail(path, "must be finite, got '" + n.Scalar() + "'");
    return v;
  }

  double number_or(const YAML::Node& map, const char* key, const std::string& path,
                   double def) const {
    const YAML::Node n = map[key];
    return n ? number(n, join(path, key)) : def;
  }

  double positive(const YAML::Node& n, const std::string& path) const {
    const double v = number(n, path);
    if (!(v > 0.0)) fail(path, "must be > 0, got " + fmt(v));
    return v;
  }

  double non_negative(const YAML::Node& n, const std::string& path) const {
    const double v = number(n, path);
    if (v < 0.0) fail(path, "must be >= 0, got " + fmt(v));
    return v;
  }

  Vec2 vec2(const YAML::Node& n, const std::string& path) const {
    if (!n.IsSequence() || n.size() != 2) fail(path, "expected [x, y]");
    return Vec2(number(n[0], index(path, 0)), number(n[1], index(path, 1)));
  }

  Vec2 size2(const YAML::Node& n, const std::string& path) const {
    if (!n.IsSequence() || n.size() != 2) fail(path, "expected [size_x, size_y]");
    return Vec2(positive(n[0], index(path, 0)), positive(n[1], index(path, 1)));
  }

  bool boolean(const YAML::Node& n, const std::string& path) const {
    bool b = false;
    if (!n.IsScalar()) fail(path, "expected true or false");
    try {
      b = n.as<bool>();
    } catch (const YAML::Exception&) {
      fail(path, "expected true or false, got '" + n.Scalar() + "'");
    }
    return b;
  }

  std::string string(const YAML::Node& n, const std::string& path) const {
    if (!n.IsScalar()) fail(path, "expected a string");
    return n.Scalar();
  }

  const YAML::Node sequence(const YAML::Node& map, const char* key) const {
    const YAML::Node n = map[key];
    if (n && !n.IsSequence() && !n.IsNull()) fail(key, "expected a list");
    return n;
  }

  int material(const Arena& arena, const YAML::Node& entry, const std::string& path) const {
    const YAML::Node n = entry["material"];
    if (!n) return arena.find_material("rigid");
    const std::string name = string(n, join(path, "material"));
    const int m = arena.find_material(name);
    if (m < 0) {
      std::string known;
      for (const auto& mat : arena.materials()) known += (known.empty() ? "" : ", ") + mat.name;
      fail(join(path, "material"), "unknown material '" + name + "' (known: " + known + ")");
    }
    return m;
  }

  std::string obstacle_name(const YAML::Node& entry, const std::string& path) const {
    const YAML::Node n = entry["name"];
    return n ? string(n, join(path, "name")) : path;
  }

 private:
  std::string source_;
  std::string prefix_;
};

void parse_materials(const Parser& p, const YAML::Node& node, Arena& arena) {
  if (!node || node.IsNull()) return;
  p.require_map(node, "materials");
  for (const auto& kv : node) {
    const std::string name = kv.first.Scalar();
    const std::string path = "materials." + name;
    if (name.empty()) p.fail("materials", "empty material name");
    for (const auto& b : builtin_materials()) {
      if (b.name == name) p.fail(path, "redefines the built-in material '" + name + "'");
    }
    const YAML::Node& m = kv.second;
    p.check_keys(m, path, {"friction", "signal_noise_scale", "stiffness", "damping"});
    Material mat = builtin_materials()[0];
    mat.name = name;
    if (m["friction"]) mat.friction = p.non_negative(m["friction"], path + ".friction");
    if (m["signal_noise_scale"]) {
      mat.signal_noise_scale = p.non_negative(m["signal_noise_scale"], path + ".signal_noise_scale");
    }
    if (m["stiffness"]) mat.stiffness = p.positive(m["stiffness"], path + ".stiffness");
    if (m["damping"]) mat.damping = p.non_negative(m["damping"], path + ".damping");
    arena.add_material(mat);
  }
}

void parse_walls(const Parser& p, const YAML::Node& list, Arena& arena) {
  if (!list) return;
  for (size_t i = 0; i < list.size(); ++i) {
    const std::string path = Parser::index("walls", i);
    const YAML::Node& w = list[i];
    p.check_keys(w, path, {"points", "material", "closed", "name"});
    const std::string pts_path = path + ".points";
    const YAML::Node pts = w["points"];
    if (!pts) p.fail(pts_path, "missing (a polyline needs at least 2 points)");
    if (!pts.IsSequence()) p.fail(pts_path, "expected a list of [x, y] points");
    if (pts.size() < 2) {
      p.fail(pts_path, "a polyline needs at least 2 points, got " + std::to_string(pts.size()));
    }
    std::vector<Vec2> v;
    for (size_t k = 0; k < pts.size(); ++k) v.push_back(p.vec2(pts[k], Parser::index(pts_path, k)));
    const bool closed = w["closed"] ? p.boolean(w["closed"], path + ".closed") : false;
    if (closed && v.size() < 3) p.fail(path + ".closed", "a closed polyline needs at least 3 points");
    const int material = p.material(arena, w, path);
    for (size_t k = 1; k < v.size(); ++k) {
      if ((v[k] - v[k - 1]).norm() < kMinLength) {
        p.fail(Parser::index(pts_path, k),
               "zero-length segment (same point as points[" + std::to_string(k - 1) + "])");
      }
    }
    if (closed && (v.front() - v.back()).norm() < kMinLength) {
      p.fail(Parser::index(pts_path, v.size() - 1),
             "zero-length closing segment (same point as points[0]; closed: true joins them)");
    }
    // Segments k: v[k] -> v[k+1] (closed: plus v[n-1] -> v[0]).
    const size_t n = v.size();
    const size_t nseg = closed ? n : n - 1;
    auto seg_a = [&](size_t k) { return v[k]; };
    auto seg_b = [&](size_t k) { return v[(k + 1) % n]; };
    for (size_t k = 0; k + 1 < nseg + (closed ? 1 : 0); ++k) {
      // Adjacent segments k and k+1 share point k+1: they may not fold back.
      const size_t k2 = (k + 1) % nseg;
      const Vec2 d1 = seg_b(k) - seg_a(k), d2 = seg_b(k2) - seg_a(k2);
      if (std::abs(geom::cross(d1, d2)) <= 1e-9 * d1.norm() * d2.norm() && d1.dot(d2) < 0.0) {
        p.fail(pts_path, "self-intersecting polyline (folds back on itself at points[" +
                             std::to_string((k + 1) % n) + "])");
      }
    }
    for (size_t a = 0; a < nseg; ++a) {
      for (size_t b = a + 2; b < nseg; ++b) {
        if (closed && a == 0 && b == nseg - 1) continue;  // adjacent through the closing point
        const auto x = geom::intersect_segments(seg_a(a), seg_b(a), seg_a(b), seg_b(b), 1e-9);
        if (x.hit) {
          p.fail(pts_path, "self-intersecting polyline (segment points[" + std::to_string(a) +
                               "]-points[" + std::to_string((a + 1) % n) +
                               "] crosses segment points[" + std::to_string(b) + "]-points[" +
                               std::to_string((b + 1) % n) + "])");
        }
      }
    }
    const int id = arena.add_obstacle(p.obstacle_name(w, path));
    for (size_t k = 0; k < nseg; ++k) arena.add_wall(seg_a(k), seg_b(k), material, id);
  }
}

void parse_boxes(const Parser& p, const YAML::Node& list, Arena& arena) {
  if (!list) return;
  for (size_t i = 0; i < list.size(); ++i) {
    const std::string path = Parser::index("boxes", i);
    const YAML::Node& b = list[i];
    p.check_keys(b, path, {"center", "size", "yaw_deg", "material", "name"});
    if (!b["center"]) p.fail(path + ".center", "missing");
    if (!b["size"]) p.fail(path + ".size", "missing");
    const Vec2 c = p.vec2(b["center"], path + ".center");
    const Vec2 s = p.size2(b["size"], path + ".size");
    const double yaw = p.number_or(b, "yaw_deg", path, 0.0) * kPi / 180.0;
    const int material = p.material(arena, b, path);
    const int id = arena.add_obstacle(p.obstacle_name(b, path));
    const Eigen::Rotation2Dd rot(yaw);
    const Vec2 h = 0.5 * s;
    const Vec2 corners[4] = {c + rot * Vec2(-h.x(), -h.y()), c + rot * Vec2(h.x(), -h.y()),
                             c + rot * Vec2(h.x(), h.y()), c + rot * Vec2(-h.x(), h.y())};
    for (int k = 0; k < 4; ++k) arena.add_wall(corners[k], corners[(k + 1) % 4], material, id);
  }
}

void parse_cylinders(const Parser& p, const YAML::Node& list, Arena& arena) {
  if (!list) return;
  for (size_t i = 0; i < list.size(); ++i) {
    const std::string path = Parser::index("cylinders", i);
    const YAML::Node& c = list[i];
    p.check_keys(c, path, {"center", "radius", "material", "name"});
    if (!c["center"]) p.fail(path + ".center", "missing");
    if (!c["radius"]) p.fail(path + ".radius", "missing");
    const Vec2 center = p.vec2(c["center"], path + ".center");
    const double r = p.positive(c["radius"], path + ".radius");
    const int material = p.material(arena, c, path);
    arena.add_cylinder(center, r, material, arena.add_obstacle(p.obstacle_name(c, path)));
  }
}

void parse_rooms(const Parser& p, const YAML::Node& list, Arena& arena) {
  if (!list) return;
  static const char* kSides[4] = {"south", "east", "north", "west"};
  for (size_t i = 0; i < list.size(); ++i) {
    const std::string path = Parser::index("rooms", i);
    const YAML::Node& r = list[i];
    p.check_keys(r, path, {"center", "size", "yaw_deg", "material", "exits", "name"});
    if (!r["center"]) p.fail(path + ".center", "missing");
    if (!r["size"]) p.fail(path + ".size", "missing");
    const Vec2 c = p.vec2(r["center"], path + ".center");
    const Vec2 s = p.size2(r["size"], path + ".size");
    const double yaw = p.number_or(r, "yaw_deg", path, 0.0) * kPi / 180.0;
    const int material = p.material(arena, r, path);
    // Local corners, counter-clockwise; side k runs from corner k to corner k+1.
    const Vec2 h = 0.5 * s;
    const Vec2 corners[4] = {{-h.x(), -h.y()}, {h.x(), -h.y()}, {h.x(), h.y()}, {-h.x(), h.y()}};
    // Gaps per side as intervals of the along-side coordinate measured from the
    // side's centre in the local +x (south, north) or +y (east, west) direction.
    struct Gap {
      double lo, hi;
      size_t exit;
    };
    std::vector<Gap> gaps[4];
    const YAML::Node exits = r["exits"];
    if (exits && !exits.IsSequence() && !exits.IsNull()) p.fail(path + ".exits", "expected a list");
    if (exits && exits.IsSequence()) {
      for (size_t e = 0; e < exits.size(); ++e) {
        const std::string ep = Parser::index(path + ".exits", e);
        const YAML::Node& x = exits[e];
        p.check_keys(x, ep, {"side", "width", "offset"});
        if (!x["side"]) p.fail(ep + ".side", "missing (north, south, east or west)");
        if (!x["width"]) p.fail(ep + ".width", "missing");
        const std::string side = p.string(x["side"], ep + ".side");
        int k = -1;
        for (int j = 0; j < 4; ++j) {
          if (side == kSides[j]) k = j;
        }
        if (k < 0) p.fail(ep + ".side", "unknown side '" + side + "' (north, south, east, west)");
        const double w = p.positive(x["width"], ep + ".width");
        const double off = p.number_or(x, "offset", ep, 0.0);
        const double len = (k == 0 || k == 2) ? s.x() : s.y();
        if (w >= len) {
          p.fail(ep + ".width", "exit (" + fmt(w) + " m) is not narrower than the " + side +
                                    " side (" + fmt(len) + " m)");
        }
        if (std::abs(off) + 0.5 * w > 0.5 * len + 1e-12) {
          p.fail(ep + ".offset", "exit [" + fmt(off - 0.5 * w) + ", " + fmt(off + 0.5 * w) +
                                     "] m extends beyond the " + side + " side (half length " +
                                     fmt(0.5 * len) + " m)");
        }
        for (const Gap& g : gaps[k]) {
          if (off - 0.5 * w < g.hi && off + 0.5 * w > g.lo) {
            p.fail(ep, "overlaps exits[" + std::to_string(g.exit) + "] on the " + side + " side");
          }
        }
        gaps[k].push_back({off - 0.5 * w, off + 0.5 * w, e});
      }
    }
    const int id = arena.add_obstacle(p.obstacle_name(r, path));
    const Eigen::Rotation2Dd rot(yaw);
    for (int k = 0; k < 4; ++k) {
      const Vec2 a = corners[k], b = corners[(k + 1) % 4];
      const double len = (b - a).norm();
      const Vec2 u = (b - a) / len;
      // Along-side coordinate s (from the side centre, +x or +y) -> parameter
      // from a: south (+x) and east (+y) run with s, north and west against it.
      const bool forward = (k == 0 || k == 1);
      std::vector<std::pair<double, double>> cuts;  // in distance from a
      for (const Gap& g : gaps[k]) {
        const double d0 = forward ? 0.5 * len + g.lo : 0.5 * len - g.hi;
        const double d1 = forward ? 0.5 * len + g.hi : 0.5 * len - g.lo;
        cuts.emplace_back(d0, d1);
      }
      std::sort(cuts.begin(), cuts.end());
      double from = 0.0;
      auto emit = [&](double d0, double d1) {
        if (d1 - d0 < kMinLength) return;
        arena.add_wall(c + rot * (a + d0 * u), c + rot * (a + d1 * u), material, id);
      };
      for (const auto& cut : cuts) {
        emit(from, cut.first);
        from = cut.second;
      }
      emit(from, len);
    }
  }
}

}  // namespace

Arena Arena::from_yaml(const YAML::Node& node, const std::string& source,
                       const std::string& key_prefix) {
  const Parser p(source, key_prefix);
  p.check_keys(node, "",
               {"name", "floor_z", "materials", "walls", "boxes", "cylinders", "rooms", "transform"});
  Arena arena;
  if (node["name"]) arena.set_name(p.string(node["name"], "name"));
  arena.set_floor_z(p.number_or(node, "floor_z", "", 0.0));
  parse_materials(p, node["materials"], arena);
  parse_walls(p, p.sequence(node, "walls"), arena);
  parse_boxes(p, p.sequence(node, "boxes"), arena);
  parse_cylinders(p, p.sequence(node, "cylinders"), arena);
  parse_rooms(p, p.sequence(node, "rooms"), arena);
  if (const YAML::Node t = node["transform"]) {
    p.check_keys(t, "transform", {"x", "y", "yaw_deg"});
    arena.transform(p.number_or(t, "x", "transform", 0.0), p.number_or(t, "y", "transform", 0.0),
                    p.number_or(t, "yaw_deg", "transform", 0.0) * kPi / 180.0);
  }
  return arena;
}

Arena Arena::from_yaml_text(const std::string& text, const std::string& source,
                            const std::string& key_prefix) {
  YAML::Node node;
  try {
    node = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw ArenaError(source + ": line " + std::to_string(e.mark.line + 1) + ", column " +
                     std::to_string(e.mark.column + 1) + ": YAML syntax error: " + e.msg);
  }
  return from_yaml(node, source, key_prefix);
}

Arena Arena::load(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ArenaError(path + ": cannot open arena file");
  std::ostringstream ss;
  ss << in.rdbuf();
  return from_yaml_text(ss.str(), path, "");
}

}  // namespace tactile_sim
