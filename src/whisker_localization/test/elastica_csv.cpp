// Test helper for the independent scipy check: lines "normal F s_a" or
// "point p_x p_y" on stdin -> "F s_a phi_a contact_x contact_y M0" on stdout.
#include <iostream>
#include <sstream>
#include <string>

#include "whisker_localization/elastica.hpp"

int main() {
  const whisker_localization::ElasticaSolver solver{whisker_localization::BeamParams{}};
  std::string line;
  std::cout.precision(17);
  while (std::getline(std::cin, line)) {
    std::istringstream in(line);
    std::string mode;
    double a = 0.0, b = 0.0;
    if (!(in >> mode >> a >> b)) continue;
    const auto s = mode == "point" ? solver.solve_point(a, b) : solver.solve_normal(a, b);
    std::cout << s.ok << " " << s.force << " " << s.s_a << " " << s.phi_a << " " << s.contact_x << " " << s.contact_y
              << " " << s.base_moment << "\n";
  }
  return 0;
}
