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

// An inspection path for one model or a whole world: the eye circles `target`'s centre once
// over params.frames frames (at params.fps), rising from 10° to 35° of elevation and back,
// always aimed at the centre, at one distance: the least at which the box lies within `fill`
// of the half-angles of a view of vertical field `fov_y_deg` and `aspect` in every frame.
// Deterministic; params.kind and seed unused.
CameraPath inspection_path(const Aabb& target, const PathParams& params, float fov_y_deg = 60.0f,
                           float aspect = 4.0f / 3.0f, float fill = 0.9f);

// The yaw and pitch (degrees, as PathFrame has them) that look from `eye` at `target`; the
// frame's own when they coincide.
void aim_at(PathFrame& frame, const Vec3& target);

}  // namespace cellwalk
