// Family `rooms` (issue 17): rectangular rooms with exits for GPIS active
// exploration, 000 Fig. 5 style (graph gpis_explore).
//
// Distribution (uniform, independent unless stated):
//   room                 sides 1.5 .. 3.5 m each, glass (000 Fig. 5: acrylic room),
//                        centred on the start, turned by -180 .. 180 deg
//                        (arena transform)
//   exits                1 or 2, width 0.6 .. 1.0 m, side north/east/south/west,
//                        centre anywhere along the side with the gap inside it
//                        (>= 0.05 m from each corner); two exits on one side are
//                        >= 0.2 m apart
//   obstacles            0 .. 2, box (sides 0.2 .. 0.5 m, yaw 0 .. 180 deg) or
//                        pillar (radius 0.05 .. 0.2 m), rigid, centre in the room
//                        >= 0.3 m from its walls
//   state estimate       mocap (000 Fig. 5's simulation trials)
// Validity: the start (room centre) is >= 0.4 m from every obstacle; every
// exit's doorway (the gap's width, 0.6 m deep into the room) is >= 0.25 m from
// every obstacle (exits clear); a disc of radius 0.2 m has a free path inside
// the room from the start to 0.3 m in front of every exit (reachable).
#include <cmath>
#include <sstream>

#include "families.hpp"

namespace tactile_cli::families {

namespace {

using tactile_sim::Vec2;

constexpr double kDeg = M_PI / 180.0;

struct Exit {
  std::string side;
  double width, offset;
};

struct Obstacle {
  bool box;
  Vec2 center;
  Vec2 size;      // box
  double yaw_deg; // box
  double radius;  // pillar
};

/// Gap centre, inward normal and the direction along the gap (room frame).
void exit_frame(const Exit& e, double w, double h, Vec2& centre, Vec2& inward, Vec2& along) {
  if (e.side == "north") {
    centre = {e.offset, h / 2}; inward = {0, -1}; along = {1, 0};
  } else if (e.side == "south") {
    centre = {e.offset, -h / 2}; inward = {0, 1}; along = {1, 0};
  } else if (e.side == "east") {
    centre = {w / 2, e.offset}; inward = {-1, 0}; along = {0, 1};
  } else {
    centre = {-w / 2, e.offset}; inward = {1, 0}; along = {0, 1};
  }
}

FamilyEnvironment draw_room(FamilyDraw& d, const std::string& family) {
  const double w = d.uniform(1.5, 3.5), h = d.uniform(1.5, 3.5);
  const double yaw = d.uniform(-180.0, 180.0);
  const int n_exits = d.uniform_int(1, 2);
  std::vector<Exit> exits;
  for (int i = 0; i < n_exits; ++i) {
    Exit e;
    e.side = d.pick<std::string>({"north", "east", "south", "west"});
    e.width = d.uniform(0.6, 1.0);
    const double side_len = (e.side == "north" || e.side == "south") ? w : h;
    const double room = side_len / 2 - e.width / 2 - 0.05;
    e.offset = d.uniform(-room, room);
    exits.push_back(e);
  }
  if (n_exits == 2 && exits[0].side == exits[1].side &&
      std::abs(exits[0].offset - exits[1].offset) < 0.5 * (exits[0].width + exits[1].width) + 0.2) {
    throw InvalidDraw("two exits on the " + exits[0].side + " side closer than 0.2 m");
  }
  const int n_obs = d.uniform_int(0, 2);
  std::vector<Obstacle> obstacles;
  for (int i = 0; i < n_obs; ++i) {
    Obstacle o;
    o.box = d.uniform_int(0, 1) == 1;
    o.center = {d.uniform(-w / 2 + 0.3, w / 2 - 0.3), d.uniform(-h / 2 + 0.3, h / 2 - 0.3)};
    o.size = {d.uniform(0.2, 0.5), d.uniform(0.2, 0.5)};
    o.yaw_deg = d.uniform(0.0, 180.0);
    o.radius = d.uniform(0.05, 0.2);
    obstacles.push_back(o);
  }

  const std::string name = family + "_" + std::to_string(d.seed);
  std::ostringstream room, obs;
  room << "  rooms:\n    - name: room\n      center: [0.0, 0.0]\n      size: [" << yaml_num(w) << ", " << yaml_num(h)
       << "]\n      material: glass\n      exits:\n";
  for (const auto& e : exits) {
    room << "        - {side: " << e.side << ", width: " << yaml_num(e.width) << ", offset: " << yaml_num(e.offset)
         << "}\n";
  }
  std::string boxes, cylinders;
  for (size_t i = 0; i < obstacles.size(); ++i) {
    const auto& o = obstacles[i];
    if (o.box) {
      boxes += "    - {name: box_" + std::to_string(i + 1) + ", center: [" + yaml_num(o.center.x()) + ", " +
               yaml_num(o.center.y()) + "], size: [" + yaml_num(o.size.x()) + ", " + yaml_num(o.size.y()) +
               "], yaw_deg: " + yaml_num(o.yaw_deg, 2) + ", material: rigid}\n";
    } else {
      cylinders += "    - {name: pillar_" + std::to_string(i + 1) + ", center: [" + yaml_num(o.center.x()) + ", " +
                   yaml_num(o.center.y()) + "], radius: " + yaml_num(o.radius) + ", material: rigid}\n";
    }
  }
  if (!boxes.empty()) obs << "  boxes:\n" << boxes;
  if (!cylinders.empty()) obs << "  cylinders:\n" << cylinders;

  // Checks in the room frame (before the transform).
  const auto whole = tactile_sim::Arena::from_yaml_text("  name: " + name + "\n" + room.str() + obs.str(), name, "arena.");
  const auto only_obstacles = tactile_sim::Arena::from_yaml_text("  name: " + name + "\n" + obs.str(), name, "arena.");
  if (clearance_at(only_obstacles, Vec2::Zero()) < 0.4) throw InvalidDraw("an obstacle within 0.4 m of the start");
  const Vec2 lo(-w / 2, -h / 2), hi(w / 2, h / 2);
  for (size_t j = 0; j < exits.size(); ++j) {
    Vec2 c, in, along;
    exit_frame(exits[j], w, h, c, in, along);
    for (double s = -exits[j].width / 2; s <= exits[j].width / 2 + 1e-9; s += 0.05) {
      for (double t = 0.0; t <= 0.6 + 1e-9; t += 0.05) {
        if (clearance_at(only_obstacles, c + s * along + t * in) < 0.25) {
          throw InvalidDraw("exit " + std::to_string(j) + " (" + exits[j].side + ") not clear of an obstacle");
        }
      }
    }
    if (!disc_path_exists(whole, Vec2::Zero(), c + 0.3 * in, 0.2, lo, hi)) {
      throw InvalidDraw("exit " + std::to_string(j) + " (" + exits[j].side + ") not reachable from the start");
    }
  }

  nlohmann::json drawn;
  drawn["room_m"] = {w, h};
  drawn["yaw_deg"] = yaw;
  for (const auto& e : exits) drawn["exits"].push_back({{"side", e.side}, {"width_m", e.width}, {"offset_m", e.offset}});
  drawn["obstacles"] = nlohmann::json::array();
  for (const auto& o : obstacles) {
    if (o.box) {
      drawn["obstacles"].push_back({{"type", "box"}, {"center", {o.center.x(), o.center.y()}},
                                    {"size", {o.size.x(), o.size.y()}}, {"yaw_deg", o.yaw_deg}});
    } else {
      drawn["obstacles"].push_back({{"type", "pillar"}, {"center", {o.center.x(), o.center.y()}}, {"radius", o.radius}});
    }
  }
  drawn["state_estimate"] = "mocap";

  const double duration = std::ceil(200.0 + 100.0 * std::max(w, h));
  std::ostringstream y;
  y << "# Generated by `tactile scenarios generate " << family << " --seed " << d.seed
    << "` (issue 17 scenario family; distribution in src/tactile_cli/src/families/rooms.cpp and\n"
    << "# config/scenarios/README.md). " << yaml_num(w, 2) << " m x " << yaml_num(h, 2) << " m room, " << n_exits
    << " exit(s), " << n_obs << " obstacle(s), draw attempt " << d.attempt + 1 << ".\n"
    << "# Flown alone with: tactile sim " << name << ".yaml --out DIR\n"
    << "name: " << name << "\n"
    << "description: \"" << family << " family, seed " << d.seed << ": " << yaml_num(w, 2) << " x " << yaml_num(h, 2)
    << " m room, " << n_exits << " exit(s), " << n_obs << " obstacle(s)\"\n"
    << "duration_s: " << yaml_num(duration, 1) << "\n"
    << "physics_rate_hz: 1000\n"
    << "seed: " << d.seed << "\n"
    << "arena:\n"
    << "  name: " << name << "\n"
    << room.str() << obs.str() << "  transform: {x: 0.0, y: 0.0, yaw_deg: " << yaml_num(yaw, 2) << "}\n"
    << "vehicle:\n"
    << "  type: whisker_crazyflie\n"
    << "  initial: {x: 0.0, y: 0.0, z: 0.0, yaw_deg: 0.0}\n"
    << "  state_estimate: mocap\n"
    << "graph: gpis_explore\n";  // the graph applies config/profiles/exploration.yaml
  FamilyEnvironment env;
  env.name = name;
  env.yaml = y.str();
  env.drawn = drawn;
  return env;
}

}  // namespace

std::vector<ScenarioFamily> room_families() {
  ScenarioFamily f;
  f.name = "rooms";
  f.description = "GPIS exploration (000 Fig. 5 style): rectangular glass rooms with 1-2 exits and 0-2 obstacles";
  f.distribution =
      "room sides 1.5-3.5 m, yaw -180-180 deg; 1-2 exits of 0.6-1.0 m anywhere along a side; 0-2 obstacles "
      "(boxes 0.2-0.5 m, pillars r 0.05-0.2 m) >= 0.3 m inside the walls; mocap; valid: start >= 0.4 m from "
      "obstacles, each exit's 0.6 m doorway >= 0.25 m from obstacles, 0.4 m disc reaches every exit";
  f.table_metrics = {"gpis.outcome", "gpis.exit_found", "gpis.outside_room", "gpis.travel_distance_m",
                     "gpis.gpis_updates", "gpis.reconstruction_error_m"};
  f.draw = [](FamilyDraw& d) { return draw_room(d, "rooms"); };
  return {f};
}

}  // namespace tactile_cli::families
