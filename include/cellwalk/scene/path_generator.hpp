// Generated camera paths over a scene's navigation graph (src/scene/path_generator.cpp).
#pragma once

#include <cstdint>
#include <string>

#include "cellwalk/core/camera_path.hpp"
#include "cellwalk/scene/scene.hpp"

namespace cellwalk {

// The session kinds the seeds replay (HDoV thesis §4.4, Li–Chiang, vLOD).
enum class SessionKind { kNormal, kSlow, kFast, kTurning, kBackward, kBackAndForth, kRandom };
SessionKind parse_session_kind(const std::string& name);  // throws Error on an unknown name
const char* to_string(SessionKind kind);

struct PathParams {
  SessionKind kind = SessionKind::kNormal;
  int frames = 600;
  double fps = 30.0;
  uint64_t seed = 1;
};

// A path that stays on the scene's navigation graph (so in streets, never inside buildings).
// Deterministic for given params and graph. Throws Error if the graph has no edges.
CameraPath generate_path(const NavGraph& nav, const PathParams& params);

}  // namespace cellwalk
