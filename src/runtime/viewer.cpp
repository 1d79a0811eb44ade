// The interactive viewer. It uses the same frame loop (render_frame) as the headless walk
// harness, so what a person sees is what the benches measure.
#include "cellwalk/runtime/viewer.hpp"

#include <GLFW/glfw3.h>

#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>

#include "cellwalk/core/camera_path.hpp"
#include "cellwalk/core/error.hpp"
#include "cellwalk/runtime/floor_probe.hpp"
#include "cellwalk/runtime/run_budget.hpp"
#include "cellwalk/runtime/strategies.hpp"
#include "cellwalk/runtime/walk.hpp"
#include "cellwalk/render/window.hpp"
#include "cellwalk/systems/stratified/stratified_strategy.hpp"
#include "cellwalk/lod/screen_error.hpp"
#include "cellwalk/store/level_choice.hpp"
#include "core/stopwatch.hpp"

namespace cellwalk {
namespace {

constexpr float kEyeHeight = 1.7f;      // metres above the world's floor, at most half its height
constexpr float kWalkSpeed = 3.0f;      // metres per second, at most a twentieth of the world's
                                        // extent a second; Shift multiplies by kRunFactor
constexpr float kRunFactor = 6.0f;
constexpr float kStepUp = 0.5f;         // the highest step a walker climbs, in eye heights
constexpr uint64_t kFloorCacheBytes = uint64_t(4) << 20;  // at most a sixteenth of the strategy's budget
constexpr float kFloorTolerance = 0.02f;  // floors are probed on levels this many eye heights coarse
constexpr float kMouseDegPerPixel = 0.15f;
const Rgba8 kChosenColour = rgba8(255, 210, 0);  // the bird's-eye view's boxes of the chosen set
const Rgba8 kPanelColour = rgba8(16, 16, 24);    // behind the statistics

// Where a viewer starts: on the first navigation edge, looking along it.
void place_at_start(const SceneInfo& info, Camera& camera) {
  if (!info.nav.edges.empty()) {
    const Vec3 a = info.nav.nodes[info.nav.edges[0].first], b = info.nav.nodes[info.nav.edges[0].second];
    camera.position = a;
    const Vec3 d = b - a;
    camera.yaw_deg = glm::degrees(std::atan2(-d.x, -d.z));
    return;
  }
  camera.position = info.bounds.center() + Vec3(0, 0, info.bounds.size().z);
}

// The walker's frustum, cut at `depth` metres so it stays readable from above.
void add_frustum(const Camera& camera, float depth, std::vector<LineSegment>& out) {
  const float h = depth * std::tan(glm::radians(camera.fov_y_deg) * 0.5f), w = h * camera.aspect;
  const Vec3 c = camera.position + camera.forward() * depth;
  const Vec3 r = camera.right() * w, u = camera.up() * h;
  const Vec3 far[4] = {c - r - u, c + r - u, c + r + u, c - r + u};
  const Rgba8 red = rgba8(230, 30, 30);
  for (int i = 0; i < 4; ++i) {
    out.push_back({camera.position, far[i], red});
    out.push_back({far[i], far[(i + 1) % 4], red});
  }
}

Camera birds_eye_camera(const Aabb& bounds, const Camera& lens) {
  Camera top = lens;
  const Vec3 size = bounds.size();
  const float span = std::max(size.x, size.z);
  top.position = Vec3(bounds.center().x, bounds.max.y + span / (2.0f * std::tan(glm::radians(lens.fov_y_deg) * 0.5f)),
                      bounds.center().z);
  top.yaw_deg = 0;
  top.pitch_deg = -89.9f;
  top.near_plane = std::max(0.1f, span * 1e-4f);
  top.far_plane = top.position.y + span;
  return top;
}

struct ViewerState {
  Camera camera;
  float floor_y = 0.0f, eye_height = kEyeHeight, walk_speed = kWalkSpeed;  // fitted to the world
  bool fly = false;
  bool birds_eye = false;
  bool recording = false;
  bool dragging = false;
  double last_x = 0, last_y = 0;
  double clock = 0;
  CameraPath recorded;
  bool screenshot_requested = false;
  bool show_help = false;
};

// Walking keeps the eye at eye height above the floor under it: a surface up to a step above
// the current floor is climbed, and with nothing under the walker it drops to the one below.
void stand_on_floor(ViewerState& s, FloorProbe& probe) {
  const Vec3 p = s.camera.position;
  s.floor_y = probe.floor_below(Vec3(p.x, s.floor_y + kStepUp * s.eye_height, p.z));
  s.camera.position.y = s.floor_y + s.eye_height;
}

void move(ViewerState& s, const Window& window, FloorProbe& probe, float dt) {
  float speed = s.walk_speed * (window.key_down(GLFW_KEY_LEFT_SHIFT) ? kRunFactor : 1.0f) * dt;
  Vec3 forward = s.camera.forward(), right = s.camera.right();
  if (!s.fly) forward = glm::normalize(Vec3(forward.x, 0, forward.z));
  Vec3 step(0.0f);
  if (window.key_down(GLFW_KEY_W) || window.key_down(GLFW_KEY_UP)) step += forward;
  if (window.key_down(GLFW_KEY_S) || window.key_down(GLFW_KEY_DOWN)) step -= forward;
  if (window.key_down(GLFW_KEY_D)) step += right;
  if (window.key_down(GLFW_KEY_A)) step -= right;
  if (s.fly && window.key_down(GLFW_KEY_E)) step.y += 1;
  if (s.fly && window.key_down(GLFW_KEY_Q)) step.y -= 1;
  if (window.key_down(GLFW_KEY_LEFT)) s.camera.yaw_deg += 90.0f * dt;
  if (window.key_down(GLFW_KEY_RIGHT)) s.camera.yaw_deg -= 90.0f * dt;
  if (glm::length(step) > 0) s.camera.position += glm::normalize(step) * speed;
  if (!s.fly) stand_on_floor(s, probe);
}

std::string overlay_text(const ViewerState& s, const FrameStats& f, double fps, const std::string& strategy) {
  char text[512];
  std::snprintf(text, sizeof text,
                "%s  %.1f fps  frame %.1f ms (query %.1f io %.1f decode %.1f render %.1f)\n"
                "%llu objects  %llu triangles  %.1f MiB resident\n"
                "%s%s%s  pos %.1f %.1f %.1f  yaw %.0f pitch %.0f  H help%s",
                strategy.c_str(), fps, f.frame_ms, f.query_ms, f.io_ms, f.decode_ms, f.render_ms,
                (unsigned long long)f.objects, (unsigned long long)f.triangles, f.resident_bytes / 1048576.0,
                s.fly ? "fly" : "walk", s.birds_eye ? "  bird's-eye" : "",
                s.recording ? "  RECORDING" : "", s.camera.position.x, s.camera.position.y,
                s.camera.position.z, s.camera.yaw_deg, s.camera.pitch_deg,
                s.show_help ? "\nWASD move, drag look, Shift run, F fly, B bird's-eye, R record, P screenshot, "
                              "Tab next strategy, 1-5 show (stratified), H hide this, Esc quit"
                            : "");
  return text;
}

// screenshot-N.png in the working folder, N the first number whose file does not exist.
std::string unused_screenshot_name() {
  for (int n = 1;; ++n) {
    const std::string name = "screenshot-" + std::to_string(n) + ".png";
    if (!std::filesystem::exists(name)) return name;
  }
}

// SIGINT and SIGTERM end the frame loop instead of the process, so what a run was asked to
// write (screenshot, recording) is still written; the previous handlers come back after.
class StopOnSignals {
 public:
  StopOnSignals() {
    flag_ = 0;
    previous_int_ = std::signal(SIGINT, on_signal);
    previous_term_ = std::signal(SIGTERM, on_signal);
  }
  ~StopOnSignals() {
    std::signal(SIGINT, previous_int_);
    std::signal(SIGTERM, previous_term_);
  }
  bool requested() const { return flag_ != 0; }

 private:
  static void on_signal(int) { flag_ = 1; }
  static inline volatile std::sig_atomic_t flag_ = 0;
  void (*previous_int_)(int);
  void (*previous_term_)(int);
};

}  // namespace

ViewerSummary run_viewer(const World& scene, const ViewerOptions& options) {
  ViewerSummary summary;
  Window window(options.width, options.height, "cellwalk — " + scene.file().path(), options.max_frames == 0);
  int fb_width, fb_height;
  window.framebuffer_size(fb_width, fb_height);
  const RunBudget budget = split_run_budget(options.budget_bytes, 0, std::nullopt);
  StrategyOptions strategy_options;
  strategy_options.viewport_height_px = float(fb_height);
  const uint64_t floor_cache = budget.total_bytes > 0 ? std::min(kFloorCacheBytes, budget.strategy_bytes / 16) : kFloorCacheBytes;
  strategy_options.memory_budget_bytes = budget.total_bytes > 0 ? budget.strategy_bytes - floor_cache : 0;
  // A walker in a 1 m scan or a 10 km plant: eye height and speed follow the world's size.
  const Aabb& world_box = scene.info().bounds;
  const float eye_height = std::min(kEyeHeight, std::max(world_box.size().y / 2, 1e-3f));
  FloorProbe probe(scene, kFloorTolerance * eye_height, floor_cache);
  if (options.strategies.empty()) fail("view", "no strategy given; name one with --strategy");
  // Every strategy is made once first, so one that cannot run here fails before the window is
  // in use; Tab then switches between them, one alive at a time (the budget is for one).
  for (size_t i = 1; i < options.strategies.size(); ++i) make_strategy(options.strategies[i], scene, strategy_options);
  size_t current = 0;
  auto strategy = make_strategy(options.strategies[0], scene, strategy_options);
  const auto switch_to = [&](const std::string& name) {
    strategy.reset();
    strategy = make_strategy(name, scene, strategy_options);
  };
  RenderSettings settings;
  settings.width = fb_width;
  settings.height = fb_height;
  settings.backdrop = true;
  if (budget.total_bytes > 0) settings.gpu_budget_bytes = budget.gpu_bytes;
  fit_backdrop(settings, scene.info().bounds);
  auto renderer = std::make_unique<Renderer>(settings);
  use_world_textures(*renderer, scene);

  ViewerState s;
  s.birds_eye = options.birds_eye;
  s.show_help = fb_width >= 800;  // a small window keeps the scene in view: H shows the keys
  s.camera.fov_y_deg = options.fov_y_deg;
  s.camera.aspect = float(fb_width) / float(fb_height);
  place_at_start(scene.info(), s.camera);
  // The floor is the surface under the start (else the world's lowest point, the backdrop's
  // ground).
  s.eye_height = eye_height;
  s.floor_y = probe.floor_below(s.camera.position);
  s.walk_speed = std::min(kWalkSpeed, std::max(std::max(world_box.size().x, world_box.size().z) / 20, 1e-3f));
  CameraPath replay;
  if (!options.replay_file.empty()) replay = read_path(options.replay_file);
  const std::string record_file = options.record_file.empty() ? "recorded.path" : options.record_file;
  s.recording = !options.record_file.empty();  // --record records from the first frame

  auto save_recording = [&] {
    if (s.recorded.frames.empty()) return;
    write_path(s.recorded, record_file);
    summary.recorded_file = record_file;
    summary.recorded_frames = s.recorded.frames.size();
    std::fprintf(stderr, "view: recorded %zu frames to %s\n", s.recorded.frames.size(), record_file.c_str());
  };
  WindowCallbacks callbacks;
  callbacks.key = [&](int key, int action, int) {
    if (action != GLFW_PRESS) return;
    if (key == GLFW_KEY_ESCAPE) window.request_close();
    if (key == GLFW_KEY_F) {
      s.fly = !s.fly;
      if (!s.fly) s.floor_y = probe.floor_below(s.camera.position);  // land where the eye is
    }
    if (key == GLFW_KEY_B) s.birds_eye = !s.birds_eye;
    if (key == GLFW_KEY_P) s.screenshot_requested = true;
    if (key == GLFW_KEY_H) s.show_help = !s.show_help;
    // Stratified's show styles (§5.1): 1 full, 2 near, 3 far objects, 4 far texture, 5 brute.
    if (key == GLFW_KEY_TAB && options.strategies.size() > 1) {
      current = (current + 1) % options.strategies.size();
      switch_to(options.strategies[current]);
    }
    if (key >= GLFW_KEY_1 && key <= GLFW_KEY_5 && is_stratified_strategy_name(options.strategies[current])) {
      static const char* const kShows[] = {"full", "near", "far-objects", "far-texture", "brute"};
      switch_to(std::string("stratified:show=") + kShows[key - GLFW_KEY_1]);
    }
    if (key == GLFW_KEY_R) {
      if (s.recording) save_recording();
      s.recording = !s.recording;
      s.recorded.frames.clear();
    }
  };
  callbacks.mouse_button = [&](int button, int action, int) {
    if (button != GLFW_MOUSE_BUTTON_LEFT && button != GLFW_MOUSE_BUTTON_RIGHT) return;
    s.dragging = action == GLFW_PRESS;
    window.cursor_position(s.last_x, s.last_y);
  };
  callbacks.cursor = [&](double x, double y) {
    if (!s.dragging) return;
    s.camera.yaw_deg -= float(x - s.last_x) * kMouseDegPerPixel;
    s.camera.pitch_deg = std::clamp(s.camera.pitch_deg - float(y - s.last_y) * kMouseDegPerPixel, -89.0f, 89.0f);
    s.last_x = x;
    s.last_y = y;
  };
  callbacks.framebuffer_size = [&](int w, int h) {
    if (w <= 0 || h <= 0) return;  // minimised
    settings.width = w;
    settings.height = h;
    renderer = std::make_unique<Renderer>(settings);
    use_world_textures(*renderer, scene);
    s.camera.aspect = float(w) / float(h);
  };
  window.set_callbacks(callbacks);

  Stopwatch clock;
  double fps = 0;
  std::vector<LineSegment> boxes;
  for (ObjectId id = 0; id < scene.object_count(); ++id) append_box_lines(scene.object(id).bounds, rgba8(40, 40, 40), boxes);
  const StopOnSignals stop;
  for (int frame = 0; !window.should_close() && !stop.requested(); ++frame) {
    if (options.max_frames > 0 && frame >= options.max_frames) break;
    if (!replay.frames.empty() && options.max_frames == 0 && size_t(frame) >= replay.frames.size()) break;
    const double dt = std::min(clock.lap_ms() / 1000.0, 0.25);
    s.clock += frame == 0 ? 0.0 : dt;
    window.poll_events();
    if (!replay.frames.empty()) {
      const PathFrame& f = replay.frames[size_t(frame) % replay.frames.size()];
      apply(f, s.camera);
      s.clock = f.time;
    } else {
      move(s, window, probe, float(dt));
    }
    if (s.recording) s.recorded.frames.push_back({s.clock, s.camera.position, s.camera.yaw_deg, s.camera.pitch_deg});

    FrameStats stats;
    if (s.birds_eye) {
      const Camera top = birds_eye_camera(scene.info().bounds, s.camera);
      // What the walker is shown, seen from above (select from the walker, draw from the top),
      // each object no finer than a pixel's error from up there needs, so the view stays
      // interactive whatever the walker's strategy chose; its boxes highlighted over the
      // overview of every object's box.
      const Lens top_lens = lens_of(top, float(settings.height));
      const auto coarsen = [&](std::vector<DrawItem>& items) {
        if (!strategy->serves_every_level()) return;
        for (DrawItem& item : items)
          if (item.kind == DrawKind::kObject && !item.transient && item.id < scene.object_count())
            item.lod = std::max(item.lod, level_for_screen_error(scene, item.id, top.position, top_lens, 1.0f));
      };
      std::vector<DrawItem> chosen;
      stats = render_frame(*strategy, *renderer, s.camera, s.clock, &chosen, &top, coarsen);
      std::vector<LineSegment> lines = boxes;
      for (const DrawItem& item : chosen)
        if (item.kind == DrawKind::kObject && item.id < scene.object_count())
          append_box_lines(scene.object(item.id).bounds, kChosenColour, lines);
      strategy->overlay(lines);
      add_frustum(s.camera, 0.05f * glm::length(scene.info().bounds.size()), lines);
      renderer->draw_lines(top, lines);
    } else {
      stats = render_frame(*strategy, *renderer, s.camera);
    }
    ++summary.frames;
    summary.mean_frame_ms += stats.frame_ms;
    summary.worst_frame_ms = std::max(summary.worst_frame_ms, stats.frame_ms);
    summary.mean_objects += double(stats.objects);
    summary.mean_triangles += double(stats.triangles);
    summary.peak_resident_bytes = std::max(summary.peak_resident_bytes, stats.resident_bytes);
    fps = fps == 0 ? 1000.0 / std::max(stats.frame_ms, 0.01) : 0.9 * fps + 100.0 / std::max(stats.frame_ms, 0.01);
    // Larger glyphs only where the window has room for them.
    renderer->draw_text(8, 8, overlay_text(s, stats, fps, strategy->name()), rgba8(255, 255, 255),
                        settings.width >= 1200 ? 1.5f : 1.0f, kPanelColour);
    int w, h;
    window.framebuffer_size(w, h);
    renderer->present(w, h);
    if (s.screenshot_requested) {
      const std::string file = unused_screenshot_name();
      write_png(renderer->read_color(), file);
      std::fprintf(stderr, "view: wrote %s\n", file.c_str());
      summary.screenshots.push_back(file);
      s.screenshot_requested = false;
    }
    window.swap_buffers();
  }
  if (s.recording) save_recording();
  if (!options.screenshot_file.empty()) {
    write_png(renderer->read_color(), options.screenshot_file);
    summary.screenshots.push_back(options.screenshot_file);
  }
  if (summary.frames > 0) {
    summary.mean_frame_ms /= summary.frames;
    summary.mean_objects /= summary.frames;
    summary.mean_triangles /= summary.frames;
  }
  summary.stopped_by_signal = stop.requested();
  return summary;
}

}  // namespace cellwalk
