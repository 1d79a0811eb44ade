// The frame loop shared by `walk`, `compare`, `view` and every bench: one way to measure.
#include "cellwalk/runtime/walk.hpp"

#include "core/stopwatch.hpp"

namespace cellwalk {

FrameStats render_frame(Strategy& strategy, Renderer& renderer, const Camera& camera, double time,
                        std::vector<DrawItem>* drawn, const Camera* render_from,
                        const std::function<void(std::vector<DrawItem>&)>& adjust) {
  FrameStats stats;
  stats.time = time;
  Stopwatch frame_watch;
  std::vector<DrawItem> items;
  strategy.select(camera, items, stats);
  if (adjust) adjust(items);
  // The renderer asks for geometry it does not hold; the strategy's I/O and decode time is
  // measured inside the render call and taken out of the render time below.
  const double io_before = stats.io_ms, decode_before = stats.decode_ms;
  uint64_t unavailable = 0;
  MeshProvider provider = [&](const DrawItem& item) -> const Mesh* {
    const Mesh* mesh = strategy.mesh(item, stats);
    if (!mesh) ++unavailable;
    return mesh;
  };
  RenderStats rs = renderer.render(render_from ? *render_from : camera, items, provider, strategy.far_faces());
  const double fetch_ms = (stats.io_ms - io_before) + (stats.decode_ms - decode_before);
  stats.render_ms = std::max(0.0, rs.ms - fetch_ms);
  stats.triangles = rs.triangles;
  stats.objects = rs.objects;
  stats.cache_hits += rs.gpu_hits;
  stats.stall = stats.stall || unavailable > 0;
  stats.resident_bytes = strategy.resident_bytes();
  stats.gpu_bytes = rs.gpu_resident_bytes;
  stats.frame_ms = frame_watch.ms();
  if (drawn) *drawn = std::move(items);
  return stats;
}

std::vector<FrameStats> walk(const CameraPath& path, const Camera& lens, Strategy& strategy,
                             Renderer& renderer, const ProgressFn& progress) {
  std::vector<FrameStats> frames;
  frames.reserve(path.frames.size());
  Camera camera = lens;
  for (size_t i = 0; i < path.frames.size(); ++i) {
    apply(path.frames[i], camera);
    FrameStats stats = render_frame(strategy, renderer, camera, path.frames[i].time);
    stats.frame = static_cast<int>(i);
    frames.push_back(stats);
    if (progress) progress(i + 1, path.frames.size());
  }
  return frames;
}

}  // namespace cellwalk
