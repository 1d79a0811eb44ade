// Options shared by every command that renders: image size, field of view, GPU budget.
#pragma once

#include <CLI/CLI.hpp>

#include "cellwalk/core/camera.hpp"
#include "cellwalk/core/error.hpp"
#include "cellwalk/render/renderer.hpp"
#include "checks.hpp"

namespace cellwalk::app {

struct LensOptions {
  int width = 640;
  int height = 480;
  float fov_y_deg = 60.0f;
  float near_plane = 0.25f;
  float far_plane = 5000.0f;
  double gpu_budget_mib = 512.0;
  bool flat_background = false;
  CLI::Option* gpu_option = nullptr;

  bool gpu_budget_given() const { return gpu_option != nullptr && gpu_option->count() > 0; }

  void add_to(CLI::App& cmd) {
    cmd.add_option("--width", width, "Image width in pixels")->capture_default_str()->check(integer_in(16, 8192));
    cmd.add_option("--height", height, "Image height in pixels")->capture_default_str()->check(integer_in(16, 8192));
    cmd.add_option("--fov", fov_y_deg, "Vertical field of view, degrees")->capture_default_str()->check(number_in(1, 170));
    cmd.add_option("--near", near_plane, "Near plane, metres")->capture_default_str()->check(number_in(0, 1e6, true));
    cmd.add_option("--far", far_plane, "Far plane, metres")->capture_default_str()->check(number_in(0, 1e7, true));
    gpu_option = cmd.add_option("--gpu-budget", gpu_budget_mib,
                                "GPU buffer cache budget, MiB (with --budget: part of it, default a quarter)")
                     ->capture_default_str()
                     ->check(number_in(0, 1 << 20));
    cmd.add_flag("--flat-background", flat_background, "Plain background instead of sky and ground");
  }
  // The lens as a whole: each bound holds alone, but a far plane before the near one draws nothing.
  void check() const {
    if (!(far_plane > near_plane))
      fail("--near " + std::to_string(near_plane) + " --far " + std::to_string(far_plane),
           "the far plane must lie beyond the near plane; give a larger --far or a smaller --near");
  }
  Camera lens() const {
    Camera c;
    c.fov_y_deg = fov_y_deg;
    c.aspect = float(width) / float(height);
    c.near_plane = near_plane;
    c.far_plane = far_plane;
    return c;
  }
  RenderSettings render_settings() const {
    RenderSettings s;
    s.width = width;
    s.height = height;
    s.gpu_budget_bytes = static_cast<uint64_t>(gpu_budget_mib * 1024 * 1024);
    s.backdrop = !flat_background;
    return s;
  }
};

}  // namespace cellwalk::app
