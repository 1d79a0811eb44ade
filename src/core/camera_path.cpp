// Camera paths: the text format (docs/paths.md).
#include "cellwalk/core/camera_path.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "cellwalk/core/atomic_file.hpp"
#include "cellwalk/core/error.hpp"

namespace cellwalk {

namespace {
constexpr const char* kHeader = "# cellwalk path 1";
constexpr const char* kWorldTag = "# world ";

// "# world <name> <identity>": the identity is the last word, the name everything before it.
PathWorld parse_world_line(const std::string& line, const std::string& where) {
  const std::string rest = line.substr(std::string(kWorldTag).size());
  const size_t space = rest.find_last_of(' ');
  if (space == std::string::npos || space == 0 || space + 1 == rest.size())
    fail(where, "expected \"# world <name> <identity>\"; fix or delete the line");
  return {rest.substr(0, space), rest.substr(space + 1)};
}

bool is_finite(const PathFrame& f) {
  return std::isfinite(f.time) && std::isfinite(f.position.x) && std::isfinite(f.position.y) &&
         std::isfinite(f.position.z) && std::isfinite(f.yaw_deg) && std::isfinite(f.pitch_deg);
}

// Exactly version 1: a later version may mean something else by the same numbers.
void check_header(const std::string& line, const std::string& where) {
  const std::string family = "# cellwalk path ";
  if (line == kHeader) return;
  if (line.rfind(family, 0) == 0)
    fail(where, "path format version '" + line.substr(family.size()) + "' is not supported; only \"" + kHeader +
                    "\" is (regenerate the path with this cellwalk)");
  fail(where, "not a cellwalk path file (the first line must be \"" + std::string(kHeader) + "\")");
}
}  // namespace

CameraPath read_path(const std::string& file) {
  if (std::filesystem::is_directory(file)) fail(file, "is a directory, not a path file; give the path file written by cellwalk path");
  std::ifstream in(file);
  if (!in) fail(file, "cannot open path file");
  CameraPath path;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    const std::string where = file + ":" + std::to_string(number);
    const std::string trimmed = line.substr(0, line.find_last_not_of(" \t\r") + 1);
    if (number == 1) check_header(trimmed, where);
    if (trimmed.rfind(kWorldTag, 0) == 0) path.world = parse_world_line(trimmed, where);
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    PathFrame f;
    if (!(fields >> f.time >> f.position.x >> f.position.y >> f.position.z >> f.yaw_deg >> f.pitch_deg))
      fail(where, "expected 6 numbers: time x y z yaw pitch");
    std::string extra;
    if (fields >> extra) fail(where, "unexpected text after the 6 numbers: \"" + extra + "\"");
    if (!is_finite(f)) fail(where, "non-finite number");
    if (!path.frames.empty() && f.time < path.frames.back().time)
      fail(where, "time goes backwards");
    path.frames.push_back(f);
  }
  if (number == 0) fail(file, "empty path file");
  if (path.frames.empty()) fail(file, "path has no frames");
  return path;
}

void write_path(const CameraPath& path, const std::string& file) {
  // A NaN or inf written here would only be refused by the next reader: refuse it now.
  for (size_t i = 0; i < path.frames.size(); ++i) {
    if (!is_finite(path.frames[i]))
      fail(file, "frame " + std::to_string(i) + " has a non-finite time, position or angle; nothing was written "
                 "(the world's coordinates are probably beyond what cellwalk handles: rebuild it from a rescaled model)");
  }
  std::ostringstream out;
  out << kHeader << "\n";
  if (path.world.known()) out << kWorldTag << path.world.name << ' ' << path.world.identity << "\n";
  out << "# time x y z yaw_deg pitch_deg\n";
  out.precision(9);
  for (const PathFrame& f : path.frames)
    out << f.time << ' ' << f.position.x << ' ' << f.position.y << ' ' << f.position.z << ' '
        << f.yaw_deg << ' ' << f.pitch_deg << '\n';
  write_file_atomically(file, out.str());
}

void apply(const PathFrame& frame, Camera& camera) {
  camera.position = frame.position;
  camera.yaw_deg = frame.yaw_deg;
  camera.pitch_deg = frame.pitch_deg;
}

}  // namespace cellwalk
