// The headless OpenGL context: EGL on Mesa's surfaceless platform, so rendering needs neither a
// GPU nor an X server (llvmpipe renders in software). The context has no surface: everything
// is drawn into the renderer's own framebuffer objects.
#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include <cstdio>
#include <memory>
#include <cstdlib>
#include <mutex>
#include <string>
#include <string_view>

#include "cellwalk/core/error.hpp"
#include "cellwalk/render/renderer.hpp"

namespace cellwalk {
namespace {

constexpr std::string_view kWhere = "headless OpenGL";
constexpr std::string_view kInstallHint =
    " (install Mesa's EGL and software renderer: apt-get install libegl1 libegl-mesa0 "
    "libgl1-mesa-dri)";

bool has_extension(const char* extensions, std::string_view name) {
  if (extensions == nullptr) return false;
  std::string_view all(extensions);
  for (size_t pos = all.find(name); pos != std::string_view::npos; pos = all.find(name, pos + 1)) {
    bool starts = pos == 0 || all[pos - 1] == ' ';
    bool ends = pos + name.size() == all.size() || all[pos + name.size()] == ' ';
    if (starts && ends) return true;
  }
  return false;
}

std::string egl_error_text() {
  char text[32];
  std::snprintf(text, sizeof text, "EGL error 0x%04X", unsigned(eglGetError()));
  return text;
}

// The surfaceless display is one per process; EGL terminates it for every context at once, so
// it is shared and terminated when the last headless context goes.
class SurfacelessDisplay {
 public:
  static EGLDisplay acquire(Rasteriser rasteriser) {
    std::lock_guard lock(mutex_);
    if (users_ == 0 && rasteriser == Rasteriser::kCallingThread) setenv("LP_NUM_THREADS", "0", /*overwrite=*/0);
    if (users_ == 0) display_ = open();
    ++users_;
    return display_;
  }
  static void release() {
    std::lock_guard lock(mutex_);
    if (--users_ == 0) eglTerminate(display_);
  }

 private:
  static EGLDisplay open() {
    const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    if (!has_extension(client, "EGL_MESA_platform_surfaceless")) {
      fail(kWhere, std::string("EGL has no surfaceless platform (EGL_MESA_platform_surfaceless)") +
                       std::string(kInstallHint));
    }
    EGLDisplay display =
        eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    EGLint major = 0, minor = 0;
    if (display == EGL_NO_DISPLAY || !eglInitialize(display, &major, &minor)) {
      fail(kWhere, "cannot initialise the surfaceless EGL display: " + egl_error_text() +
                       std::string(kInstallHint));
    }
    return display;
  }

  static inline std::mutex mutex_;
  static inline int users_ = 0;
  static inline EGLDisplay display_ = EGL_NO_DISPLAY;
};

class EglContext : public GlContext {
 public:
  explicit EglContext(Rasteriser rasteriser) : display_(SurfacelessDisplay::acquire(rasteriser)) {
    try {
      create();
    } catch (...) {
      SurfacelessDisplay::release();
      throw;
    }
  }
  // Makes current again the EGL context that was current when this one was made (nested
  // contexts, such as a far-field baker's inside a walk, must be destroyed in reverse order of
  // making). A GLFW window's GLX context is not EGL's to see: its owner makes it current again.
  ~EglContext() override {
    if (eglGetCurrentContext() == context_) {
      if (previous_.context == EGL_NO_CONTEXT ||
          !eglMakeCurrent(previous_.display, previous_.draw, previous_.read, previous_.context))
        eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    }
    eglDestroyContext(display_, context_);
    SurfacelessDisplay::release();
  }
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  std::string renderer_name() const override {
    return reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  }

 private:
  void create() {
    if (!has_extension(eglQueryString(display_, EGL_EXTENSIONS), "EGL_KHR_surfaceless_context")) {
      fail(kWhere,
           "EGL cannot make a context current without a surface "
           "(EGL_KHR_surfaceless_context missing)" +
               std::string(kInstallHint));
    }
    // The surfaceless platform offers pbuffer configurations only (the default asks for windows).
    const EGLint config_attributes[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE,
                                        EGL_OPENGL_BIT, EGL_NONE};
    EGLConfig config = nullptr;
    EGLint count = 0;
    if (!eglChooseConfig(display_, config_attributes, &config, 1, &count) || count == 0) {
      fail(kWhere, "no EGL configuration supports desktop OpenGL: " + egl_error_text());
    }
    // What is current for the API bound now (before binding desktop GL): given back at the end.
    previous_ = {eglGetCurrentDisplay(), eglGetCurrentSurface(EGL_DRAW), eglGetCurrentSurface(EGL_READ),
                 eglGetCurrentContext()};
    if (!eglBindAPI(EGL_OPENGL_API)) fail(kWhere, "EGL cannot bind desktop OpenGL");
    const EGLint context_attributes[] = {EGL_CONTEXT_MAJOR_VERSION,
                                         4,
                                         EGL_CONTEXT_MINOR_VERSION,
                                         5,
                                         EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                         EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                         EGL_NONE};
    context_ = eglCreateContext(display_, config, EGL_NO_CONTEXT, context_attributes);
    if (context_ == EGL_NO_CONTEXT) {
      fail(kWhere, "cannot create an OpenGL 4.5 core context: " + egl_error_text() +
                       " (needs Mesa 20 or newer)");
    }
    if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_)) {
      eglDestroyContext(display_, context_);
      fail(kWhere, "cannot make the OpenGL context current: " + egl_error_text());
    }
  }

  // The EGL binding current before this context was made.
  struct Binding {
    EGLDisplay display = EGL_NO_DISPLAY;
    EGLSurface draw = EGL_NO_SURFACE, read = EGL_NO_SURFACE;
    EGLContext context = EGL_NO_CONTEXT;
  };

  EGLDisplay display_;
  EGLContext context_ = EGL_NO_CONTEXT;
  Binding previous_;
};

}  // namespace

std::unique_ptr<GlContext> GlContext::headless(Rasteriser rasteriser) {
  return std::make_unique<EglContext>(rasteriser);
}

}  // namespace cellwalk
