// ID cube maps through the renderer and the per-pixel solid-angle weights of HDoV thesis
// §5.5.2, eq. 5.11 (digest 000 §3.9).
#include "precompute/cube_map.hpp"

#include <cmath>
#include <condition_variable>
#include <deque>
#include <functional>
#include <future>
#include <mutex>
#include <thread>

#include "cellwalk/core/error.hpp"
#include "cellwalk/render/renderer.hpp"

namespace cellwalk::visibility {

namespace {

constexpr std::array<std::array<float, 2>, 6> kFaces = {{{0, 0}, {90, 0}, {180, 0}, {270, 0}, {0, 90}, {0, -90}}};

// ∫∫ dx dy / (x² + y² + 1)^{3/2} over [0, x] × [0, y]: the solid angle of a rectangle on the
// plane at distance 1 with one corner at the foot of the perpendicular.
double corner_solid_angle(double x, double y) { return std::atan(x * y / std::sqrt(x * x + y * y + 1.0)); }

}  // namespace

Camera cube_face_camera(const Vec3& p, size_t face, float far_plane) {
  Camera camera;
  camera.position = p;
  camera.yaw_deg = kFaces.at(face)[0];
  camera.pitch_deg = kFaces.at(face)[1];
  camera.fov_y_deg = 90.0f;
  camera.aspect = 1.0f;
  camera.near_plane = kCubeNearPlane;
  camera.far_plane = far_plane;
  return camera;
}

float cube_far_plane(const World& world) { return 2.0f * glm::length(world.info().bounds.size()) + 10.0f; }

// A face is one square framebuffer: at least a pixel, at most what any GL driver allocates.
int checked_cube_resolution(int resolution) {
  if (resolution < 1 || resolution > kMaxCubeResolution)
    fail("cube map", "face resolution " + std::to_string(resolution) + " must lie in [1, " +
                         std::to_string(kMaxCubeResolution) + "]; give a resolution such as 256");
  return resolution;
}

struct CubeMapRenderer::Impl {
  const World& world;
  int resolution;
  float far_plane;
  std::mutex mutex;
  std::condition_variable wake;
  std::deque<std::function<void(Renderer&)>> jobs;
  bool stop = false;
  std::exception_ptr startup_error;
  std::promise<void> started;
  std::thread thread;

  Impl(const World& w, int r) : world(w), resolution(r) {
    far_plane = cube_far_plane(w);
    std::future<void> ready = started.get_future();
    thread = std::thread([this] { run(); });
    try {
      ready.get();  // rethrows a failed context creation here, in the caller
    } catch (...) {
      thread.join();  // the thread has returned; a joinable thread would std::terminate here
      throw;
    }
  }

  ~Impl() {
    {
      std::lock_guard lock(mutex);
      stop = true;
    }
    wake.notify_all();
    thread.join();
  }

  void run() {
    std::unique_ptr<GlContext> context;
    std::unique_ptr<Renderer> renderer;
    try {
      context = GlContext::headless();
      RenderSettings settings;
      settings.width = settings.height = resolution;
      renderer = std::make_unique<Renderer>(settings);
    } catch (...) {
      started.set_exception(std::current_exception());
      return;
    }
    started.set_value();
    for (;;) {
      std::function<void(Renderer&)> job;
      {
        std::unique_lock lock(mutex);
        wake.wait(lock, [&] { return stop || !jobs.empty(); });
        if (stop && jobs.empty()) return;
        job = std::move(jobs.front());
        jobs.pop_front();
      }
      job(*renderer);
    }
  }

  CubeIds render_on_thread(Renderer& renderer, const Vec3& p) {
    CubeIds out;
    Mesh current;
    const MeshProvider provider = [&](const DrawItem& item) {
      current = world.decode_level(item.id, 0, world.read_level(item.id, 0));
      return &current;
    };
    for (size_t f = 0; f < 6; ++f) {
      const Camera camera = cube_face_camera(p, f, far_plane);
      const Frustum frustum(camera);
      std::vector<DrawItem> items;
      for (ObjectId id = 0; id < world.object_count(); ++id)
        if (world.object(id).bounds.empty() == false && frustum.intersects(world.object(id).bounds))
          items.push_back(DrawItem{id, 0, world.object(id).color});
      renderer.render(camera, items, provider);
      out[f] = renderer.read_ids();
    }
    return out;
  }
};

CubeMapRenderer::CubeMapRenderer(const World& world, int resolution)
    : resolution_(checked_cube_resolution(resolution)), impl_(std::make_unique<Impl>(world, resolution)) {}

CubeMapRenderer::~CubeMapRenderer() = default;

CubeIds CubeMapRenderer::render(const Vec3& p) const {
  auto task = std::make_shared<std::packaged_task<CubeIds(Renderer&)>>(
      [this, p](Renderer& r) { return impl_->render_on_thread(r, p); });
  std::future<CubeIds> result = task->get_future();
  {
    std::lock_guard lock(impl_->mutex);
    impl_->jobs.push_back([task](Renderer& r) { (*task)(r); });
  }
  impl_->wake.notify_one();
  return result.get();
}

std::vector<double> cube_pixel_weights(int resolution, bool midpoint) {
  std::vector<double> w(size_t(resolution) * resolution);
  const double step = 2.0 / resolution;
  for (int j = 0; j < resolution; ++j)
    for (int i = 0; i < resolution; ++i) {
      const double x0 = -1.0 + i * step, y0 = -1.0 + j * step, x1 = x0 + step, y1 = y0 + step;
      double omega;
      if (midpoint) {
        const double x = x0 + step / 2, y = y0 + step / 2;
        omega = step * step / std::pow(x * x + y * y + 1.0, 1.5);
      } else {
        // Inclusion–exclusion of the four corner rectangles: the exact integral of eq. 5.11.
        omega = corner_solid_angle(x1, y1) - corner_solid_angle(x0, y1) - corner_solid_angle(x1, y0) +
                corner_solid_angle(x0, y0);
      }
      w[size_t(j) * resolution + i] = omega / (4.0 * M_PI);
    }
  return w;
}

}  // namespace cellwalk::visibility
