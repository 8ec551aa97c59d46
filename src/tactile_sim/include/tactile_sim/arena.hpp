// The arena of the SITL world: vertical walls (2D segments), vertical
// cylinders and a floor, seen from above. Boxes and rooms of the arena file
// are expanded into wall segments when loaded. Queries (closest, raycast,
// first_hit) are allocation-free and deterministic; walls are culled by their
// bounding boxes. File schema: docs/sitl_design.md and
// config/scenarios/README.md ("Arena files").
#pragma once

#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "tactile_sim/geometry.hpp"
#include "tactile_sim/types.hpp"

namespace YAML {
class Node;
}

namespace tactile_sim {

/// Bad arena file or arena map; the message names the source file, the key
/// path and the reason ("arena.yaml: walls[2].points[1]: zero-length segment ...").
class ArenaError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Surface material of a wall or cylinder (contact and sensor properties).
struct Material {
  std::string name;
  double friction = 0.5;            ///< Coulomb coefficient mu [-]
  double signal_noise_scale = 1.0;  ///< multiplies the whisker barometer noise while in contact [-]
  double stiffness = 3000.0;        ///< penalty contact stiffness [N/m]
  double damping = 6.0;             ///< penalty contact damping [N s/m]
};

/// Built-in materials, in this order: rigid (0), glass (1), textile (2).
/// Values are choices (the papers give none), documented in
/// config/scenarios/README.md and docs/physics.md.
const std::vector<Material>& builtin_materials();

/// A vertical wall between a and b (zero thickness).
struct Wall {
  Vec2 a = Vec2::Zero();
  Vec2 b = Vec2::Zero();
  int material = 0;     ///< index into Arena::materials()
  int obstacle_id = 0;  ///< index into Arena::obstacle_names()
  Vec2 lo = Vec2::Zero(), hi = Vec2::Zero();  ///< bounding box (kept up to date by Arena)
};

/// A vertical cylinder (pipe, bin).
struct Cylinder {
  Vec2 center = Vec2::Zero();
  double radius = 0.0;
  int material = 0;
  int obstacle_id = 0;
};

/// Result of an arena query.
struct Hit {
  bool hit = false;
  /// closest(): distance from the query point to the surface (negative inside
  /// a cylinder); raycast()/first_hit(): distance along the ray/segment.
  double distance = std::numeric_limits<double>::infinity();
  Vec2 point = Vec2::Zero();   ///< surface point
  /// Unit surface normal pointing from the surface toward the query point
  /// (closest) or toward the ray origin (raycast, first_hit).
  Vec2 normal = Vec2::Zero();
  int material = -1;
  int obstacle_id = -1;
};

/// Axis-aligned bounds of everything in the arena.
struct Bounds {
  bool empty = true;
  Vec2 min = Vec2::Zero();
  Vec2 max = Vec2::Zero();
};

class Arena {
 public:
  /// Empty arena with the built-in materials.
  Arena();

  /// Parses an arena map (see the schema). `source` (file name) and
  /// `key_prefix` (e.g. "arena." when inline in a scenario) only prefix error
  /// messages. Throws ArenaError.
  static Arena from_yaml(const YAML::Node& node, const std::string& source,
                         const std::string& key_prefix = "");
  /// Same from YAML text (syntax errors are ArenaErrors too).
  static Arena from_yaml_text(const std::string& text, const std::string& source,
                              const std::string& key_prefix = "");
  /// Loads an arena file. Throws ArenaError naming the file.
  static Arena load(const std::string& path);

  // --- building -----------------------------------------------------------
  void set_name(const std::string& name) { name_ = name; }
  void set_floor_z(double z) { floor_z_ = z; }
  /// Adds (or replaces, by name) a material; returns its index.
  int add_material(const Material& m);
  /// Index of a material by name, -1 if unknown.
  int find_material(const std::string& name) const;
  /// Registers an obstacle (one wall polyline, box, cylinder or room); returns its id.
  int add_obstacle(const std::string& name);
  void add_wall(const Vec2& a, const Vec2& b, int material, int obstacle_id);
  void add_cylinder(const Vec2& center, double radius, int material, int obstacle_id);
  /// Rotates everything by yaw_rad about the origin, then translates by (dx, dy).
  void transform(double dx, double dy, double yaw_rad);

  // --- queries (allocation-free) --------------------------------------------
  /// Nearest surface point within max_dist of p (no hit if none).
  Hit closest(const Vec2& p, double max_dist) const;
  /// First surface hit along origin + s * unit_dir, s in [0, max_range].
  Hit raycast(const Vec2& origin, const Vec2& unit_dir, double max_range) const;
  /// First surface hit along the segment a -> b (e.g. a whisker shaft);
  /// distance is measured from a.
  Hit first_hit(const Vec2& a, const Vec2& b) const;
  Bounds bounds() const;

  /// Calls f(const Hit&) for every wall and cylinder whose surface is within
  /// max_dist of p (one call per wall segment / cylinder, closest point and
  /// normal toward p). Allocation-free; used by the contact model.
  template <class F>
  void for_each_within(const Vec2& p, double max_dist, F&& f) const;

  // --- contents -------------------------------------------------------------
  const std::string& name() const { return name_; }
  double floor_z() const { return floor_z_; }
  const std::vector<Wall>& walls() const { return walls_; }
  const std::vector<Cylinder>& cylinders() const { return cylinders_; }
  const std::vector<Material>& materials() const { return materials_; }
  const Material& material(int index) const { return materials_.at(index); }
  const std::vector<std::string>& obstacle_names() const { return obstacles_; }

 private:
  /// Closest-point hit of one wall (normal toward p; left normal if p is on it).
  static Hit wall_hit(const Wall& w, const Vec2& p);
  static Hit cylinder_hit(const Cylinder& c, const Vec2& p);

  std::string name_;
  double floor_z_ = 0.0;
  std::vector<Material> materials_;
  std::vector<std::string> obstacles_;
  std::vector<Wall> walls_;
  std::vector<Cylinder> cylinders_;
};

template <class F>
void Arena::for_each_within(const Vec2& p, double max_dist, F&& f) const {
  for (const Wall& w : walls_) {
    if (p.x() + max_dist < w.lo.x() || p.x() - max_dist > w.hi.x() ||
        p.y() + max_dist < w.lo.y() || p.y() - max_dist > w.hi.y()) {
      continue;
    }
    const Hit h = wall_hit(w, p);
    if (h.distance <= max_dist) f(h);
  }
  for (const Cylinder& c : cylinders_) {
    const Hit h = cylinder_hit(c, p);
    if (h.distance <= max_dist) f(h);
  }
}

}  // namespace tactile_sim
