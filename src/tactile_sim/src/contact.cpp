#include "tactile_sim/contact.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace tactile_sim {

void ContactParams::validate() const {
  if (!(friction_slip_speed > 0.0) || !std::isfinite(friction_slip_speed)) {
    throw std::invalid_argument("ContactParams.friction_slip_speed: must be > 0, got " +
                                std::to_string(friction_slip_speed));
  }
  if (!(release_gap >= 0.0) || !std::isfinite(release_gap)) {
    throw std::invalid_argument("ContactParams.release_gap: must be >= 0, got " +
                                std::to_string(release_gap));
  }
}

CircleContact::CircleContact(const ContactParams& params) : params_(params) {
  params_.validate();
  reset();
}

void CircleContact::reset() {
  in_episode_ = false;
  prev_count_ = 0;
  for (auto& n : prev_normal_) n.setZero();
}

ContactResult CircleContact::step(const Arena& arena, const Vec2& center, double radius,
                                  const Vec2& velocity) {
  constexpr int kMax = ContactParams::kMaxContacts;
  struct Candidate {
    Hit hit;
    double pen;  // penetration depth [m], negative = gap
  };
  Candidate cand[kMax];
  int n = 0;

  arena.for_each_within(center, radius + params_.release_gap, [&](const Hit& h) {
    Candidate c{h, radius - h.distance};
    // Thin walls: if the centre crossed the surface since the last step, the
    // normal flips; keep the side the circle came from (depth r + d).
    bool same_side = false, flipped = false;
    for (int i = 0; i < prev_count_; ++i) {
      if (prev_obstacle_[i] != h.obstacle_id) continue;
      const double dot = prev_normal_[i].dot(h.normal);
      if (dot > 0.0) same_side = true;
      if (dot < -0.5) flipped = true;
    }
    if (flipped && !same_side) {
      c.hit.normal = -h.normal;
      c.pen = radius + h.distance;
    }
    // Merge duplicates (both segments at a convex polyline vertex report the
    // same point and normal): keep the deeper.
    for (int i = 0; i < n; ++i) {
      if (cand[i].hit.obstacle_id == c.hit.obstacle_id &&
          cand[i].hit.normal.dot(c.hit.normal) > 0.999) {
        if (c.pen > cand[i].pen) cand[i] = c;
        return;
      }
    }
    if (n < kMax) {
      cand[n++] = c;
      return;
    }
    int shallowest = 0;
    for (int i = 1; i < n; ++i) {
      if (cand[i].pen < cand[shallowest].pen) shallowest = i;
    }
    if (c.pen > cand[shallowest].pen) cand[shallowest] = c;
  });

  ContactResult out;
  int deepest = -1;
  bool near = false;
  for (int i = 0; i < n; ++i) {
    const Candidate& c = cand[i];
    if (c.pen > -params_.release_gap) near = true;
    if (!(c.pen > 0.0)) continue;
    const Material& m = arena.material(c.hit.material);
    const Vec2& nrm = c.hit.normal;
    const double vn = velocity.dot(nrm);  // < 0: moving into the obstacle
    // Normal force: spring-damper on the penetration, never pulling.
    const double fn = std::max(0.0, m.stiffness * c.pen - m.damping * vn);
    // Coulomb friction against the tangential velocity, regularised: the
    // magnitude mu * N * |vt| / max(|vt|, v_slip) never exceeds mu * N.
    const Vec2 vt = velocity - vn * nrm;
    const double speed_t = vt.norm();
    const Vec2 ft = -m.friction * fn * vt / std::max(speed_t, params_.friction_slip_speed);
    out.force += fn * nrm + ft;
    out.normal_force += fn;
    out.friction_force += ft.norm();
    ++out.count;
    if (deepest < 0 || c.pen > cand[deepest].pen) deepest = i;
  }
  if (deepest >= 0) {
    const Candidate& c = cand[deepest];
    out.contact = true;
    out.penetration = c.pen;
    out.point = c.hit.point;
    out.normal = c.hit.normal;
    out.impact_speed = std::max(0.0, -velocity.dot(c.hit.normal));
    out.obstacle_id = c.hit.obstacle_id;
    out.material = c.hit.material;
  }
  out.began = out.contact && !in_episode_;
  in_episode_ = out.contact || (in_episode_ && near);

  prev_count_ = 0;
  for (int i = 0; i < n; ++i) {
    if (cand[i].pen > -params_.release_gap) {
      prev_obstacle_[prev_count_] = cand[i].hit.obstacle_id;
      prev_normal_[prev_count_] = cand[i].hit.normal;
      ++prev_count_;
    }
  }
  return out;
}

}  // namespace tactile_sim
