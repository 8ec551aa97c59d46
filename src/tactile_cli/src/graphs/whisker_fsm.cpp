// Graph `whisker_fsm` (paper 000): TDORC x2 -> tactile_depth -> whisker
// wall-following FSM flying the whiskered Crazyflie to the scenario's target
// (metrics.target, arena frame), evaluated against the ground truth.
#include "graphs.hpp"

#include "tactile_cli/host_nodes.hpp"
#include "tactile_cli/whisker_eval.hpp"

namespace tactile_cli::graphs {

namespace {

class WhiskerFsmGraph : public SimGraph {
 public:
  explicit WhiskerFsmGraph(GraphContext& ctx) {
    add_whisker_front_end(ctx.host, ctx.overrides("tdorc_filter"), ctx.overrides("tactile_depth"));
    tactile_common::ParamMap extra;
    if (auto t = ctx.target()) {
      extra.set("target_x", t->x());
      extra.set("target_y", t->y());
    }
    fsm_ = add_whisker_fsm(ctx.host, ctx.overrides("whisker_fsm", extra));
    const auto& fp = fsm_->params().fsm;
    eval_ = std::make_unique<WallFollowingEvaluation>(ctx.host, *ctx.whisker_truth, fp.t_min, fp.t_max,
                                                      fp.whisker_spacing);
  }

  nlohmann::json metrics() const override {
    nlohmann::json m = eval_->metrics();
    m["target"] = {fsm_->params().target_x, fsm_->params().target_y};
    m["reached_target"] = *reached_goal();
    return m;
  }

  /// The FSM reached its target (000 Methods: land when the target is reached).
  std::optional<bool> reached_goal() const override {
    const auto state = fsm_->fsm().state();
    return state == tactile_fsm::FsmState::kLanding || state == tactile_fsm::FsmState::kLanded;
  }

  void decorate(TopView& view) const override {
    view.targets.emplace_back(fsm_->params().target_x, fsm_->params().target_y);
  }

 private:
  std::shared_ptr<tactile_fsm::WhiskerFsmLogic> fsm_;
  std::unique_ptr<WallFollowingEvaluation> eval_;
};

}  // namespace

GraphInfo whisker_fsm_graph() {
  GraphInfo g;
  g.name = "whisker_fsm";
  g.description = "TDORC -> tactile_depth -> whisker wall-following FSM to metrics.target (000)";
  g.vehicles = {tactile_sim::VehicleType::kWhiskerCrazyflie};
  g.nodes = {"tdorc_filter", "tactile_depth", "whisker_fsm"};
  g.metrics_key = "fsm";
  g.build = [](GraphContext& ctx) { return std::make_unique<WhiskerFsmGraph>(ctx); };
  return g;
}

}  // namespace tactile_cli::graphs
