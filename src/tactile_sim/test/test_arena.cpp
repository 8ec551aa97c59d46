// Arena: loading every arena file, rooms with exits, transform, queries
// against hand-computed answers, and every validation error.
#include <gtest/gtest.h>

#include <filesystem>

#include <cmath>
#include <map>
#include <string>

#include "tactile_sim/arena.hpp"

using tactile_sim::Arena;
using tactile_sim::ArenaError;
using tactile_sim::Hit;
using tactile_sim::Vec2;

namespace {

const std::string kArenaDir = std::string(TACTILE_CONFIG_DIR) + "/scenarios/arenas/";
constexpr double kPi = 3.14159265358979323846;

Arena text(const std::string& yaml) { return Arena::from_yaml_text(yaml, "test.yaml"); }

// Expects an ArenaError whose message contains every fragment.
void expect_error(const std::string& yaml, std::initializer_list<std::string> fragments,
                  const std::string& prefix = "") {
  try {
    Arena::from_yaml_text(yaml, "bad.yaml", prefix);
    FAIL() << "no error for:\n" << yaml;
  } catch (const ArenaError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.rfind("bad.yaml: ", 0), 0u) << msg;
    for (const auto& f : fragments) EXPECT_NE(msg.find(f), std::string::npos) << "'" << f << "' not in: " << msg;
  }
}

}  // namespace

TEST(ArenaFiles, EveryFileLoadsWithExpectedContents) {
  struct Expect {
    size_t walls, cylinders;
    Vec2 min, max;
  };
  const std::map<std::string, Expect> files = {
      {"wall", {1, 0, {1.0, -1.5}, {1.0, 1.5}}},
      {"glass_wall", {1, 0, {1.0, -1.5}, {1.0, 1.5}}},
      {"textile_wall", {1, 0, {1.0, -1.5}, {1.0, 1.5}}},
      {"three_baffles", {3, 0, {0.9920, -0.8998}, {3.0081, 0.8999}}},
      {"tilted_baffles", {3, 0, {0.9906, -0.8469}, {3.0120, 0.8999}}},
      {"room_exit", {5, 0, {-1.0, -1.0}, {1.0, 1.0}}},  // east side split by the exit
      {"xplorer_wall", {1, 0, {1.0, -2.0}, {1.0, 2.0}}},
      {"xplorer_box", {4, 0, {0.8, -0.61}, {1.8, 0.61}}},
      {"xplorer_pipe", {0, 1, {0.85, -0.15}, {1.15, 0.15}}},
      {"xplorer_pipe_d40", {0, 1, {0.8, -0.2}, {1.2, 0.2}}},
      {"xplorer_bin", {0, 1, {0.8, -0.25}, {1.3, 0.25}}},
      {"ducted_wall", {1, 0, {-2.0, 0.0}, {2.0, 0.0}}},
  };
  for (const auto& [name, e] : files) {
    SCOPED_TRACE(name);
    const Arena a = Arena::load(kArenaDir + name + ".yaml");
    EXPECT_EQ(a.name(), name);
    EXPECT_EQ(a.walls().size(), e.walls);
    EXPECT_EQ(a.cylinders().size(), e.cylinders);
    const auto b = a.bounds();
    ASSERT_FALSE(b.empty);
    EXPECT_NEAR(b.min.x(), e.min.x(), 1e-9);
    EXPECT_NEAR(b.min.y(), e.min.y(), 1e-9);
    EXPECT_NEAR(b.max.x(), e.max.x(), 1e-9);
    EXPECT_NEAR(b.max.y(), e.max.y(), 1e-9);
    EXPECT_EQ(a.floor_z(), 0.0);
  }
}

TEST(ArenaFiles, BaffleOrientationsMatchThePaper) {
  // 000 Fig. 4: orientation = direction points[0] -> points[1].
  const std::map<std::string, std::array<double, 3>> expected = {
      {"three_baffles", {-90.76, -91.34, -90.77}}, {"tilted_baffles", {-90.90, -65.71, -91.15}}};
  for (const auto& [name, deg] : expected) {
    const Arena a = Arena::load(kArenaDir + name + ".yaml");
    ASSERT_EQ(a.walls().size(), 3u);
    for (int i = 0; i < 3; ++i) {
      const Vec2 d = a.walls()[i].b - a.walls()[i].a;
      EXPECT_NEAR(std::atan2(d.y(), d.x()) * 180.0 / kPi, deg[i], 0.01) << name << " " << i;
      EXPECT_NEAR(d.norm(), 1.2, 1e-3);
      EXPECT_EQ(a.materials()[a.walls()[i].material].name, "glass");
    }
  }
}

TEST(ArenaFiles, RoomExitIsEighyCentimetresOnTheEastSide) {
  const Arena a = Arena::load(kArenaDir + "room_exit.yaml");
  // From the centre: east ray escapes through the exit; rays elsewhere hit at 1 m.
  EXPECT_FALSE(a.raycast({0, 0}, {1, 0}, 5.0).hit);
  EXPECT_FALSE(a.raycast({0, 0.39}, {1, 0}, 5.0).hit);
  EXPECT_TRUE(a.raycast({0, 0.41}, {1, 0}, 5.0).hit);
  for (const Vec2& d : {Vec2(-1, 0), Vec2(0, 1), Vec2(0, -1)}) {
    const Hit h = a.raycast({0, 0}, d, 5.0);
    ASSERT_TRUE(h.hit);
    EXPECT_NEAR(h.distance, 1.0, 1e-12);
    EXPECT_EQ(a.materials()[h.material].name, "glass");
  }
  // Exit edges: along x = 1 the wall is present for |y| >= 0.4 only.
  const Hit up = a.raycast({1.5, 0.0}, {0, 1}, 5.0);
  EXPECT_FALSE(up.hit);  // x = 1.5 is outside the room: nothing above
  const Hit side = a.raycast({2.0, 0.5}, {-1, 0}, 5.0);
  ASSERT_TRUE(side.hit);
  EXPECT_NEAR(side.distance, 1.0, 1e-12);
}

TEST(Arena, RoomExitsOnEverySideWithOffsets) {
  const Arena a = text(R"(
rooms:
  - center: [0, 0]
    size: [4, 2]
    exits:
      - {side: north, width: 1.0, offset: 1.0}
      - {side: south, width: 0.5, offset: -1.5}
      - {side: west, width: 0.4, offset: 0.2}
      - {side: east, width: 0.4, offset: -0.8}
)");
  // north gap x in [0.5, 1.5]; south gap x in [-1.75, -1.25] (touches no corner);
  // west gap y in [0, 0.4]; east gap y in [-1.0, -0.6] (reaches the corner).
  EXPECT_EQ(a.walls().size(), 2u + 2u + 2u + 1u);
  EXPECT_FALSE(a.raycast({1.0, 0}, {0, 1}, 5).hit);
  EXPECT_TRUE(a.raycast({0.4, 0}, {0, 1}, 5).hit);
  EXPECT_FALSE(a.raycast({-1.5, 0}, {0, -1}, 5).hit);
  EXPECT_TRUE(a.raycast({-1.0, 0}, {0, -1}, 5).hit);
  EXPECT_FALSE(a.raycast({0, 0.2}, {-1, 0}, 5).hit);
  EXPECT_TRUE(a.raycast({0, -0.2}, {-1, 0}, 5).hit);
  EXPECT_FALSE(a.raycast({0, -0.8}, {1, 0}, 5).hit);
  EXPECT_TRUE(a.raycast({0, -0.4}, {1, 0}, 5).hit);
}

TEST(Arena, ClosestRaycastFirstHitHandComputed) {
  const Arena a = text(R"(
walls:
  - points: [[1, -1], [1, 1]]
cylinders:
  - center: [-2, 0]
    radius: 0.5
    material: textile
)");
  // Closest to (0.3, 0.2): the wall at distance 0.7, normal -x (toward the point).
  Hit h = a.closest({0.3, 0.2}, 1.0);
  ASSERT_TRUE(h.hit);
  EXPECT_NEAR(h.distance, 0.7, 1e-12);
  EXPECT_TRUE(h.point.isApprox(Vec2(1, 0.2)));
  EXPECT_TRUE(h.normal.isApprox(Vec2(-1, 0)));
  EXPECT_EQ(h.obstacle_id, 0);
  EXPECT_FALSE(a.closest({0.3, 0.2}, 0.69).hit);
  // Beyond the wall's end: distance to the endpoint (1,1) from (1.3, 1.4) = 0.5.
  h = a.closest({1.3, 1.4}, 1.0);
  ASSERT_TRUE(h.hit);
  EXPECT_NEAR(h.distance, 0.5, 1e-12);
  EXPECT_TRUE(h.normal.isApprox(Vec2(0.6, 0.8)));
  // Cylinder: from (-2, 1.5) distance 1.0, normal +y; inside: negative.
  h = a.closest({-2, 1.5}, 2.0);
  ASSERT_TRUE(h.hit);
  EXPECT_NEAR(h.distance, 1.0, 1e-12);
  EXPECT_TRUE(h.normal.isApprox(Vec2(0, 1)));
  EXPECT_EQ(h.obstacle_id, 1);
  EXPECT_EQ(a.materials()[h.material].name, "textile");
  h = a.closest({-2.2, 0}, 1.0);
  EXPECT_NEAR(h.distance, -0.3, 1e-12);
  // Raycast +x from (0, 0.5): wall at 1, normal faces back (-x).
  h = a.raycast({0, 0.5}, {1, 0}, 3.0);
  ASSERT_TRUE(h.hit);
  EXPECT_NEAR(h.distance, 1.0, 1e-12);
  EXPECT_TRUE(h.normal.isApprox(Vec2(-1, 0)));
  // From the other side: normal +x.
  h = a.raycast({3, 0.5}, {-1, 0}, 3.0);
  EXPECT_NEAR(h.distance, 2.0, 1e-12);
  EXPECT_TRUE(h.normal.isApprox(Vec2(1, 0)));
  // Raycast -x from the origin: wall is behind, cylinder entered at 1.5.
  h = a.raycast({0, 0}, {-1, 0}, 3.0);
  ASSERT_TRUE(h.hit);
  EXPECT_NEAR(h.distance, 1.5, 1e-12);
  EXPECT_TRUE(h.normal.isApprox(Vec2(1, 0)));
  EXPECT_FALSE(a.raycast({0, 0}, {-1, 0}, 1.4).hit);
  // first_hit along a whisker shaft (0,0) -> (2,2): crosses x = 1 at (1,1), sqrt 2.
  h = a.first_hit({0, 0}, {2, 2});
  ASSERT_TRUE(h.hit);
  EXPECT_NEAR(h.distance, std::sqrt(2.0), 1e-12);
  EXPECT_TRUE(h.point.isApprox(Vec2(1, 1)));
  EXPECT_FALSE(a.first_hit({0, 0}, {0.9, 0.9}).hit);
  EXPECT_FALSE(a.first_hit({0, 0}, {0, 0}).hit);
  // Nearest of two along the ray: a second wall in front of the first.
  const Arena two = text("walls:\n  - points: [[2, -1], [2, 1]]\n  - points: [[1, -1], [1, 1]]\n");
  h = two.raycast({0, 0}, {1, 0}, 5);
  EXPECT_NEAR(h.distance, 1.0, 1e-12);
  EXPECT_EQ(h.obstacle_id, 1);
}

TEST(Arena, TransformPreservesDistancesAndRotatesHits) {
  const Arena base = Arena::load(kArenaDir + "xplorer_box.yaml");
  Arena moved = base;
  const double yaw = 0.7, dx = -0.4, dy = 1.3;
  moved.transform(dx, dy, yaw);
  const Eigen::Rotation2Dd R(yaw);
  const Vec2 t(dx, dy);
  for (const Vec2& p : {Vec2(0, 0), Vec2(0.5, 0.9), Vec2(1.3, 0.0), Vec2(3, -2)}) {
    const Hit h0 = base.closest(p, 10);
    const Hit h1 = moved.closest(R * p + t, 10);
    ASSERT_TRUE(h0.hit && h1.hit);
    EXPECT_NEAR(h0.distance, h1.distance, 1e-12);
    EXPECT_TRUE((R * h0.point + t).isApprox(h1.point, 1e-12));
    EXPECT_TRUE((R * h0.normal).isApprox(h1.normal, 1e-12));
  }
  // Ray from the origin along +x hits the near face at 0.8; the rotated ray too.
  const Hit r0 = base.raycast({0, 0}, {1, 0}, 5);
  const Hit r1 = moved.raycast(t, R * Vec2(1, 0), 5);
  ASSERT_TRUE(r0.hit && r1.hit);
  EXPECT_NEAR(r0.distance, 0.8, 1e-12);
  EXPECT_NEAR(r1.distance, 0.8, 1e-12);
  EXPECT_TRUE(r1.normal.isApprox(R * Vec2(-1, 0), 1e-12));
  // The YAML transform key does the same.
  const Arena y = text("boxes:\n  - {center: [1.3, 0], size: [1.0, 1.22]}\ntransform: {x: 0, y: 0, yaw_deg: 90}\n");
  const Hit ry = y.raycast({0, 0}, {0, 1}, 5);
  ASSERT_TRUE(ry.hit);
  EXPECT_NEAR(ry.distance, 0.8, 1e-12);
}

TEST(Arena, MaterialsAndDefaults) {
  const Arena a = text(R"(
name: m
floor_z: 0.25
materials:
  foam: {friction: 0.9, signal_noise_scale: 2.5, stiffness: 400.0, damping: 4.0}
walls:
  - points: [[0, 0], [1, 0], [1, 1]]
    material: foam
    closed: true
  - points: [[5, 0], [6, 0]]
)");
  EXPECT_EQ(a.floor_z(), 0.25);
  ASSERT_EQ(a.materials().size(), 4u);
  EXPECT_EQ(a.materials()[0].name, "rigid");
  EXPECT_EQ(a.materials()[1].name, "glass");
  EXPECT_EQ(a.materials()[2].name, "textile");
  const auto& foam = a.materials()[3];
  EXPECT_EQ(foam.friction, 0.9);
  EXPECT_EQ(foam.signal_noise_scale, 2.5);
  EXPECT_EQ(foam.stiffness, 400.0);
  EXPECT_EQ(foam.damping, 4.0);
  ASSERT_EQ(a.walls().size(), 4u);  // closed triangle + one segment
  EXPECT_EQ(a.walls()[0].material, 3);
  EXPECT_EQ(a.walls()[3].material, 0);  // default rigid
  EXPECT_TRUE(a.walls()[2].b.isApprox(Vec2(0, 0)));  // closing segment
  EXPECT_EQ(a.obstacle_names().size(), 2u);
  EXPECT_EQ(a.obstacle_names()[1], "walls[1]");
  // Textile is softer and rougher than rigid; glass is smoother.
  const auto& m = a.materials();
  EXPECT_LT(m[2].stiffness, m[0].stiffness);
  EXPECT_GT(m[2].friction, m[0].friction);
  EXPECT_GT(m[2].signal_noise_scale, 1.0);
  EXPECT_LT(m[1].signal_noise_scale, 1.0);
  EXPECT_LT(m[1].friction, m[0].friction);
  EXPECT_TRUE(text("{}").bounds().empty);
}

TEST(ArenaValidation, ErrorsNameFileKeyAndReason) {
  expect_error("walls:\n  - points: [[0, 0], [1, 0]]\n  - points: [[0, 1], [0, 1]]\n",
               {"walls[1].points[1]", "zero-length segment", "points[0]"});
  expect_error("walls:\n  - points: [[0, 0], [2, 0], [2, 1], [1, -1]]\n",
               {"walls[0].points", "self-intersecting", "points[0]-points[1]", "points[2]-points[3]"});
  expect_error("walls:\n  - points: [[0, 0], [2, 0], [1, 0]]\n",
               {"walls[0].points", "self-intersecting", "folds back"});
  expect_error("walls:\n  - points: [[0, 0], [1, 0], [1, 1], [0, 0]]\n    closed: true\n",
               {"walls[0].points[3]", "zero-length closing segment"});
  expect_error("walls:\n  - points: [[0, 0], [1, 0]]\n    material: marble\n",
               {"walls[0].material", "unknown material 'marble'", "rigid, glass, textile"});
  expect_error("cylinders:\n  - {center: [0, 0], radius: -0.1}\n",
               {"cylinders[0].radius", "must be > 0", "-0.1"});
  expect_error("boxes:\n  - {center: [0, 0], size: [1, 0]}\n", {"boxes[0].size[1]", "must be > 0"});
  expect_error("rooms:\n  - center: [0, 0]\n    size: [2, 2]\n    exits: [{side: north, width: 2.0}]\n",
               {"rooms[0].exits[0].width", "not narrower than the north side"});
  expect_error("rooms:\n  - center: [0, 0]\n    size: [2, 2]\n    exits: [{side: west, width: 0.8, offset: 0.7}]\n",
               {"rooms[0].exits[0].offset", "extends beyond the west side"});
  expect_error("rooms:\n  - center: [0, 0]\n    size: [2, 2]\n    exits: [{side: up, width: 0.8}]\n",
               {"rooms[0].exits[0].side", "unknown side 'up'"});
  expect_error("rooms:\n  - center: [0, 0]\n    size: [2, 2]\n    exits: [{side: north, width: 0.8}, {side: north, width: 0.4, offset: 0.3}]\n",
               {"rooms[0].exits[1]", "overlaps exits[0]"});
  expect_error("walls:\n  - points: [[0, 0], [1, 0]]\n    colour: red\n",
               {"walls[0].colour", "unknown key", "allowed: points, material, closed, name"});
  expect_error("floor: 1\n", {"floor", "unknown key"});
  expect_error("walls:\n  - points: [[0, zero], [1, 0]]\n",
               {"walls[0].points[0][1]", "expected a number", "'zero'"});
  expect_error("floor_z: .nan\n", {"floor_z", "must be finite"});
  expect_error("walls:\n  - points: [[0, 0]]\n", {"walls[0].points", "at least 2 points, got 1"});
  expect_error("walls:\n  - points: [[0, 0], [1, 0, 2]]\n", {"walls[0].points[1]", "expected [x, y]"});
  expect_error("walls:\n  - material: glass\n", {"walls[0].points", "missing"});
  expect_error("walls:\n  - points: [[0, 0], [1, 0]]\n    closed: maybe\n", {"walls[0].closed", "true or false"});
  expect_error("walls:\n  - points: [[0, 0], [1, 0]]\n    closed: true\n", {"walls[0].closed", "at least 3 points"});
  expect_error("walls: 3\n", {"walls", "expected a list"});
  expect_error("materials:\n  glass: {friction: 0.1}\n", {"materials.glass", "redefines the built-in"});
  expect_error("materials:\n  foam: {stiffness: 0}\n", {"materials.foam.stiffness", "must be > 0"});
  expect_error("materials:\n  foam: {friction: -1}\n", {"materials.foam.friction", "must be >= 0"});
  expect_error("transform: {x: 1, z: 2}\n", {"transform.z", "unknown key"});
  expect_error("- 1\n- 2\n", {"<root>", "expected a map"});
  // Inline in a scenario: the prefix is part of the key path.
  expect_error("cylinders:\n  - {center: [0, 0], radius: 0}\n", {"arena.cylinders[0].radius"}, "arena.");
}

TEST(ArenaValidation, GarbageTruncatedAndMissingFiles) {
  expect_error("walls:\n  - points: [[0, 0], [1, 0\n", {"YAML syntax error"});
  expect_error("walls: [[[[\n", {"YAML syntax error"});
  expect_error("\x01\x02\xff\xfe garbage: [", {"bad.yaml"});
  expect_error("just a string", {"expected a map"});
  // Oversized: a long valid polyline loads; its many segments are all walls.
  std::string big = "walls:\n  - points: [";
  for (int i = 0; i < 5000; ++i) big += (i ? ", " : "") + std::string("[") + std::to_string(i * 0.01) + ", " + std::to_string((i % 2) * 0.01) + "]";
  big += "]\n";
  EXPECT_EQ(text(big).walls().size(), 4999u);
  try {
    Arena::load(kArenaDir + "does_not_exist.yaml");
    FAIL();
  } catch (const ArenaError& e) {
    EXPECT_NE(std::string(e.what()).find("does_not_exist.yaml: cannot open"), std::string::npos);
  }
}

// Every arena file shipped in config/scenarios/arenas loads and validates,
// including the ones added after the paper set (generalisation layouts).
TEST(ArenaFiles, EveryShippedFileLoads) {
  size_t n = 0;
  for (const auto& e : std::filesystem::directory_iterator(kArenaDir)) {
    if (e.path().extension() != ".yaml") continue;
    SCOPED_TRACE(e.path().string());
    const Arena a = Arena::load(e.path().string());
    EXPECT_FALSE(a.walls().empty() && a.cylinders().empty());
    ++n;
  }
  EXPECT_GE(n, 14u);
}
