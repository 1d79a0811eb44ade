// Generated camera paths: the session kinds the seeds replay: normal, fast, slow, turning,
// backward (HDoV thesis §4.4, Fig. 4.17), back-and-forth (HDoV §5.8 session 3; Zheng thesis
// §7.2's oscillation across a border) and random (Zheng §7.3's random route). Speeds and turn
// rates are ours: docs/paths.md.
#include "cellwalk/scene/path_generator.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>

#include "cellwalk/core/error.hpp"
#include "cellwalk/core/random.hpp"

namespace cellwalk {

namespace {

const std::map<std::string, SessionKind>& kind_names() {
  static const std::map<std::string, SessionKind> names = {
      {"normal", SessionKind::kNormal},     {"slow", SessionKind::kSlow},
      {"fast", SessionKind::kFast},         {"turning", SessionKind::kTurning},
      {"backward", SessionKind::kBackward}, {"back-and-forth", SessionKind::kBackAndForth},
      {"random", SessionKind::kRandom}};
  return names;
}

// A route through the navigation graph, extended on demand by a random walk that avoids
// going straight back where it came from unless the node is a dead end.
class Route {
 public:
  Route(const NavGraph& nav, Random& rng) : nav_(nav), rng_(rng), adjacent_(nav.nodes.size()) {
    for (auto [a, b] : nav.edges) {
      // Edges of (almost) no length lead nowhere: leaving them out keeps every node with a
      // neighbour a node the walk can leave.
      if (glm::length(nav.nodes[a] - nav.nodes[b]) <= 1e-3f) continue;
      adjacent_[a].push_back(b);
      adjacent_[b].push_back(a);
    }
    uint32_t start;
    do start = static_cast<uint32_t>(rng_.integer(0, static_cast<int64_t>(nav.nodes.size()) - 1));
    while (adjacent_[start].empty());
    nodes_ = {start};
    lengths_ = {0.0};
  }

  // Position and unit direction of travel at arc length s >= 0 along the route.
  std::pair<Vec3, Vec3> at(double s) {
    while (lengths_.back() <= s) extend();
    size_t i = static_cast<size_t>(std::upper_bound(lengths_.begin(), lengths_.end(), s) - lengths_.begin());
    const Vec3 a = nav_.nodes[nodes_[i - 1]], b = nav_.nodes[nodes_[i]];
    const double t = (s - lengths_[i - 1]) / (lengths_[i] - lengths_[i - 1]);
    return {a + (b - a) * static_cast<float>(t), glm::normalize(b - a)};
  }

 private:
  void extend() {
    const uint32_t here = nodes_.back();
    const uint32_t previous = nodes_.size() > 1 ? nodes_[nodes_.size() - 2] : UINT32_MAX;
    std::vector<uint32_t> choices;
    for (uint32_t n : adjacent_[here])
      if (n != previous) choices.push_back(n);
    if (choices.empty()) choices.push_back(previous);  // dead end: turn back
    const uint32_t next = choices[static_cast<size_t>(rng_.integer(0, static_cast<int64_t>(choices.size()) - 1))];
    lengths_.push_back(lengths_.back() + glm::length(nav_.nodes[next] - nav_.nodes[here]));
    nodes_.push_back(next);
  }

  const NavGraph& nav_;
  Random& rng_;
  std::vector<std::vector<uint32_t>> adjacent_;
  std::vector<uint32_t> nodes_;
  std::vector<double> lengths_;  // cumulative arc length at each node
};

struct Motion {
  double speed;          // metres per second along the route
  double turn_rate;      // how fast the view follows the heading, degrees per second
  double look_amplitude; // degrees of side-to-side looking (turning sessions)
  bool facing_back;      // looks opposite to the direction of travel
};

Motion motion_of(SessionKind kind) {
  switch (kind) {
    case SessionKind::kSlow: return {0.7, 90, 0, false};
    case SessionKind::kFast: return {8.0, 180, 0, false};
    case SessionKind::kTurning: return {1.5, 120, 70, false};
    case SessionKind::kBackward: return {1.5, 90, 0, true};
    case SessionKind::kRandom: return {2.0, 120, 0, false};
    case SessionKind::kNormal:
    case SessionKind::kBackAndForth: break;
  }
  return {2.0, 90, 0, false};
}

float heading_yaw(const Vec3& dir) {
  // Inverse of Camera::forward() at pitch 0: forward = (-sin yaw, 0, -cos yaw).
  return static_cast<float>(glm::degrees(std::atan2(-dir.x, -dir.z)));
}

float wrap180(float deg) {
  deg = std::fmod(deg + 180.0f, 360.0f);
  if (deg < 0) deg += 360.0f;
  return deg - 180.0f;
}

}  // namespace

SessionKind parse_session_kind(const std::string& name) {
  auto it = kind_names().find(name);
  if (it == kind_names().end()) {
    std::string known;
    for (const auto& [n, k] : kind_names()) known += (known.empty() ? "" : ", ") + n;
    fail("session kind \"" + name + "\"", "unknown; choose one of " + known);
  }
  return it->second;
}

const char* to_string(SessionKind kind) {
  for (const auto& [n, k] : kind_names())
    if (k == kind) return n.c_str();
  return "?";
}

CameraPath generate_path(const NavGraph& nav, const PathParams& params) {
  bool has_edge = false;
  for (auto [a, b] : nav.edges) has_edge |= a != b && glm::length(nav.nodes.at(a) - nav.nodes.at(b)) > 1e-3f;
  if (!has_edge) fail("path", "the scene's navigation graph has no edges to walk on");
  if (params.frames < 1 || !(params.fps > 0)) fail("path", "need at least one frame and a positive fps");
  // Nodes beyond the coordinate bound make lengths and headings overflow to inf and NaN.
  for (size_t i = 0; i < nav.nodes.size(); ++i)
    check_position(nav.nodes[i], "path", "the world's navigation node " + std::to_string(i));

  Random rng(params.seed);
  Route route(nav, rng);
  const Motion motion = motion_of(params.kind);
  const double dt = 1.0 / params.fps;
  CameraPath path;
  double s = 0.0, speed = motion.speed, pitch = 0.0;
  float yaw = 0.0f;
  // Back-and-forth: 30 m forward, 20 m back, repeated: the same borders are crossed again and
  // again with net progress.
  int direction = 1;
  double leg_start = 0.0;
  for (int i = 0; i < params.frames; ++i) {
    const double t = i * dt;
    auto [position, heading] = route.at(s);
    Vec3 travel = heading * static_cast<float>(direction);
    float target = heading_yaw(motion.facing_back ? -travel : travel);
    if (motion.look_amplitude > 0) target += static_cast<float>(motion.look_amplitude * std::sin(t * 0.8));
    if (i == 0) yaw = target;
    const float max_step = static_cast<float>(motion.turn_rate * dt);
    yaw = wrap180(yaw + std::clamp(wrap180(target - yaw), -max_step, max_step));
    if (params.kind == SessionKind::kRandom) {
      // Random walkers change pace and glance up and down now and then.
      if (rng.chance(dt * 0.5)) speed = rng.uniform(0.5, 6.0);
      if (rng.chance(dt * 0.3)) direction = -direction;
      pitch += (rng.uniform(-1, 1) * 20.0 - pitch) * std::min(1.0, dt * 0.5);
    }
    path.frames.push_back({t, position, yaw, static_cast<float>(pitch)});
    if (params.kind == SessionKind::kBackAndForth) {
      const double leg = direction > 0 ? 30.0 : 20.0;
      if (std::abs(s - leg_start) >= leg) {
        direction = -direction;
        leg_start = s;
      }
    }
    s = std::max(0.0, s + direction * speed * dt);
    if (s == 0.0) direction = 1;
  }
  return path;
}

void aim_at(PathFrame& frame, const Vec3& target) {
  const Vec3 d = target - frame.position;
  const float length = glm::length(d);
  if (!(length > 0.0f)) return;
  // Camera::forward() is (-sin yaw cos pitch, sin pitch, -cos yaw cos pitch).
  frame.yaw_deg = glm::degrees(std::atan2(-d.x, -d.z));
  frame.pitch_deg = glm::degrees(std::asin(std::clamp(d.y / length, -1.0f, 1.0f)));
}

namespace {

// Whether every corner of `box` lies within `fill` of the half-angles of a camera at `eye`
// looking along unit `d` (yaw-pitch camera: right is horizontal).
bool box_in_view(const Aabb& box, const Vec3& eye, const Vec3& d, float tan_x, float tan_y) {
  const Vec3 right = glm::normalize(glm::cross(d, Vec3(0, 1, 0)));
  const Vec3 up = glm::cross(right, d);
  for (int k = 0; k < 8; ++k) {
    const Vec3 p((k & 1 ? box.max : box.min).x, (k & 2 ? box.max : box.min).y, (k & 4 ? box.max : box.min).z);
    const Vec3 v = p - eye;
    const float depth = glm::dot(v, d);
    if (depth <= 0.0f || std::abs(glm::dot(v, right)) > tan_x * depth || std::abs(glm::dot(v, up)) > tan_y * depth) return false;
  }
  return true;
}

// The eye's direction from the centre at step u in [0, 1): once around, elevation 10° to 35° and back.
Vec3 inspection_direction(float u) {
  constexpr float kLow = 10.0f, kHigh = 35.0f;
  const float around = 2.0f * std::numbers::pi_v<float> * u;
  const float up = glm::radians(kLow + (kHigh - kLow) * 0.5f * (1.0f - std::cos(around)));
  return {std::cos(up) * std::sin(around), std::sin(up), std::cos(up) * std::cos(around)};
}

}  // namespace

CameraPath inspection_path(const Aabb& target, const PathParams& params, float fov_y_deg, float aspect, float fill) {
  if (target.empty()) fail("inspection path", "the target has no bounds");
  if (params.frames < 1) fail("inspection path", "needs at least one frame");
  const Vec3 c = target.center();
  const float r = std::max(glm::length(target.size()) / 2, 1e-6f);
  const float tan_y = fill * std::tan(glm::radians(fov_y_deg) / 2), tan_x = tan_y * aspect;
  // One distance for the whole path (no zooming): the least at which the box fits every frame.
  // Farther than r / sin(atan(tan_y)) the bounding sphere fits, so the box does too.
  const float far = 1.001f * r / std::sin(std::atan(tan_y));
  float R = 0.0f;
  for (int i = 0; i < params.frames; ++i) {
    const Vec3 out = inspection_direction(float(i) / float(params.frames));
    float lo = 0.0f, hi = far;
    for (int step = 0; step < 32 && R < hi; ++step) {
      const float mid = 0.5f * (lo + hi);
      (box_in_view(target, c + mid * out, -out, tan_x, tan_y) ? hi : lo) = mid;
    }
    R = std::max(R, hi);
  }
  R *= 1.002f;  // the search's last step and the frustum planes' rounding, so the fit holds as drawn
  CameraPath path;
  for (int i = 0; i < params.frames; ++i) {
    PathFrame f;
    f.time = i / params.fps;
    f.position = c + R * inspection_direction(float(i) / float(params.frames));
    aim_at(f, c);
    path.frames.push_back(f);
  }
  return path;
}

}  // namespace cellwalk
