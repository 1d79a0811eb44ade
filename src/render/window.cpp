// The GLFW window: a 4.5 core context and its input events forwarded to plain callbacks.
#include "cellwalk/render/window.hpp"

#include <epoxy/gl.h>

// GL comes from epoxy; GLFW must not include the system GL header too.
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <exception>
#include <utility>

#include "cellwalk/core/error.hpp"

namespace cellwalk {
namespace {

constexpr std::string_view kWhere = "window";

std::string glfw_error_text() {
  const char* description = nullptr;
  glfwGetError(&description);
  return description != nullptr ? description : "unknown GLFW error";
}

// glfwInit/glfwTerminate bracket all windows of the process.
class GlfwLibrary {
 public:
  static void acquire() {
    if (users_ == 0 && !glfwInit()) {
      fail(kWhere,
           "cannot initialise GLFW: " + glfw_error_text() + " (set DISPLAY or run under xvfb-run)");
    }
    ++users_;
  }
  static void release() {
    if (--users_ == 0) glfwTerminate();
  }

 private:
  static inline int users_ = 0;  // main thread only, as GLFW requires
};

}  // namespace

struct Window::Impl {
  GLFWwindow* window = nullptr;
  WindowCallbacks callbacks;
  // An exception must not unwind through GLFW's C frames: the first one a callback throws is
  // kept here (later events are dropped) and rethrown by poll_events() once GLFW returns.
  std::exception_ptr pending;

  static Impl& of(GLFWwindow* window) {
    return *static_cast<Impl*>(glfwGetWindowUserPointer(window));
  }
  template <class F, class... A>
  static void call(GLFWwindow* w, F WindowCallbacks::*member, A... args) {
    Impl& impl = of(w);
    if (impl.pending || !(impl.callbacks.*member)) return;
    try {
      (impl.callbacks.*member)(args...);
    } catch (...) {
      impl.pending = std::current_exception();
    }
  }
  void install_callbacks() {
    glfwSetWindowUserPointer(window, this);
    glfwSetKeyCallback(window, [](GLFWwindow* w, int key, int, int action, int mods) {
      call(w, &WindowCallbacks::key, key, action, mods);
    });
    glfwSetMouseButtonCallback(window, [](GLFWwindow* w, int button, int action, int mods) {
      call(w, &WindowCallbacks::mouse_button, button, action, mods);
    });
    glfwSetCursorPosCallback(window, [](GLFWwindow* w, double x, double y) { call(w, &WindowCallbacks::cursor, x, y); });
    glfwSetScrollCallback(window, [](GLFWwindow* w, double dx, double dy) { call(w, &WindowCallbacks::scroll, dx, dy); });
    glfwSetFramebufferSizeCallback(window, [](GLFWwindow* w, int width, int height) {
      call(w, &WindowCallbacks::framebuffer_size, width, height);
    });
  }
};

Window::Window(int width, int height, const std::string& title, bool vsync)
    : impl_(std::make_unique<Impl>()) {
  GlfwLibrary::acquire();
  glfwWindowHint(GLFW_CLIENT_API, GLFW_OPENGL_API);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  impl_->window = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
  if (impl_->window == nullptr) {
    std::string reason = glfw_error_text();
    GlfwLibrary::release();
    fail(kWhere, "cannot open a window with OpenGL 4.5 core: " + reason);
  }
  glfwMakeContextCurrent(impl_->window);
  glfwSwapInterval(vsync ? 1 : 0);
  impl_->install_callbacks();
}

Window::~Window() {
  glfwDestroyWindow(impl_->window);
  GlfwLibrary::release();
}

std::string Window::renderer_name() const {
  return reinterpret_cast<const char*>(glGetString(GL_RENDERER));
}

void Window::set_callbacks(WindowCallbacks callbacks) {
  impl_->callbacks = std::move(callbacks);
}
bool Window::should_close() const {
  return glfwWindowShouldClose(impl_->window);
}
void Window::request_close() {
  glfwSetWindowShouldClose(impl_->window, GLFW_TRUE);
}
void Window::poll_events() {
  glfwPollEvents();
  if (std::exception_ptr e = std::exchange(impl_->pending, nullptr)) std::rethrow_exception(e);
}
void Window::swap_buffers() {
  glfwSwapBuffers(impl_->window);
}
bool Window::key_down(int key) const {
  return glfwGetKey(impl_->window, key) == GLFW_PRESS;
}
void Window::cursor_position(double& x, double& y) const {
  glfwGetCursorPos(impl_->window, &x, &y);
}
void Window::framebuffer_size(int& width, int& height) const {
  glfwGetFramebufferSize(impl_->window, &width, &height);
}

}  // namespace cellwalk
