// Graph `none`: the simulator alone (open-loop vehicles, hover tests).
#include "graphs.hpp"

namespace tactile_cli::graphs {

GraphInfo none_graph() {
  GraphInfo g;
  g.name = "none";
  g.description = "the simulator alone, no nodes";
  g.build = [](GraphContext&) { return std::make_unique<SimGraph>(); };
  return g;
}

}  // namespace tactile_cli::graphs
