#include "whisker_localization/whisker_localization_logic.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "tactile_common/time.hpp"
#include "whisker_localization/stage_sim.hpp"
#include "tactile_common/geometry.hpp"

namespace whisker_localization {

using tactile_common::ParamMap;

namespace {

geometry_msgs::msg::Pose to_pose(const Pose2& p) {
  geometry_msgs::msg::Pose m;
  m.position.x = p.x;
  m.position.y = p.y;
  m.position.z = 0.0;
  m.orientation.x = 0.0;
  m.orientation.y = 0.0;
  m.orientation.z = std::sin(0.5 * p.theta);
  m.orientation.w = std::cos(0.5 * p.theta);
  return m;
}

}  // namespace

void WhiskerLocalizationLogic::Params::validate() const {
  beam.validate();
  localizer.validate();
  if (!(map_spacing > 0.0) || !std::isfinite(map_spacing))
    throw std::invalid_argument("WhiskerLocalizationLogic.map_spacing: must be finite and > 0, got " + std::to_string(map_spacing));
  if (!(fillet_radius > 0.0)) throw std::invalid_argument("WhiskerLocalizationLogic.fillet_radius: must be > 0, got " + std::to_string(fillet_radius));
  if (!(leg > 0.0)) throw std::invalid_argument("WhiskerLocalizationLogic.leg: must be > 0, got " + std::to_string(leg));
  for (const auto& [field, v] : {std::pair<const char*, double>{"prior_x", prior_x}, {"prior_y", prior_y},
                                  {"prior_yaw", prior_yaw}}) {
    if (!std::isfinite(v))
      throw std::invalid_argument(std::string("WhiskerLocalizationLogic.") + field + ": must be finite, got " +
                                  std::to_string(v));
  }
  if (input != "moment" && input != "flux")
    throw std::invalid_argument("WhiskerLocalizationLogic.input: must be \"moment\" or \"flux\", got \"" + input + "\"");
  if (hall_coefficients.empty() || hall_coefficients.size() > 10)
    throw std::invalid_argument("WhiskerLocalizationLogic.hall_coefficients: must have 1 to 10 elements, got " +
                                std::to_string(hall_coefficients.size()));
  for (double c : hall_coefficients) {
    if (!std::isfinite(c)) throw std::invalid_argument("WhiskerLocalizationLogic.hall_coefficients: must be finite");
  }
  if (!(contact_threshold >= 0.0)) throw std::invalid_argument("WhiskerLocalizationLogic.contact_threshold: must be >= 0, got " + std::to_string(contact_threshold));
  if (!(min_step >= 0.0) || !std::isfinite(min_step)) throw std::invalid_argument("WhiskerLocalizationLogic.min_step: must be finite and >= 0, got " + std::to_string(min_step));
  if (!(max_odom_age_s > 0.0)) throw std::invalid_argument("WhiskerLocalizationLogic.max_odom_age_s: must be > 0, got " + std::to_string(max_odom_age_s));
}

ParamMap WhiskerLocalizationLogic::default_parameters() {
  using tactile_common::at_least;
  using tactile_common::choice;
  using tactile_common::closed;
  using tactile_common::paper;
  using tactile_common::ParamRange;
  using tactile_common::positive;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  // "> 0" and ">= 0" without a finite check: validate() takes inf too (inf = never stale, never a contact).
  const ParamRange above_zero{0.0, kInf, true, false};
  const ParamRange from_zero{0.0, kInf, false, false};
  const ParamRange any_finite{-kInf, kInf, true, true};  // (-inf, inf): checked finite only
  const Params d;
  ParamMap m(kNodeName, "defaults");
  // The localizer's parameter spec: value, description (from the Params comments; README
  // "Parameters"), unit, the range params_from()/validate() take for the key alone, and none
  // live: the beam model, the map and the pose set are built at start, so `ros2 param set`
  // refuses every key (read-only).
  m.set("beam.length", d.beam.length, {"L, whisker length (002 Sec. V-A: 75 mm)", "m", positive(), false,
        paper("002 Sec. V-A: L = 75 mm")});
  m.set("beam.youngs_modulus", d.beam.youngs_modulus,
        {"E, Young's modulus (002 Sec. V-A: nitinol, 52 GPa)", "Pa", positive(), false,
         paper("002 Sec. V-A: nitinol, E = 52 GPa")});
  m.set("beam.moment_of_inertia", d.beam.moment_of_inertia,
        {"I at the base (002 Sec. V-A: pi d^4 / 64, d = 0.58 mm)", "m^4", positive(), false,
         paper("002 Sec. V-A: pi d^4 / 64, d = 0.58 mm")});
  m.set("beam.taper_ratio", d.beam.taper_ratio,
        {"tip-to-base diameter ratio of a linear taper; 1: uniform wire", "", ParamRange{0.0, 1.0, true, false},
         false, paper("002 Sec. V-A: a uniform wire")});
  m.set("beam.n_segments", static_cast<int64_t>(d.beam.n_segments),
        {"RK4 steps over the loaded part of the beam (choice; 16 already within 1 um)", "", closed(4, 100000),
         false, choice()});
  m.set("contact_tolerance", d.localizer.contact_tolerance,
        {"a projected contact point must lie this close to the map boundary (choice: best of 0.2-0.5 mm in the "
         "Table II SITL)", "m", positive(), false, choice("best of 0.2-0.5 mm in the Table II SITL")});
  m.set("match_angle", d.localizer.match_angle,
        {"boundary-slope tolerance of the set intersection (choice: 3 deg)", "rad", positive(), false, choice()});
  m.set("epsilon", d.localizer.epsilon,
        {"possibilistic bound as a fraction of the observation (002 eq. 24: 5 %)", "",
         ParamRange{0.0, 1.0, false, true}, false, paper("002 eq. 24: 5 %")});
  m.set("epsilon_samples", static_cast<int64_t>(d.localizer.epsilon_samples),
        {"samples across the possibilistic bounds of the observation and of phi_E (choice)", "",
         closed(1, 1000), false, choice()});
  m.set("possibilistic", d.localizer.possibilistic,
        {"false: deterministic preimages (002 Sec. VII-B); true: possibilistic (002 Sec. VII-C, eq. 23-25)", "",
         {}, false, paper("002 Sec. VII-B deterministic; Sec. VII-C, eq. 23-25")});
  m.set("slope_samples", static_cast<int64_t>(d.localizer.slope_samples),
        {"contact points that estimate the boundary slope phi_E (002 Sec. VII-A/D: 2 to 5)", "", closed(2, 50),
         false, paper("002 Sec. VII-A/D: 2 to 5")});
  m.set("min_clearance", d.localizer.min_clearance,
        {"the base must lie at least this far on the free side of the boundary (choice)", "m", from_zero, false,
         choice()});
  m.set("heading_samples", static_cast<int64_t>(d.localizer.heading_samples),
        {"heading hypotheses per aligned pose when a set is (re)built (choice)", "", closed(1, 101), false, choice()});
  m.set("heading_spread", d.localizer.heading_spread,
        {"... over +- this about the contact point (choice: about 3 sigma of phi_E at 0.5 % noise)", "rad",
         ParamRange{0.0, 0.5, false, true}, false, choice()});
  m.set("prior_radius", d.localizer.prior_radius,
        {"only poses within this of the prior start the set (002 Sec. VII-D; choice: 30 mm); <= 0: the whole "
         "map; finite", "m", {}, false, choice()});
  m.set("mode_radius", d.localizer.mode_radius,
        {"neighbourhood of the mode used as the best estimate (choice: 2 mm)", "m", above_zero, false, choice()});
  m.set("refine_passes", static_cast<int64_t>(d.localizer.refine_passes),
        {"shape refinement passes, force along the estimated boundary normal (choice)", "", closed(0, 10), false,
         choice()});
  m.set("map_file", d.map_file,
        {"known map: YAML polylines: [[[x, y], ...], ...], free space on the left; \"\": the Table II concave "
         "corner (fillet_radius, leg)", "", {}, false, paper("002 Table II: concave corner by default")});
  m.set("map_spacing", d.map_spacing,
        {"boundary discretisation (002 Sec. VII-B: 1 mm)", "m", positive(), false, paper("002 Sec. VII-B: 1 mm")});
  m.set("fillet_radius", d.fillet_radius,
        {"default map: radius of the concave arc (choice)", "m", above_zero, false, choice()});
  m.set("leg", d.leg, {"default map: length of the straight floor and wall (choice)", "m", above_zero, false,
        choice()});
  m.set("use_prior", d.use_prior, {"start from a known pose prior_x/y/yaw (002 Sec. VII-D)", "", {}, false,
        paper("002 Sec. VII-D: sweeps start at a known location")});
  m.set("prior_x", d.prior_x, {"known start x (use_prior); finite", "m", any_finite, false, choice()});
  m.set("prior_y", d.prior_y, {"known start y (use_prior); finite", "m", any_finite, false, choice()});
  m.set("prior_yaw", d.prior_yaw, {"known start heading (use_prior); finite", "rad", any_finite, false, choice()});
  m.set("input", d.input,
        {"what torque.z carries: moment (M(0) [N m]) or flux (Hall flux density B [mT], 002 Sec. V-B)", "", {},
         false, paper("002 Sec. V-B: Hall flux density or M(0)")});
  m.set("hall_coefficients", d.hall_coefficients,
        {"M(0) = c0 + c1 B + c2 B^2 + ... [N m, B in mT] (002 Sec. V-B, HallCalibration); 1 to 10 finite "
         "values", "", {}, false, choice("identity until fitted with HallCalibration (002 Sec. V-B)")});
  m.set("contact_threshold", d.contact_threshold,
        {"|M(0)| below this is no contact (choice: 5x a 0.2 uN m noise floor)", "N m", from_zero, false, choice()});
  m.set("max_odom_age_s", d.max_odom_age_s,
        {"odometry older than this at a moment sample is stale (choice)", "s", above_zero, false, choice()});
  m.set("min_step", d.min_step,
        {"a contact sample is localized only after this much base travel since the previous one (002 Sec. "
         "VII-D: steps below 1 mm; choice); 0: every sample", "m", at_least(0.0), false,
         choice("002 Sec. VII-D steps below 1 mm; 0: every sample")});
  return m;
}

WhiskerLocalizationLogic::Params WhiskerLocalizationLogic::params_from(const ParamMap& m) {
  Params p;
  p.beam.length = m.get_double("beam.length");
  p.beam.youngs_modulus = m.get_double("beam.youngs_modulus");
  p.beam.moment_of_inertia = m.get_double("beam.moment_of_inertia");
  p.beam.taper_ratio = m.get_double("beam.taper_ratio");
  p.beam.n_segments = m.get_int("beam.n_segments", 4, 100000);
  p.localizer.contact_tolerance = m.get_double("contact_tolerance");
  p.localizer.match_angle = m.get_double("match_angle");
  p.localizer.epsilon = m.get_double("epsilon");
  p.localizer.epsilon_samples = m.get_int("epsilon_samples", 1, 1000);
  p.localizer.possibilistic = m.get_bool("possibilistic");
  p.localizer.slope_samples = m.get_int("slope_samples", 2, 50);
  p.localizer.min_clearance = m.get_double("min_clearance");
  p.localizer.heading_samples = m.get_int("heading_samples", 1, 101);
  p.localizer.heading_spread = m.get_double("heading_spread");
  p.localizer.prior_radius = m.get_double("prior_radius");
  p.localizer.mode_radius = m.get_double("mode_radius");
  p.localizer.refine_passes = m.get_int("refine_passes", 0, 10);
  p.map_file = m.get_string("map_file");
  p.map_spacing = m.get_double("map_spacing");
  p.fillet_radius = m.get_double("fillet_radius");
  p.leg = m.get_double("leg");
  p.use_prior = m.get_bool("use_prior");
  p.prior_x = m.get_double("prior_x");
  p.prior_y = m.get_double("prior_y");
  p.prior_yaw = m.get_double("prior_yaw");
  p.input = m.get_string("input");
  p.hall_coefficients = m.get_double_array("hall_coefficients");
  p.contact_threshold = m.get_double("contact_threshold");
  p.max_odom_age_s = m.get_double("max_odom_age_s");
  p.min_step = m.get_double("min_step");
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    // "<Struct>.<field>: <reason>" -> parameter <field> (beam.* for BeamParams).
    const std::string what = e.what();
    const auto dot = what.find('.');
    const auto colon = what.find(": ");
    std::string key = what.substr(dot + 1, colon - dot - 1);
    if (what.rfind("BeamParams", 0) == 0) key = "beam." + key;
    throw m.error(key, colon == std::string::npos ? what : what.substr(colon + 2));
  }
  return p;
}

std::vector<std::vector<std::array<double, 2>>> load_map_file(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const std::exception& e) {
    throw std::runtime_error(path + ": cannot read map: " + e.what());
  }
  const YAML::Node pls = root["polylines"];
  if (!pls || !pls.IsSequence() || pls.size() == 0) throw std::runtime_error(path + ": polylines: must be a non-empty list of polylines");
  std::vector<std::vector<std::array<double, 2>>> out;
  for (std::size_t i = 0; i < pls.size(); ++i) {
    const std::string key = path + ": polylines[" + std::to_string(i) + "]";
    if (!pls[i].IsSequence() || pls[i].size() < 2) throw std::runtime_error(key + ": must be a list of >= 2 [x, y] points");
    std::vector<std::array<double, 2>> pl;
    for (std::size_t j = 0; j < pls[i].size(); ++j) {
      const YAML::Node p = pls[i][j];
      if (!p.IsSequence() || p.size() != 2) throw std::runtime_error(key + "[" + std::to_string(j) + "]: must be [x, y]");
      try {
        pl.push_back({p[0].as<double>(), p[1].as<double>()});
      } catch (const YAML::Exception&) {
        throw std::runtime_error(key + "[" + std::to_string(j) + "]: x and y must be numbers");
      }
    }
    out.push_back(std::move(pl));
  }
  return out;
}

WhiskerLocalizationLogic::WhiskerLocalizationLogic(const Params& params) : params_(params) {
  params_.validate();
  std::vector<std::vector<std::array<double, 2>>> polylines;
  if (params_.map_file.empty()) {
    polylines = {concave_corner_polyline(params_.fillet_radius, params_.leg, params_.map_spacing)};
  } else {
    polylines = load_map_file(params_.map_file);
  }
  try {
    map_ = std::make_unique<BoundaryMap>(polylines, params_.map_spacing);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error((params_.map_file.empty() ? std::string("default map") : params_.map_file) + ": " + e.what());
  }
  solver_ = std::make_unique<ElasticaSolver>(params_.beam);
  localizer_ = std::make_unique<PreimageLocalizer>(*map_, *solver_, params_.localizer);
  if (params_.use_prior) localizer_->set_prior(Pose2{params_.prior_x, params_.prior_y, params_.prior_yaw});
}

void WhiskerLocalizationLogic::restart(const Pose2* prior) {
  localizer_->reset();
  if (prior) localizer_->set_prior(*prior);
  have_last_ = false;
}

void WhiskerLocalizationLogic::on_odometry(const nav_msgs::msg::Odometry& msg) {
  ++stats_.odom_received;
  const auto& p = msg.pose.pose;
  const double yaw = tactile_common::yaw_of(p.orientation);
  if (!std::isfinite(p.position.x) || !std::isfinite(p.position.y) || !std::isfinite(yaw)) {
    ++stats_.dropped_nonfinite;
    return;
  }
  odom_ = Pose2{p.position.x, p.position.y, yaw};
  odom_stamp_ = tactile_common::from_stamp(msg.header.stamp);
  have_odom_ = true;
}

WhiskerLocalizationLogic::Outputs WhiskerLocalizationLogic::on_moment(const geometry_msgs::msg::WrenchStamped& msg) {
  Outputs out;
  ++stats_.moments_received;
  double m0 = msg.wrench.torque.z;
  if (params_.input == "flux") {  // Hall flux density -> M(0) (002 Sec. V-B calibration)
    const double b = m0;
    m0 = 0.0;
    for (auto it = params_.hall_coefficients.rbegin(); it != params_.hall_coefficients.rend(); ++it) m0 = m0 * b + *it;
  }
  if (!std::isfinite(m0)) {
    ++stats_.dropped_nonfinite;
    return out;
  }
  const int64_t stamp = tactile_common::from_stamp(msg.header.stamp);
  if (have_last_ && stamp <= last_stamp_) {
    ++stats_.dropped_out_of_order;
    return out;
  }
  if (!have_odom_ || std::fabs(tactile_common::to_seconds(stamp - odom_stamp_)) > params_.max_odom_age_s) {
    ++stats_.dropped_no_odom;
    return out;
  }
  const bool contact = std::fabs(m0) >= params_.contact_threshold;
  if (contact && have_last_ && params_.min_step > 0.0 &&
      std::hypot(odom_.x - last_odom_.x, odom_.y - last_odom_.y) < params_.min_step) {
    ++stats_.skipped_small_motion;
    return out;
  }
  // Motion since the previous sample in the previous base frame (002 Sec. IV-D: T_local).
  Pose2 motion;
  if (have_last_) {
    const double c = std::cos(last_odom_.theta), s = std::sin(last_odom_.theta);
    const double dx = odom_.x - last_odom_.x, dy = odom_.y - last_odom_.y;
    motion = Pose2{c * dx + s * dy, -s * dx + c * dy, wrap_angle(odom_.theta - last_odom_.theta)};
  }
  have_last_ = true;
  last_stamp_ = stamp;
  last_odom_ = odom_;
  if (!contact) ++stats_.no_contact;
  const PreimageLocalizer::StepResult r = localizer_->step(motion, contact ? m0 : 0.0);
  stats_.resets = localizer_->resets();

  tactile_msgs::msg::LocalizationResult res;
  res.header.stamp = msg.header.stamp;
  res.header.frame_id = kMapFrame;
  res.contact_valid = r.contact && (r.geometry.cx != 0.0 || r.geometry.cy != 0.0);
  res.contact_point.x = r.geometry.cx;  // whisker base frame: the base moment's
  res.contact_frame_id = msg.header.frame_id;
  res.contact_point.y = r.geometry.cy;
  res.contact_point.z = 0.0;
  res.base_moment = m0;
  geometry_msgs::msg::PoseArray set;
  set.header = res.header;
  for (const auto& q : localizer_->set().poses) set.poses.push_back(to_pose(q));
  res.pose_set = set;
  if (!localizer_->set().empty()) {
    res.best_estimate = to_pose(r.best);
    res.spread = r.spread;
  } else {
    res.spread = std::nan("");
  }
  out.result = std::move(res);
  out.pose_set = std::move(set);
  ++stats_.published;
  return out;
}

}  // namespace whisker_localization
