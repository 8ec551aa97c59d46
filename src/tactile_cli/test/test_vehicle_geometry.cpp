// The vehicle geometry has one source: the simulated vehicles' parameter structs
// (tactile_sim), from which the frames, the static transforms and robot_description
// are built (tactile_sim/robot_model.hpp). The node configs that repeat a dimension for
// their own maths (whisker spacing and base position, the XPLORER hinge and arm) must
// say the same, or a depth, a wall angle or a slab would be computed for another
// vehicle than the one in RViz: this test reads each config file as its node does.
#include <gtest/gtest.h>

#include <string>

#include "gpis_explorer/gpis_explorer_logic.hpp"
#include "mapping_pcl/xplorer_map_logic.hpp"
#include "tactile_common/parameters.hpp"
#include "tactile_depth/tactile_depth_logic.hpp"
#include "tactile_fsm/whisker_fsm_logic.hpp"
#include "tactile_sim/robot_model.hpp"

namespace {

const std::string kConfig = TACTILE_CONFIG_DIR;

double config_value(const std::string& file, const char* node, const tactile_common::ParamMap& defaults,
                    const char* key) {
  return tactile_common::load_node_parameters(kConfig + "/" + file, node, defaults).get_double(key);
}

}  // namespace

TEST(VehicleGeometry, WhiskerNodeConfigsAgreeWithTheWhiskeredCrazyflie) {
  const tactile_sim::CrazyflieParams cf;
  const auto depth = tactile_depth::TactileDepthLogic::default_parameters();
  EXPECT_DOUBLE_EQ(config_value("tactile_depth.yaml", "tactile_depth", depth, "whisker_spacing"), cf.whisker_spacing);
  EXPECT_DOUBLE_EQ(config_value("tactile_depth.yaml", "tactile_depth", depth, "whisker_base_x"), cf.whisker_base_x);
  const auto fsm = tactile_fsm::WhiskerFsmLogic::default_parameters();
  EXPECT_DOUBLE_EQ(config_value("tactile_fsm.yaml", "whisker_fsm", fsm, "whisker_spacing"), cf.whisker_spacing);
  EXPECT_DOUBLE_EQ(config_value("tactile_fsm.yaml", "whisker_fsm", fsm, "whisker_base_x"), cf.whisker_base_x);
  const auto gpis = gpis_explorer::GpisExplorerLogic::default_parameters();
  EXPECT_DOUBLE_EQ(config_value("gpis_explorer.yaml", "gpis_explorer", gpis, "whisker_spacing"), cf.whisker_spacing);
  // ... and the frames: whisker_left at (whisker_base_x, whisker_spacing / 2).
  bool found = false;
  for (const auto& f : tactile_common::static_frames(tactile_sim::robot_model(cf), "")) {
    if (f.child != "whisker_left") continue;
    found = true;
    EXPECT_DOUBLE_EQ(f.transform.xyz[0], cf.whisker_base_x);
    EXPECT_DOUBLE_EQ(f.transform.xyz[1], cf.whisker_spacing / 2);
  }
  EXPECT_TRUE(found);
}

TEST(VehicleGeometry, XplorerMappingConfigAgreesWithTheXplorer) {
  const tactile_sim::XplorerParams x;
  const auto map = mapping_pcl::XplorerMapLogic::default_parameters();
  EXPECT_DOUBLE_EQ(config_value("xplorer_mapping.yaml", "xplorer_mapping", map, "arm_hinge_offset"), x.hinge_offset);
  EXPECT_DOUBLE_EQ(config_value("xplorer_mapping.yaml", "xplorer_mapping", map, "arm_length"), x.arm_length);
}
