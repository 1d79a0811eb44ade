// A desktop window with an OpenGL 4.5 core context (GLFW), for the interactive viewer. Under
// Xvfb it runs on Mesa's llvmpipe like the headless context; the renderer is the same.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "cellwalk/render/renderer.hpp"

namespace cellwalk {

// Events use GLFW's codes (GLFW_KEY_W, GLFW_PRESS, GLFW_MOUSE_BUTTON_LEFT, ...); include
// <GLFW/glfw3.h> to name them. Callbacks run inside poll_events() on the window's thread; an
// exception one throws is rethrown by poll_events() (the events after it in that poll are dropped).
struct WindowCallbacks {
  std::function<void(int key, int action, int mods)> key;
  std::function<void(int button, int action, int mods)> mouse_button;
  std::function<void(double x, double y)> cursor;  // pixels from the top-left corner
  std::function<void(double dx, double dy)> scroll;
  std::function<void(int width, int height)> framebuffer_size;
};

// Creating a Window makes its context current on the calling thread. One thread only: GLFW
// requires the main thread for window creation and events.
class Window : public GlContext {
 public:
  // Throws Error when no display is reachable (set DISPLAY or run under xvfb-run) or the
  // driver cannot give OpenGL 4.5 core. `vsync` false lets frames run as fast as they render.
  Window(int width, int height, const std::string& title, bool vsync = true);
  ~Window() override;
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;

  std::string renderer_name() const override;

  void set_callbacks(WindowCallbacks callbacks);
  bool should_close() const;
  void request_close();
  void poll_events();
  void swap_buffers();
  // Current state, for continuous motion (keys held down) rather than events.
  bool key_down(int key) const;
  void cursor_position(double& x, double& y) const;
  // Size in pixels of the default framebuffer, what Renderer::present() fills.
  void framebuffer_size(int& width, int& height) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cellwalk
