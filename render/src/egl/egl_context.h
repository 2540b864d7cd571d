#pragma once
// The headless EGL display and OpenGL 4.5 core context the EGL renderer draws with.
#include <string>
#include <string_view>

#include <EGL/egl.h>

namespace weft::render::detail {

/// An OpenGL 4.5 core context with no window: made on the first EGL display that gives one, in
/// this order: each device of EGL_EXT_device_enumeration (EGL_EXT_platform_device: a GPU without
/// a display server, or Mesa's software device), Mesa's surfaceless platform, then the default
/// display. Current on the creating thread once made; `make_current` makes it current again (one
/// thread may hold several contexts and switch between them).
class EglContext {
public:
    /// Throws `weft::Error` listing every display tried and why it failed when none gives a
    /// context. `debug`: a debug context (KHR_debug messages for validation).
    explicit EglContext(bool debug);
    ~EglContext();
    EglContext(const EglContext&) = delete;
    EglContext& operator=(const EglContext&) = delete;

    /// Makes this context current on the calling thread; throws `weft::Error` when EGL refuses
    /// (for instance, the context is current on another thread).
    void make_current() const;
    /// Leaves the calling thread with no OpenGL context current (whichever was).
    void release_current() const;
    /// The platform of the display: "device", "surfaceless" or "default".
    [[nodiscard]] std::string_view platform() const { return platform_; }

private:
    EGLDisplay display_ = EGL_NO_DISPLAY;
    EGLContext context_ = EGL_NO_CONTEXT;
    EGLSurface surface_ = EGL_NO_SURFACE;  ///< a 1×1 pbuffer where EGL_KHR_surfaceless_context is missing
    std::string platform_;
};

}  // namespace weft::render::detail
