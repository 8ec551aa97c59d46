// Graph `pilot`: the scenario's scripted pilot flies the vehicle (any
// vehicle); on the whiskered Crazyflie the TDORC chain runs too, since the
// pilot's `until: contact` steps listen to the compensated signals.
#include "graphs.hpp"

#include <cmath>

#include "tactile_cli/host_nodes.hpp"

namespace tactile_cli::graphs {

namespace {

class PilotGraph : public SimGraph {
 public:
  PilotGraph(GraphContext& ctx) : steps_(ctx.scenario.pilot.size()) {
    if (ctx.scenario.vehicle == tactile_sim::VehicleType::kWhiskerCrazyflie) {
      add_whisker_front_end(ctx.host, ctx.overrides("tdorc_filter"), std::nullopt);  // no depth: signals only
    }
    pilot_ = std::make_shared<tactile_sim::ScriptedPilotLogic>(ctx.scenario.pilot, ctx.scenario.vehicle,
                                                                ctx.scenario.initial_position, ctx.scenario.initial_yaw);
    add_scenario_pilot(ctx.host, pilot_);
  }

  nlohmann::json metrics() const override {
    const auto& ps = pilot_->stats();
    return {{"finished", ps.finished},
            {"steps", steps_},
            {"steps_completed", ps.steps_completed},
            {"steps_timed_out", ps.steps_timed_out},
            {"contact_time_s",
             std::isfinite(ps.contact_time_s) ? nlohmann::json(ps.contact_time_s) : nlohmann::json(nullptr)}};
  }

  /// The pilot flew its whole script and no `until` timed out.
  std::optional<bool> reached_goal() const override {
    return pilot_->stats().finished && pilot_->stats().steps_timed_out == 0;
  }

 private:
  size_t steps_;
  std::shared_ptr<tactile_sim::ScriptedPilotLogic> pilot_;
};

}  // namespace

GraphInfo pilot_graph() {
  GraphInfo g;
  g.name = "pilot";
  g.description = "scripted pilot (setpoints, 'until' conditions); TDORC chain on the whiskered Crazyflie";
  // tactile_depth: the depth evaluation (metrics.depth_evaluation) runs on this graph.
  g.nodes = {"tdorc_filter", "tactile_depth"};
  g.metrics_key = "pilot";
  g.build = [](GraphContext& ctx) { return std::make_unique<PilotGraph>(ctx); };
  return g;
}

}  // namespace tactile_cli::graphs
