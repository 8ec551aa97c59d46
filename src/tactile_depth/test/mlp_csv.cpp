// Test helper for test_mlp_sklearn.py: reads a model file and lines of
// "side,s1,s2,s3" (side = left|right) on stdin, prints one depth per line.
#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>

#include "tactile_depth/mlp_model.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: tactile_depth_mlp_csv MODEL.json < side,s1,s2,s3 lines\n";
    return 2;
  }
  try {
    const tactile_depth::SensorModelFile f = tactile_depth::SensorModelFile::load(argv[1]);
    std::string line;
    while (std::getline(std::cin, line)) {
      if (line.empty()) continue;
      std::istringstream is(line);
      std::string side, v;
      std::getline(is, side, ',');
      std::array<double, 3> x{};
      for (double& xi : x) {
        std::getline(is, v, ',');
        xi = std::stod(v);
      }
      const tactile_depth::MlpModel& m = side == "left" ? f.left : f.right;
      std::printf("%.17g\n", m.predict(x));
    }
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
  return 0;
}
