// One function per graph of `tactile sim`, each defined in its own file.
#pragma once

#include "tactile_cli/sim_graph.hpp"

namespace tactile_cli::graphs {

GraphInfo none_graph();         // none.cpp
GraphInfo pilot_graph();        // pilot.cpp
GraphInfo whisker_fsm_graph();  // whisker_fsm.cpp
GraphInfo gpis_explore_graph();  // gpis_explore.cpp
GraphInfo xplorer_graph();      // xplorer.cpp
GraphInfo whisker_fsm_crtp_graph();  // whisker_fsm_crtp.cpp
GraphInfo wall_effect_graph();  // wall_effect.cpp
GraphInfo wall_effect_nav_graph();  // wall_effect_nav.cpp
GraphInfo whisker_stage_graph();  // whisker_stage.cpp

}  // namespace tactile_cli::graphs
