#include "graphs.hpp"

#include <stdexcept>

namespace tactile_cli {

const std::vector<GraphInfo>& sim_graphs() {
  // One line per graph.
  static const std::vector<GraphInfo> table = {
      graphs::none_graph(),
      graphs::pilot_graph(),
      graphs::whisker_fsm_graph(),
      graphs::gpis_explore_graph(),
      graphs::xplorer_graph(),
      graphs::whisker_fsm_crtp_graph(),
      graphs::wall_effect_graph(),
      graphs::wall_effect_nav_graph(),
      graphs::whisker_stage_graph(),
  };
  return table;
}

const GraphInfo& find_sim_graph(const std::string& name, const std::string& source) {
  std::string known;
  for (const auto& g : sim_graphs()) {
    if (g.name == name) return g;
    known += (known.empty() ? "" : ", ") + g.name;
  }
  throw std::runtime_error(source + ": graph: unknown graph '" + name + "' (" + known + ")");
}

}  // namespace tactile_cli
