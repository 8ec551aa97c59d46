#include "tactile_cli/host_nodes.hpp"

#include "tactile_common/time.hpp"

namespace tactile_cli {

std::shared_ptr<whisker_driver::WhiskerDriverLogic> add_whisker_driver(
    Host& host, const std::string& ns, const tactile_common::ParamMap& over) {
  using Logic = whisker_driver::WhiskerDriverLogic;
  auto params = host.load_parameters(ns, Logic::kNodeName, Logic::default_parameters(), over);
  auto logic = std::make_shared<Logic>(Logic::params_from(params));
  const std::string out = resolve_topic(ns, Logic::kOutputTopic);
  Host* h = &host;
  Logic* l = logic.get();
  host.executor().add_timer(
      logic->period_ns(),
      [h, l, out](int64_t now_ns) {
        for (const auto& msg : l->on_timer(now_ns).pressure) h->bus().publish(out, msg, now_ns);
      },
      host.executor().now_ns());
  host.add_reporter([l, name = resolve_topic(ns, Logic::kNodeName)] {
    const auto s = l->stats();
    return NodeReport{name,
                      {{"published", s.published},
                       {"source_errors", s.source_errors},
                       {"sequence_gaps", s.sequence_gaps},
                       {"parse_lines", s.parse.lines},
                       {"parse_frames", s.parse.frames},
                       {"parse_dropped_lines", s.parse.dropped_lines()},
                       {"parse_dropped_frames", s.parse.dropped_frames()}}};
  });
  host.keep(logic);
  return logic;
}

std::shared_ptr<tdorc_filter::TdorcFilterLogic> add_tdorc_filter(
    Host& host, const std::string& ns, const tactile_common::ParamMap& over) {
  using Logic = tdorc_filter::TdorcFilterLogic;
  auto params = host.load_parameters(ns, Logic::kNodeName, Logic::default_parameters(), over);
  auto logic = std::make_shared<Logic>(Logic::params_from(params));
  const std::string out = resolve_topic(ns, Logic::kOutputTopic);
  Host* h = &host;
  Logic* l = logic.get();
  host.bus().subscribe<tactile_msgs::msg::WhiskerPressure>(
      resolve_topic(ns, Logic::kInputTopic), [h, l, out](const tactile_msgs::msg::WhiskerPressure& msg) {
        if (auto sig = l->on_pressure(msg)) h->bus().publish(out, *sig, h->executor().now_ns());
      });
  host.add_reporter([l, name = resolve_topic(ns, Logic::kNodeName)] {
    const auto& s = l->stats();
    return NodeReport{name,
                      {{"received", s.received},
                       {"published", s.published},
                       {"dropped_nonfinite", s.dropped_nonfinite},
                       {"dropped_wrong_whisker", s.dropped_wrong_whisker},
                       {"dropped_out_of_order", s.dropped_out_of_order},
                       {"resets_on_gap", s.resets_on_gap},
                       {"sequence_gaps", s.sequence_gaps}}};
  });
  host.keep(logic);
  return logic;
}

}  // namespace tactile_cli
