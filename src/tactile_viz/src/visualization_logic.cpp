#include "tactile_viz/visualization_logic.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "tactile_common/time.hpp"

namespace tactile_viz {
namespace {

using visualization_msgs::msg::Marker;
using geometry_msgs::msg::Point;

[[noreturn]] void bad(const std::string& field, const std::string& reason) {
  throw std::invalid_argument("VisualizationParams." + field + ": " + reason);
}

void positive_finite(const char* field, double v) {
  if (!(v > 0.0) || !std::isfinite(v)) bad(field, "must be finite and > 0, got " + std::to_string(v));
}

bool finite(const Point& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

Point point(double x, double y, double z) {
  Point p;
  p.x = x;
  p.y = y;
  p.z = z;
  return p;
}

/// An ADD marker of `ns`/`id` in `frame` stamped with the input's stamp; identity pose.
Marker make(const builtin_interfaces::msg::Time& stamp, const std::string& frame, const char* ns, int id,
            int type) {
  Marker m;
  m.header.stamp = stamp;
  m.header.frame_id = frame;
  m.ns = ns;
  m.id = id;
  m.type = type;
  m.action = Marker::ADD;
  m.pose.orientation.w = 1.0;
  return m;
}

Marker remove(const builtin_interfaces::msg::Time& stamp, const std::string& frame, const char* ns, int id) {
  Marker m = make(stamp, frame, ns, id, Marker::SPHERE);
  m.action = Marker::DELETE;
  return m;
}

void uniform_scale(Marker& m, double s) {
  m.scale.x = s;
  m.scale.y = s;
  m.scale.z = s;
}

// Colours of the sources (README "Markers").
const auto kLeft = VisualizationLogic::color(0.1f, 0.8f, 0.1f);       // left whisker: green
const auto kRight = VisualizationLogic::color(0.1f, 0.4f, 1.0f);      // right whisker: blue
const auto kWall = VisualizationLogic::color(1.0f, 0.5f, 0.0f);       // wall estimate: orange
const auto kContour = VisualizationLogic::color(1.0f, 1.0f, 1.0f);    // GPIS zero level set: white
const auto kSurface = VisualizationLogic::color(1.0f, 0.1f, 0.1f);    // training label 0: red
const auto kInterior = VisualizationLogic::color(0.2f, 0.2f, 1.0f);   // training label -1: blue
const auto kCorner = VisualizationLogic::color(1.0f, 1.0f, 0.0f);     // corners: yellow
const auto kTarget = VisualizationLogic::color(1.0f, 0.0f, 1.0f);     // target: magenta
const auto kExit = VisualizationLogic::color(0.0f, 1.0f, 0.0f);       // target through an opening: green
const auto kBody = VisualizationLogic::color(1.0f, 0.0f, 0.0f);       // collision of body: red
const auto kGuard = VisualizationLogic::color(1.0f, 0.5f, 0.0f);      // ... guard: orange
const auto kArm = VisualizationLogic::color(1.0f, 1.0f, 0.0f);        // ... arm0..arm3: yellow
const auto kOther = VisualizationLogic::color(0.6f, 0.6f, 0.6f);      // ... other part: grey
const auto kLocalization = VisualizationLogic::color(0.0f, 1.0f, 1.0f);  // localization: cyan

std::string where(const char* type, const std::string& field) { return std::string(type) + ": " + field + ": "; }

}  // namespace

std_msgs::msg::ColorRGBA VisualizationLogic::color(float r, float g, float b, float a) {
  std_msgs::msg::ColorRGBA c;
  c.r = r;
  c.g = g;
  c.b = b;
  c.a = a;
  return c;
}

void VisualizationParams::validate() const {
  if (max_markers < 1 || max_markers > 100000)
    bad("max_markers", "must be in [1, 100000], got " + std::to_string(max_markers));
  if (!(min_interval_s >= 0.0) || !std::isfinite(min_interval_s))
    bad("min_interval_s", "must be finite and >= 0, got " + std::to_string(min_interval_s));
  positive_finite("contact_diameter", contact_diameter);
  positive_finite("collision_diameter", collision_diameter);
  positive_finite("normal_length", normal_length);
  positive_finite("wall_length", wall_length);
  positive_finite("line_width", line_width);
  positive_finite("point_size", point_size);
  positive_finite("target_diameter", target_diameter);
  positive_finite("mean_range", mean_range);
  positive_finite("variance_max", variance_max);
}

tactile_common::ParamMap VisualizationLogic::default_parameters() {
  const Params d;
  tactile_common::ParamMap m(kNodeName, "defaults");
  using tactile_common::at_least;
  using tactile_common::choice;
  using tactile_common::closed;
  using tactile_common::positive;
  // None is live: the histories are sized at start (read-only in ROS).
  m.set("max_markers", d.max_markers,
        {"length of each contact history (whisker contacts per whisker, collisions): a ring buffer", "points",
         closed(1, 100000), false, choice()});
  m.set("min_interval_s", d.min_interval_s,
        {"whisker contacts, wall estimate and localization markers at most once per this interval of input "
         "stamps (a marker that disappears is deleted at once); 0: every input",
         "s", at_least(0.0), false, choice()});
  m.set("contact_diameter", d.contact_diameter, {"whisker contact spheres", "m", positive(), false, choice()});
  m.set("collision_diameter", d.collision_diameter, {"collision spheres", "m", positive(), false, choice()});
  m.set("normal_length", d.normal_length, {"collision normal lines", "m", positive(), false, choice()});
  m.set("wall_length", d.wall_length, {"drawn length of the estimated wall", "m", positive(), false, choice()});
  m.set("line_width", d.line_width, {"width of line markers", "m", positive(), false, choice()});
  m.set("point_size", d.point_size, {"GPIS training points and corners", "m", positive(), false, choice()});
  m.set("target_diameter", d.target_diameter, {"exploration target sphere", "m", positive(), false, choice()});
  m.set("mean_range", d.mean_range,
        {"GPIS mean grid: cell = round(50 + 50 clamp(mean / mean_range, -1, 1)) (50: the surface)", "m",
         positive(), false, choice()});
  m.set("variance_max", d.variance_max,
        {"GPIS variance grid: cell = round(100 clamp(variance / variance_max, 0, 1)) (1: the IMQ prior "
         "variance, 000 eq. 33)",
         "m^2", positive(), false, choice("the IMQ prior variance k(x, x), 000 eq. 33, 35")});
  return m;
}

VisualizationParams VisualizationLogic::params_from(const tactile_common::ParamMap& m) {
  Params p;
  p.max_markers = m.get_int64("max_markers", 1, 100000);
  p.min_interval_s = m.get_double("min_interval_s");
  p.contact_diameter = m.get_double("contact_diameter");
  p.collision_diameter = m.get_double("collision_diameter");
  p.normal_length = m.get_double("normal_length");
  p.wall_length = m.get_double("wall_length");
  p.line_width = m.get_double("line_width");
  p.point_size = m.get_double("point_size");
  p.target_diameter = m.get_double("target_diameter");
  p.mean_range = m.get_double("mean_range");
  p.variance_max = m.get_double("variance_max");
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    throw m.error_from(e);  // "<Type>.<field>: <reason>" -> parameter <field>
  }
  return p;
}

VisualizationLogic::VisualizationLogic(const Params& params) : params_(params) { params_.validate(); }

void VisualizationLogic::start(Source& s, const char* ns, MarkerArray& out) {
  if (s.started) return;
  Marker m;
  m.ns = ns;
  m.action = Marker::DELETEALL;
  m.pose.orientation.w = 1.0;
  out.markers.push_back(m);
  s.started = true;
}

bool VisualizationLogic::due(Source& s, int64_t now_ns, bool forced) {
  const auto interval_ns = static_cast<int64_t>(std::llround(params_.min_interval_s * 1e9));
  // Time going back (a new run, a bag looping) publishes at once.
  if (forced || !s.published_once || now_ns < s.last_publish_ns || now_ns - s.last_publish_ns >= interval_ns) {
    s.published_once = true;
    s.last_publish_ns = now_ns;
    return true;
  }
  ++stats_.throttled;
  return false;
}

void VisualizationLogic::push(History& h, const Point& p, std::size_t per_item) {
  const auto cap = static_cast<std::size_t>(params_.max_markers);
  if (h.points.size() >= cap) {
    h.points.erase(h.points.begin());
    if (!h.colors.empty()) h.colors.erase(h.colors.begin());
    if (per_item > 0) h.lines.erase(h.lines.begin(), h.lines.begin() + static_cast<std::ptrdiff_t>(per_item));
  }
  h.points.push_back(p);
}

VisualizationLogic::MarkerArray VisualizationLogic::on_tactile_depth(const tactile_msgs::msg::TactileDepth& msg) {
  bool added = false;
  for (int side = 0; side < 2; ++side) {
    const bool contact = side == 0 ? msg.contact_left : msg.contact_right;
    const Point& p = side == 0 ? msg.contact_point_left : msg.contact_point_right;
    if (!contact) continue;
    if (msg.contact_frame_id.empty()) {
      ++stats_.contacts_without_frame;
      continue;
    }
    if (!finite(p)) {
      ++stats_.nonfinite_dropped;
      continue;
    }
    History& h = contacts_[side];
    if (h.frame_id != msg.contact_frame_id) {  // points of another frame cannot be kept in one marker
      h.points.clear();
      h.frame_id = msg.contact_frame_id;
    }
    push(h, p, 0);
    added = true;
  }
  MarkerArray out;
  if (!added || !due(depth_src_, tactile_common::from_stamp(msg.header.stamp), false)) return out;
  start(depth_src_, kNsWhiskerContacts, out);
  for (int side = 0; side < 2; ++side) {
    const History& h = contacts_[side];
    if (h.points.empty()) continue;
    Marker m = make(msg.header.stamp, h.frame_id, kNsWhiskerContacts, side, Marker::SPHERE_LIST);
    uniform_scale(m, params_.contact_diameter);
    m.color = side == 0 ? kLeft : kRight;
    m.points = h.points;
    out.markers.push_back(std::move(m));
  }
  return out;
}

VisualizationLogic::MarkerArray VisualizationLogic::on_wall_estimate(const tactile_msgs::msg::WallEstimate& msg) {
  MarkerArray out;
  const bool finite_estimate = std::isfinite(msg.distance) && std::isfinite(msg.direction);
  if (msg.wall_detected && !finite_estimate) ++stats_.nonfinite_dropped;
  if (!msg.wall_detected || !finite_estimate) {
    if (wall_shown_) {
      start(wall_src_, kNsWallEstimate, out);
      out.markers.push_back(remove(msg.header.stamp, msg.header.frame_id, kNsWallEstimate, 0));
      out.markers.push_back(remove(msg.header.stamp, msg.header.frame_id, kNsWallEstimate, 1));
      wall_shown_ = false;
    }
    return out;
  }
  if (!due(wall_src_, tactile_common::from_stamp(msg.header.stamp), !wall_shown_)) return out;
  start(wall_src_, kNsWallEstimate, out);
  // direction: from the vehicle centre to the wall in the body frame (wall_effect_ekf
  // README "Frames"); the wall is the line through the foot point, normal to it.
  const double ux = std::cos(msg.direction), uy = std::sin(msg.direction);
  const double fx = msg.distance * ux, fy = msg.distance * uy;
  const double h = 0.5 * params_.wall_length;
  Marker wall = make(msg.header.stamp, msg.header.frame_id, kNsWallEstimate, 0, Marker::LINE_STRIP);
  wall.scale.x = params_.line_width;
  wall.color = kWall;
  wall.points = {point(fx + h * uy, fy - h * ux, 0.0), point(fx - h * uy, fy + h * ux, 0.0)};
  Marker arrow = make(msg.header.stamp, msg.header.frame_id, kNsWallEstimate, 1, Marker::ARROW);
  arrow.scale.x = params_.line_width;        // shaft diameter
  arrow.scale.y = 2.0 * params_.line_width;  // head diameter
  arrow.scale.z = 0.0;                       // head length: RViz's default
  arrow.color = kWall;
  arrow.points = {point(0.0, 0.0, 0.0), point(fx, fy, 0.0)};
  out.markers.push_back(std::move(wall));
  out.markers.push_back(std::move(arrow));
  wall_shown_ = true;
  return out;
}

void VisualizationLogic::check_gpis(const tactile_msgs::msg::GpisMap& msg) {
  const char* t = "tactile_msgs/msg/GpisMap";
  const auto cells = static_cast<std::size_t>(msg.width) * static_cast<std::size_t>(msg.height);
  if (msg.mean.size() != cells)
    throw InputError(where(t, "mean") + "has " + std::to_string(msg.mean.size()) + " values, width * height = " +
                     std::to_string(msg.width) + " * " + std::to_string(msg.height) + " = " + std::to_string(cells));
  if (msg.variance.size() != cells)
    throw InputError(where(t, "variance") + "has " + std::to_string(msg.variance.size()) +
                     " values, width * height = " + std::to_string(cells));
  if (cells > 0 && (!(msg.resolution > 0.0) || !std::isfinite(msg.resolution)))
    throw InputError(where(t, "resolution") + "must be finite and > 0, got " + std::to_string(msg.resolution));
  if (cells > 0 && (!std::isfinite(msg.origin_x) || !std::isfinite(msg.origin_y)))
    throw InputError(where(t, "origin_x/origin_y") + "must be finite");
  if (msg.training_labels.size() != msg.training_points.size())
    throw InputError(where(t, "training_labels") + "has " + std::to_string(msg.training_labels.size()) +
                     " labels for " + std::to_string(msg.training_points.size()) + " training_points");
  for (std::size_t i = 0; i < msg.training_labels.size(); ++i) {
    if (msg.training_labels[i] != 0 && msg.training_labels[i] != -1)
      throw InputError(where(t, "training_labels[" + std::to_string(i) + "]") + "must be 0 (surface) or -1 (interior), got " +
                       std::to_string(msg.training_labels[i]));
  }
  if (!msg.contour.empty() && (msg.contour_starts.empty() || msg.contour_starts.front() != 0))
    throw InputError(where(t, "contour_starts") + "must start with 0 for " + std::to_string(msg.contour.size()) +
                     " contour points");
  for (std::size_t i = 0; i < msg.contour_starts.size(); ++i) {
    const uint32_t s = msg.contour_starts[i];
    if (s >= msg.contour.size() || (i > 0 && s <= msg.contour_starts[i - 1]))
      throw InputError(where(t, "contour_starts[" + std::to_string(i) + "]") + "= " + std::to_string(s) +
                       ": must increase and be < contour size " + std::to_string(msg.contour.size()));
  }
}

VisualizationLogic::MarkerArray VisualizationLogic::on_gpis_map(const tactile_msgs::msg::GpisMap& msg) {
  check_gpis(msg);
  MarkerArray out;
  const auto& stamp = msg.header.stamp;
  const std::string& frame = msg.header.frame_id;
  // Contours: one LINE_STRIP each (ids 0.. in order; a contour of fewer than 2 finite
  // points is not drawn), the ids of the previous map's extra contours deleted.
  start(contour_src_, kNsGpisContour, out);
  int id = 0;
  for (std::size_t i = 0; i < msg.contour_starts.size(); ++i) {
    const std::size_t begin = msg.contour_starts[i];
    const std::size_t end = i + 1 < msg.contour_starts.size() ? msg.contour_starts[i + 1] : msg.contour.size();
    Marker m = make(stamp, frame, kNsGpisContour, id, Marker::LINE_STRIP);
    m.scale.x = params_.line_width;
    m.color = kContour;
    for (std::size_t k = begin; k < end; ++k) {
      if (finite(msg.contour[k])) {
        m.points.push_back(msg.contour[k]);
      } else {
        ++stats_.nonfinite_dropped;
      }
    }
    if (m.points.size() < 2) continue;
    out.markers.push_back(std::move(m));
    ++id;
  }
  for (int stale = id; stale <= contour_src_.max_id; ++stale) out.markers.push_back(remove(stamp, frame, kNsGpisContour, stale));
  contour_src_.max_id = id - 1;
  // Training points coloured by label.
  start(training_src_, kNsGpisTraining, out);
  Marker tp = make(stamp, frame, kNsGpisTraining, 0, Marker::POINTS);
  tp.scale.x = params_.point_size;
  tp.scale.y = params_.point_size;
  tp.color = kSurface;
  for (std::size_t i = 0; i < msg.training_points.size(); ++i) {
    if (!finite(msg.training_points[i])) {
      ++stats_.nonfinite_dropped;
      continue;
    }
    tp.points.push_back(msg.training_points[i]);
    tp.colors.push_back(msg.training_labels[i] == 0 ? kSurface : kInterior);
  }
  if (!tp.points.empty()) {
    out.markers.push_back(std::move(tp));
    training_src_.max_id = 0;
  } else if (training_src_.max_id >= 0) {
    out.markers.push_back(remove(stamp, frame, kNsGpisTraining, 0));
    training_src_.max_id = -1;
  }
  // Corners.
  start(corners_src_, kNsGpisCorners, out);
  Marker c = make(stamp, frame, kNsGpisCorners, 0, Marker::SPHERE_LIST);
  uniform_scale(c, 2.0 * params_.point_size);
  c.color = kCorner;
  for (const auto& p : msg.corners) {
    if (finite(p)) {
      c.points.push_back(p);
    } else {
      ++stats_.nonfinite_dropped;
    }
  }
  if (!c.points.empty()) {
    out.markers.push_back(std::move(c));
    corners_src_.max_id = 0;
  } else if (corners_src_.max_id >= 0) {
    out.markers.push_back(remove(stamp, frame, kNsGpisCorners, 0));
    corners_src_.max_id = -1;
  }
  return out;
}

VisualizationLogic::MarkerArray VisualizationLogic::on_exploration_target(
    const tactile_msgs::msg::ExplorationTarget& msg) {
  MarkerArray out;
  start(target_src_, kNsGpisTarget, out);
  if (!finite(msg.target)) {
    ++stats_.nonfinite_dropped;
    if (target_src_.max_id >= 0) out.markers.push_back(remove(msg.header.stamp, msg.header.frame_id, kNsGpisTarget, 0));
    target_src_.max_id = -1;
    return out;
  }
  Marker m = make(msg.header.stamp, msg.header.frame_id, kNsGpisTarget, 0, Marker::SPHERE);
  m.pose.position = msg.target;
  uniform_scale(m, params_.target_diameter);
  m.color = msg.exit_found ? kExit : kTarget;
  out.markers.push_back(std::move(m));
  target_src_.max_id = 0;
  return out;
}

VisualizationLogic::MarkerArray VisualizationLogic::on_collision(const tactile_msgs::msg::CollisionEvent& msg) {
  MarkerArray out;
  if (!finite(msg.point) || !std::isfinite(msg.normal.x) || !std::isfinite(msg.normal.y) ||
      !std::isfinite(msg.normal.z)) {
    ++stats_.nonfinite_dropped;
    return out;
  }
  History& h = collisions_;
  if (h.frame_id != msg.header.frame_id) {
    h.points.clear();
    h.colors.clear();
    h.lines.clear();
    h.frame_id = msg.header.frame_id;
  }
  push(h, msg.point, 2);
  const std::string& part = msg.part;
  h.colors.push_back(part == "body" ? kBody : part == "guard" ? kGuard : part.rfind("arm", 0) == 0 ? kArm : kOther);
  const double n = params_.normal_length;
  h.lines.push_back(msg.point);
  h.lines.push_back(point(msg.point.x + n * msg.normal.x, msg.point.y + n * msg.normal.y, msg.point.z + n * msg.normal.z));
  start(collision_src_, kNsCollisions, out);
  Marker s = make(msg.header.stamp, h.frame_id, kNsCollisions, 0, Marker::SPHERE_LIST);
  uniform_scale(s, params_.collision_diameter);
  s.color = kBody;
  s.points = h.points;
  s.colors = h.colors;
  Marker l = make(msg.header.stamp, h.frame_id, kNsCollisions, 1, Marker::LINE_LIST);
  l.scale.x = params_.line_width;
  l.color = kBody;
  l.points = h.lines;
  l.colors.reserve(h.colors.size() * 2);
  for (const auto& c : h.colors) {
    l.colors.push_back(c);
    l.colors.push_back(c);
  }
  out.markers.push_back(std::move(s));
  out.markers.push_back(std::move(l));
  return out;
}

VisualizationLogic::MarkerArray VisualizationLogic::on_localization(const tactile_msgs::msg::LocalizationResult& msg) {
  MarkerArray out;
  const bool contact = msg.contact_valid && !msg.contact_frame_id.empty() && finite(msg.contact_point);
  if (msg.contact_valid && msg.contact_frame_id.empty()) ++stats_.contacts_without_frame;
  if (msg.contact_valid && !finite(msg.contact_point)) ++stats_.nonfinite_dropped;
  if (!contact && localization_contact_shown_) {
    start(localization_src_, kNsLocalization, out);
    out.markers.push_back(remove(msg.header.stamp, msg.header.frame_id, kNsLocalization, 0));
    localization_contact_shown_ = false;
  }
  if (!due(localization_src_, tactile_common::from_stamp(msg.header.stamp), contact && !localization_contact_shown_)) return out;
  start(localization_src_, kNsLocalization, out);
  if (contact) {
    Marker c = make(msg.header.stamp, msg.contact_frame_id, kNsLocalization, 0, Marker::SPHERE);
    c.pose.position = msg.contact_point;
    uniform_scale(c, params_.contact_diameter * 1.5);
    c.color = kLocalization;
    out.markers.push_back(std::move(c));
    localization_contact_shown_ = true;
  }
  const std::string& set_frame =
      msg.pose_set.header.frame_id.empty() ? msg.header.frame_id : msg.pose_set.header.frame_id;
  Marker set = make(msg.header.stamp, set_frame, kNsLocalization, 1, Marker::POINTS);
  set.scale.x = params_.point_size;
  set.scale.y = params_.point_size;
  set.color = kLocalization;
  set.color.a = 0.5f;
  for (const auto& pose : msg.pose_set.poses) {
    if (finite(pose.position)) {
      set.points.push_back(pose.position);
    } else {
      ++stats_.nonfinite_dropped;
    }
  }
  // An empty POINTS marker draws nothing: it replaces the previous set.
  out.markers.push_back(std::move(set));
  Marker best = make(msg.header.stamp, msg.header.frame_id, kNsLocalization, 2, Marker::ARROW);
  best.pose = msg.best_estimate;
  best.scale.x = 0.1;  // arrow length along the pose's x axis [m]
  best.scale.y = 2.0 * params_.line_width;
  best.scale.z = 2.0 * params_.line_width;
  best.color = kLocalization;
  if (finite(best.pose.position)) {
    out.markers.push_back(std::move(best));
  } else {
    ++stats_.nonfinite_dropped;
  }
  return out;
}

namespace {
nav_msgs::msg::OccupancyGrid grid_of(const tactile_msgs::msg::GpisMap& msg) {
  nav_msgs::msg::OccupancyGrid g;
  g.header = msg.header;
  g.info.map_load_time = msg.header.stamp;
  g.info.resolution = static_cast<float>(msg.resolution);
  g.info.width = msg.width;
  g.info.height = msg.height;
  // GpisMap: row-major, row 0 at origin_y, column 0 at origin_x; OccupancyGrid: row-major
  // from the cell at info.origin, x along columns: the same order, no copy-reordering.
  g.info.origin.position.x = msg.origin_x;
  g.info.origin.position.y = msg.origin_y;
  g.info.origin.orientation.w = 1.0;
  g.data.resize(msg.mean.size());
  return g;
}
}  // namespace

VisualizationLogic::Grid VisualizationLogic::mean_grid(const tactile_msgs::msg::GpisMap& msg) {
  check_gpis(msg);
  Grid g = grid_of(msg);
  for (std::size_t i = 0; i < msg.mean.size(); ++i) {
    const double v = msg.mean[i];
    if (!std::isfinite(v)) {
      g.data[i] = -1;
      ++stats_.grid_cells_unknown;
      continue;
    }
    g.data[i] = static_cast<int8_t>(std::lround(50.0 + 50.0 * std::clamp(v / params_.mean_range, -1.0, 1.0)));
  }
  return g;
}

VisualizationLogic::Grid VisualizationLogic::variance_grid(const tactile_msgs::msg::GpisMap& msg) {
  check_gpis(msg);
  Grid g = grid_of(msg);
  for (std::size_t i = 0; i < msg.variance.size(); ++i) {
    const double v = msg.variance[i];
    if (!std::isfinite(v)) {
      g.data[i] = -1;
      ++stats_.grid_cells_unknown;
      continue;
    }
    g.data[i] = static_cast<int8_t>(std::lround(100.0 * std::clamp(v / params_.variance_max, 0.0, 1.0)));
  }
  return g;
}

VisualizationLogic::MarkerArray VisualizationLogic::reset() {
  MarkerArray out;
  for (Source* s : {&depth_src_, &wall_src_, &contour_src_, &training_src_, &corners_src_, &target_src_,
                    &collision_src_, &localization_src_})
    *s = Source{};
  for (const char* ns : {kNsWhiskerContacts, kNsWallEstimate, kNsGpisContour, kNsGpisTraining, kNsGpisCorners,
                         kNsGpisTarget, kNsCollisions, kNsLocalization}) {
    Marker m;
    m.ns = ns;
    m.action = Marker::DELETEALL;
    m.pose.orientation.w = 1.0;
    out.markers.push_back(m);
  }
  for (Source* s : {&depth_src_, &wall_src_, &contour_src_, &training_src_, &corners_src_, &target_src_,
                    &collision_src_, &localization_src_})
    s->started = true;
  contacts_[0] = History{};
  contacts_[1] = History{};
  collisions_ = History{};
  wall_shown_ = false;
  localization_contact_shown_ = false;
  return out;
}

}  // namespace tactile_viz
