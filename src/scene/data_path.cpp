// Where scripts/setup unpacks the project's meshes (and installs the browser client's packages): $CELLWALK_DATA when set (an installed
// binary, a CI cache), else the source tree's data/ folder this library was built from.
#include <cstdlib>
#include <string>

#include "cellwalk/scene/generators.hpp"

namespace cellwalk {

std::string data_path(const std::string& relative) {
  const char* root = std::getenv("CELLWALK_DATA");
  const std::string base =
      root && *root ? std::string(root) : std::string(CELLWALK_SOURCE_DIR) + "/data";
  return base + "/" + relative;
}

std::string web_client_dir() {
  const char* root = std::getenv("CELLWALK_WEB");
  return root && *root ? std::string(root) : std::string(CELLWALK_SOURCE_DIR) + "/web";
}

}  // namespace cellwalk
