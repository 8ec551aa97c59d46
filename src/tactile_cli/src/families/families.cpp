#include "families.hpp"

namespace tactile_cli {

const std::vector<ScenarioFamily>& scenario_families() {
  // One line per family file.
  static const std::vector<ScenarioFamily> table = [] {
    std::vector<ScenarioFamily> t;
    for (auto* add : {&families::baffle_families, &families::room_families, &families::xplorer_object_families}) {
      for (auto& f : add()) t.push_back(std::move(f));
    }
    return t;
  }();
  return table;
}

}  // namespace tactile_cli
