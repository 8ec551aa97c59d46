// libFuzzer harness of the YAML loaders a user feeds by hand: arbitrary bytes as a scenario
// file (tactile_sim::load_scenario_from_string, then its arena and SimLogic's fault checks,
// where the simulator is built), as an arena file (Arena::from_yaml_text) and as a node
// parameter file (tactile_common::load_node_parameters_from_string against defaults of every
// type). Each must succeed or throw its error type (ScenarioError, ArenaError, ParamError, or a
// vehicle Params::validate()'s std::invalid_argument): no crash, no
// other exception, no sanitizer report, no allocation sized by a number in the file (a
// duration or rate is bounded before the simulator allocates anything). Seed corpus:
// fuzz/corpus/fuzz_scenario (shipped scenarios and arenas, and past findings).
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "tactile_common/parameters.hpp"
#include "tactile_sim/arena.hpp"
#include "tactile_sim/logic/sim_logic.hpp"
#include "tactile_sim/scenario.hpp"

namespace {

const tactile_common::ParamMap& defaults() {
  static const tactile_common::ParamMap d = [] {
    tactile_common::ParamMap m("fuzz_node", "defaults");
    m.set("rate_hz", 50.0);
    m.set("window", static_cast<int64_t>(3));
    m.set("enabled", true);
    m.set("topic", std::string("/x"));
    m.set("gains", std::vector<double>{1.0, 2.0});
    m.set("names", std::vector<std::string>{"a", "b"});
    return m;
  }();
  return d;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const auto scenario = tactile_sim::load_scenario_from_string(text, "fuzz.yaml", ".");
    // Building the simulator parses the arena and checks the faults against its topics; it
    // allocates nothing sized by duration_s (bounded by the loader anyway).
    tactile_sim::SimLogic sim(scenario, scenario.seed);
  } catch (const tactile_sim::ScenarioError&) {
  } catch (const tactile_sim::ArenaError&) {
  } catch (const tactile_common::ParamError&) {
  } catch (const std::invalid_argument&) {  // a vehicle Params::validate() naming the field
  }
  try {
    (void)tactile_sim::Arena::from_yaml_text(text, "fuzz_arena.yaml");
  } catch (const tactile_sim::ArenaError&) {
  }
  try {
    (void)tactile_common::load_node_parameters_from_string(text, "fuzz_params.yaml", "fuzz_node", defaults());
  } catch (const tactile_common::ParamError&) {
  }
  return 0;
}
