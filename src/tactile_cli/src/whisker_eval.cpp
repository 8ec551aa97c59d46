#include "tactile_cli/whisker_eval.hpp"

#include <algorithm>
#include <cmath>

#include "tactile_cli/host_nodes.hpp"
#include "tactile_common/time.hpp"

namespace tactile_cli {

namespace {

struct ErrorStats {
  double sum_abs = 0.0, sum_sq = 0.0;
  size_t n = 0;
  void add(double e) {
    sum_abs += std::abs(e);
    sum_sq += e * e;
    ++n;
  }
  nlohmann::json mae() const { return n ? nlohmann::json(sum_abs / static_cast<double>(n)) : nlohmann::json(nullptr); }
  nlohmann::json rmse() const {
    return n ? nlohmann::json(std::sqrt(sum_sq / static_cast<double>(n))) : nlohmann::json(nullptr);
  }
};

}  // namespace

WhiskerTruth::WhiskerTruth(Host& host) {
  const char* topics[2] = {"/ground_truth/whisker/left/contact", "/ground_truth/whisker/right/contact"};
  for (int side = 0; side < 2; ++side) {
    auto* samples = &samples_[side];
    host.bus().subscribe<tactile_msgs::msg::WhiskerGroundTruth>(
        topics[side], [samples](const tactile_msgs::msg::WhiskerGroundTruth& m) {
          (*samples)[tactile_common::from_stamp(m.header.stamp)] = Sample{m.contact, m.depth};
        });
  }
}

const WhiskerTruth::Sample* WhiskerTruth::at(int side, int64_t stamp_ns) const {
  auto it = samples_[side].find(stamp_ns);
  return it == samples_[side].end() ? nullptr : &it->second;
}

DepthEvaluation::DepthEvaluation(Host& host, const WhiskerTruth& truth, const tactile_sim::Arena& arena,
                                 const tactile_common::ParamMap& base)
    : truth_(truth), arena_(arena) {
  static const std::pair<const char*, const char*> kModels[] = {
      {"mlp", "mlp"}, {"kf_simplified", "mlp_kf_simplified"}, {"kf_full", "mlp_kf_full"}};
  for (const auto& [estimator, name] : kModels) {
    const std::string topic = std::string("/evaluation/depth/") + name;
    tactile_common::ParamMap over = base;
    over.set("estimator", std::string(estimator));
    auto logic = add_tactile_depth(host, over, topic);
    spacing_ = logic->params().estimator.whisker_spacing;
    auto* store = &estimates_[name];
    host.bus().subscribe<tactile_msgs::msg::TactileDepth>(
        topic, [store](const tactile_msgs::msg::TactileDepth& m) { store->push_back(m); });
  }
}

nlohmann::json DepthEvaluation::metrics() const {
  nlohmann::json out;
  for (const auto& [name, estimates] : estimates_) {
    ErrorStats depth[2], orientation, reconstruction;
    for (const auto& e : estimates) {
      const int64_t t = tactile_common::from_stamp(e.header.stamp);
      const WhiskerTruth::Sample* tr[2] = {truth_.at(0, t), truth_.at(1, t)};
      const bool est_contact[2] = {e.contact_left, e.contact_right};
      const double est_depth[2] = {e.depth_left, e.depth_right};
      const geometry_msgs::msg::Point* points[2] = {&e.contact_point_left,
                                                    &e.contact_point_right};
      bool both = true;
      for (int s = 0; s < 2; ++s) {
        const bool true_contact = tr[s] && tr[s]->contact && std::isfinite(tr[s]->depth);
        both = both && true_contact && est_contact[s] && std::isfinite(est_depth[s]);
        if (!true_contact || !est_contact[s] || !std::isfinite(est_depth[s])) continue;
        depth[s].add((est_depth[s] - tr[s]->depth) * 1000.0);
        const tactile_sim::Hit h = arena_.closest(tactile_sim::Vec2(points[s]->x, points[s]->y), 10.0);
        if (h.hit) reconstruction.add(h.distance * 1000.0);
      }
      if (both && std::isfinite(e.wall_angle)) {
        const double truth_angle = std::atan((tr[0]->depth - tr[1]->depth) / spacing_);
        orientation.add((e.wall_angle - truth_angle) * 180.0 / M_PI);
      }
    }
    out[name] = {{"mae_left_mm", depth[0].mae()},          {"rmse_left_mm", depth[0].rmse()},
                 {"mae_right_mm", depth[1].mae()},         {"rmse_right_mm", depth[1].rmse()},
                 {"mae_orientation_deg", orientation.mae()}, {"mae_reconstruction_mm", reconstruction.mae()},
                 {"samples_left", depth[0].n},             {"samples_right", depth[1].n}};
  }
  return out;
}

namespace {
bool is_wall_following(const std::string& state) { return state.rfind("WALL_FOLLOWING", 0) == 0; }
}  // namespace

FsmStateLog::FsmStateLog(Host& host) {
  host.bus().subscribe<tactile_msgs::msg::FsmState>("/fsm_state", [this](const tactile_msgs::msg::FsmState& m) {
    if (m.state != state_) states_.emplace_back(tactile_common::from_stamp(m.header.stamp), m.state);
    state_ = m.state;
  });
}

FsmStateLog::Episode FsmStateLog::first_wall_following() const {
  Episode e;
  for (const auto& [t, state] : states_) {
    if (e.start_ns < 0 && is_wall_following(state)) e.start_ns = t;
    if (e.start_ns >= 0 && !is_wall_following(state)) {
      e.end_ns = t;
      break;
    }
  }
  return e;
}

size_t FsmStateLog::wall_following_episodes() const {
  size_t episodes = 0;
  bool prev = false;
  for (const auto& [t, state] : states_) {
    const bool wf = is_wall_following(state);
    if (wf && !prev) ++episodes;
    prev = wf;
  }
  return episodes;
}

nlohmann::json FsmStateLog::sweep_metrics(int64_t end_ns) const {
  const Episode e = first_wall_following();
  const auto seconds = [](int64_t ns) { return static_cast<double>(ns) / tactile_common::kNanosPerSecond; };
  nlohmann::json m;
  m["wall_following_episodes"] = wall_following_episodes();
  if (e.start_ns >= 0) {
    m["first_sweep_start_s"] = seconds(e.start_ns);
    m["first_sweep_s"] = seconds(std::max(e.end_ns >= 0 ? e.end_ns : end_ns, e.start_ns) - e.start_ns);
  } else {
    m["first_sweep_start_s"] = nullptr;
    m["first_sweep_s"] = 0.0;
  }
  return m;
}

WallFollowingEvaluation::WallFollowingEvaluation(Host& host, const WhiskerTruth& truth, double t_min, double t_max,
                                                 double spacing)
    : truth_(truth), t_min_(t_min), t_max_(t_max), spacing_(spacing), log_(host) {}

nlohmann::json WallFollowingEvaluation::metrics(int64_t end_ns) const {
  // Walk the 50 Hz truth samples of the left whisker (the right one has the
  // same stamps); the FSM state at each is the last transition at or before it.
  const auto& states = log_.transitions();
  size_t in_band = 0, wall_samples = 0, heading_n = 0;
  double heading_sum = 0.0;
  // First wall-following episode [start, end) (000 Fig. 6 sweeps).
  const FsmStateLog::Episode sweep = log_.first_wall_following();
  const int64_t window_end = sweep.start_ns + static_cast<int64_t>(kSweepWindowS * tactile_common::kNanosPerSecond);
  size_t sweep_samples = 0, sweep_in_band = 0;
  int64_t last_sample = -1;
  for (const auto& [t, left] : truth_.samples(0)) {
    if (end_ns >= 0 && t > end_ns) break;
    const WhiskerTruth::Sample* l = &left;
    const WhiskerTruth::Sample* r = truth_.at(1, t);
    if (!r) continue;
    auto it = std::upper_bound(states.begin(), states.end(), t, [](int64_t v, const auto& s) { return v < s.first; });
    if (it == states.begin()) continue;
    if (!is_wall_following(std::prev(it)->second)) continue;
    if (!l->contact && !r->contact) continue;
    ++wall_samples;
    last_sample = t;
    const bool ok_l = !l->contact || (l->depth >= t_min_ && l->depth <= t_max_);
    const bool ok_r = !r->contact || (r->depth >= t_min_ && r->depth <= t_max_);
    if (ok_l && ok_r) ++in_band;
    if (sweep.start_ns >= 0 && t >= sweep.start_ns && (sweep.end_ns < 0 || t < sweep.end_ns) && t < window_end) {
      ++sweep_samples;
      if (ok_l && ok_r) ++sweep_in_band;
    }
    if (l->contact && r->contact) {
      heading_sum += std::abs(std::atan((l->depth - r->depth) / spacing_)) * 180.0 / M_PI;
      ++heading_n;
    }
  }
  // An episode still running at the end lasts to end_ns, or else to the last
  // evaluated sample.
  nlohmann::json m = log_.sweep_metrics(end_ns >= 0 ? end_ns : last_sample);
  m["wall_following_contact_samples"] = wall_samples;
  m["depth_in_band_fraction"] = wall_samples ? nlohmann::json(static_cast<double>(in_band) / static_cast<double>(wall_samples))
                                             : nlohmann::json(nullptr);
  m["mean_abs_heading_error_deg"] =
      heading_n ? nlohmann::json(heading_sum / static_cast<double>(heading_n)) : nlohmann::json(nullptr);
  m["first_sweep_in_band_fraction"] =
      sweep_samples ? nlohmann::json(static_cast<double>(sweep_in_band) / static_cast<double>(sweep_samples))
                    : nlohmann::json(nullptr);
  m["final_state"] = log_.last_state();
  m["band_m"] = {t_min_, t_max_};
  return m;
}

}  // namespace tactile_cli
