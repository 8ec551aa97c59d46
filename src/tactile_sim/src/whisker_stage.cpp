#include "tactile_sim/whisker_stage.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

namespace tactile_sim {

namespace wl = whisker_localization;

void WhiskerStageParams::validate() const {
  beam.validate();
  auto positive = [](double v, const char* f) {
    if (!(v > 0.0) || !std::isfinite(v))
      throw std::invalid_argument(std::string("WhiskerStageParams.") + f + ": must be finite and > 0, got " + std::to_string(v));
  };
  positive(speed, "speed");
  positive(yaw_rate, "yaw_rate");
  positive(sample_rate_hz, "sample_rate_hz");
  positive(pin_radius, "pin_radius");
  if (!(noise_relative >= 0.0 && noise_relative < 1.0))
    throw std::invalid_argument("WhiskerStageParams.noise_relative: must be in [0, 1), got " + std::to_string(noise_relative));
  if (!(noise_absolute >= 0.0) || !std::isfinite(noise_absolute))
    throw std::invalid_argument("WhiskerStageParams.noise_absolute: must be finite and >= 0, got " + std::to_string(noise_absolute));
}

WhiskerStage::WhiskerStage(const WhiskerStageParams& params, const Vec3& position, double yaw, uint64_t seed)
    : params_(params), rng_(seed) {
  params_.validate();
  solver_ = std::make_unique<wl::ElasticaSolver>(params_.beam);
  state_.position = position;
  yaw_ = yaw;
  state_.orientation = Quat(Eigen::AngleAxisd(yaw, Vec3::UnitZ()));
  setpoint_ = position;
  yaw_setpoint_ = yaw;
}

WhiskerStage::~WhiskerStage() = default;

void WhiskerStage::set_setpoint(const Vec3& position, double yaw) {
  setpoint_ = position;
  yaw_setpoint_ = yaw;
}

void WhiskerStage::step(double dt) {
  const Vec3 d = setpoint_ - state_.position;
  const double n = d.norm(), max_step = params_.speed * dt;
  const Vec3 move = n <= max_step ? d : d * (max_step / n);
  state_.position += move;
  state_.velocity = move / dt;
  const double dy = wl::wrap_angle(yaw_setpoint_ - yaw_);
  const double turn = std::clamp(dy, -params_.yaw_rate * dt, params_.yaw_rate * dt);
  yaw_ = wl::wrap_angle(yaw_ + turn);
  state_.angular_velocity = Vec3(0.0, 0.0, turn / dt);
  state_.orientation = Quat(Eigen::AngleAxisd(yaw_, Vec3::UnitZ()));
}

std::vector<std::vector<std::array<double, 2>>> wall_polylines(const Arena& arena) {
  // Wall segments of one obstacle that continue each other form a polyline.
  std::vector<std::vector<std::array<double, 2>>> lines;
  int last_obstacle = -1;
  Vec2 last_b(NAN, NAN);
  for (const Wall& w : arena.walls()) {
    const bool continues = !lines.empty() && w.obstacle_id == last_obstacle && (w.a - last_b).norm() < 1e-12;
    if (!continues) lines.push_back({{w.a.x(), w.a.y()}});
    lines.back().push_back({w.b.x(), w.b.y()});
    last_obstacle = w.obstacle_id;
    last_b = w.b;
  }
  return lines;
}

void WhiskerStage::build_map(const Arena& arena) {
  const auto lines = wall_polylines(arena);
  if (!lines.empty()) walls_ = std::make_unique<wl::BoundaryMap>(lines, 0.001);
  pin_side_.assign(arena.cylinders().size(), 0);
  map_built_ = true;
}

double WhiskerStage::noisy(double m) {
  if (params_.noise_bounded) {
    std::uniform_real_distribution<double> u(-params_.noise_relative, params_.noise_relative);
    return m * (1.0 + u(rng_));
  }
  std::normal_distribution<double> g(0.0, 1.0);
  const double a = g(rng_), b = g(rng_);
  return m * (1.0 + params_.noise_relative * a) + params_.noise_absolute * b;
}

WhiskerStage::Reading WhiskerStage::sense(const Arena& arena) {
  if (!map_built_) build_map(arena);
  Reading r;
  const double L = params_.beam.length;
  const double c = std::cos(yaw_), s = std::sin(yaw_);
  const Vec2 base = state_.position.head<2>();
  // Pins (002 Table I poles): point mode at the pin's centre.
  const auto& cyl = arena.cylinders();
  for (std::size_t i = 0; i < cyl.size() && !r.contact; ++i) {
    if (cyl[i].radius > params_.pin_radius) continue;
    const Vec2 d = cyl[i].center - base;
    const double px = c * d.x() + s * d.y(), py = -s * d.x() + c * d.y();
    int& side = pin_side_[i];
    const double rad = cyl[i].radius;
    if (side == 0) {
      // Touch: the pin within its radius of the undeformed whisker; which
      // side it presses is decided when it leaves that band (2 = not yet).
      if (px > 0.0 && px < L && std::fabs(py) <= rad) side = 2;
      if (side == 0) continue;
    }
    if (side == 2 && std::fabs(py) > rad) side = py > 0.0 ? 1 : -1;
    double dy = py;
    if (side != 2) {
      // The pin presses the whisker toward `side` while it is on that side.
      if (side * py < -rad) {
        side = 0;
        continue;
      }
      dy = side * std::max(0.0, side * py);
    }
    if (std::fabs(dy) < 1e-12) {
      if (px <= 0.0 || px >= L) {
        side = 0;
        continue;
      }
      r.contact = true;
      r.contact_point = cyl[i].center;
      break;
    }
    const wl::BeamShape b = solver_->solve_point(px, dy);
    if (!b.ok) {  // beyond the whisker's reach: slipped off the tip
      side = 0;
      continue;
    }
    r.contact = true;
    r.m0_true = b.base_moment;
    r.contact_point = cyl[i].center;
  }
  // Walls: tip contact.
  if (!r.contact && walls_) {
    const wl::WallContact w = wl::tip_wall_contact(*solver_, *walls_, wl::Pose2{base.x(), base.y(), yaw_});
    if (w.contact) {
      r.contact = true;
      r.tip = true;
      r.ok = w.ok;
      r.m0_true = w.ok ? w.m0 : 0.0;
      r.contact_point = Vec2(w.tip_x, w.tip_y);
    }
  }
  r.m0 = noisy(r.m0_true);
  return r;
}

}  // namespace tactile_sim
