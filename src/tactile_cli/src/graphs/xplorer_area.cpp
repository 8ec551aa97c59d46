#include "xplorer_area.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <variant>
#include <vector>

namespace tactile_cli {

XplorerAreaGoal XplorerAreaGoal::from(const tactile_sim::Scenario& s) {
  XplorerAreaGoal g;
  if (auto it = s.metrics.find("box_size"); it != s.metrics.end()) {
    const auto* v = std::get_if<std::vector<double>>(&it->second);
    if (!v || v->size() != 2 || !((*v)[0] > 0) || !((*v)[1] > 0) || !std::isfinite((*v)[0]) || !std::isfinite((*v)[1]))
      throw std::runtime_error(s.source + ": metrics.box_size: must be [length, width] > 0 in metres");
    g.box_size = std::array<double, 2>{std::max((*v)[0], (*v)[1]), std::min((*v)[0], (*v)[1])};
  }
  g.rectangle = g.box_size.has_value();
  if (auto it = s.metrics.find("area_accuracy_of"); it != s.metrics.end()) {
    const auto* v = std::get_if<std::string>(&it->second);
    if (!v || (*v != "rectangle" && *v != "hull"))
      throw std::runtime_error(s.source + ": metrics.area_accuracy_of: must be 'rectangle' or 'hull'");
    if (*v == "rectangle" && !g.box_size)
      throw std::runtime_error(s.source + ": metrics.area_accuracy_of: 'rectangle' needs metrics.box_size");
    g.rectangle = *v == "rectangle";
  }
  if (auto it = s.metrics.find("min_area_accuracy"); it != s.metrics.end()) {
    const double* d = std::get_if<double>(&it->second);
    if (!d || !(*d > 0.0) || !(*d <= 1.0))
      throw std::runtime_error(s.source + ": metrics.min_area_accuracy: must be a number in (0, 1]");
    g.min_accuracy = *d;
  }
  return g;
}

double object_hull_area(const tactile_sim::Arena& arena) {
  std::vector<Eigen::Vector2d> pts;
  for (const auto& w : arena.walls()) {
    pts.push_back(w.a);
    pts.push_back(w.b);
  }
  for (const auto& c : arena.cylinders()) {
    for (int k = 0; k < 720; ++k) {
      const double a = 2.0 * M_PI * k / 720.0;
      pts.emplace_back(c.center.x() + c.radius * std::cos(a), c.center.y() + c.radius * std::sin(a));
    }
  }
  if (pts.size() < 3) return 0.0;
  return mapping_pcl::min_area_rectangle(pts).hull_area;
}

std::optional<double> measure_map_area(const mapping_pcl::PointMap& map, const XplorerAreaGoal& goal,
                                       double object_area, nlohmann::json& out) {
  // The map as exported: 1 cm voxel filter + statistical outlier removal.
  mapping_pcl::PointMap copy(map.params());
  std::vector<mapping_pcl::Vec3> pts;
  pts.reserve(map.size());
  for (const auto& p : map.cloud()) pts.emplace_back(p.x, p.y, p.z);
  copy.insert(pts);
  copy.voxel_filter();
  copy.remove_outliers();
  const auto r = copy.measure();
  out["map_points"] = r.points;
  out["map_length_m"] = r.length;
  out["map_width_m"] = r.width;
  out["map_height_m"] = r.height;
  out["map_area_m2"] = r.obb_area;
  out["map_hull_area_m2"] = r.hull_area;
  std::optional<double> hull, rect;
  if (object_area > 0.0) {
    hull = r.points > 0 ? 1.0 - std::abs(r.hull_area - object_area) / object_area : 0.0;
    out["true_area_m2"] = object_area;
    out["map_hull_area_accuracy"] = *hull;
  }
  if (goal.box_size) {
    const double a_true = (*goal.box_size)[0] * (*goal.box_size)[1];
    rect = r.points > 0 ? 1.0 - std::abs(r.obb_area - a_true) / a_true : 0.0;
    out["true_length_m"] = (*goal.box_size)[0];
    out["true_width_m"] = (*goal.box_size)[1];
    out["map_area_accuracy"] = *rect;
  }
  const std::optional<double> acc = goal.rectangle ? rect : hull;
  out["area_accuracy"] = acc ? nlohmann::json(*acc) : nlohmann::json(nullptr);
  out["min_area_accuracy"] = goal.min_accuracy ? nlohmann::json(*goal.min_accuracy) : nlohmann::json(nullptr);
  return acc;
}

void add_turn_outcomes(const std::vector<std::pair<double, std::string>>& states, nlohmann::json& out) {
  int recontacted = 0, turn_failed = 0, turn_closing = 0, contact_lost = 0;
  for (std::size_t i = 1; i < states.size(); ++i) {
    const auto& a = states[i - 1].second;
    const auto& b = states[i].second;
    if (a == "tactile_turning") (b == "tactile_traversal" ? recontacted : b == "done" ? turn_closing : turn_failed)++;
    if (a == "tactile_traversal" && b == "exploration") ++contact_lost;
  }
  out["turns_recontacted"] = recontacted;
  out["turns_without_recontact"] = turn_failed;
  out["turns_closing_the_loop"] = turn_closing;
  out["traversal_contact_lost"] = contact_lost;
}

}  // namespace tactile_cli
