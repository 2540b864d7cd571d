// The EGL display and context of the EGL renderer (see egl_context.h).
#include "egl/egl_context.h"

#include <algorithm>
#include <cstdio>
#include <map>
#include <mutex>
#include <vector>

#include <EGL/eglext.h>

#include "weft/error.h"

namespace weft::render::detail {
namespace {

std::string egl_error_name(EGLint code) {
    switch (code) {
        case EGL_SUCCESS: return "EGL_SUCCESS";
        case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
        case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
        case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
        case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
        case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
        case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
        case EGL_BAD_CURRENT_SURFACE: return "EGL_BAD_CURRENT_SURFACE";
        case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
        case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
        case EGL_BAD_NATIVE_PIXMAP: return "EGL_BAD_NATIVE_PIXMAP";
        case EGL_BAD_NATIVE_WINDOW: return "EGL_BAD_NATIVE_WINDOW";
        case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
        case EGL_BAD_SURFACE: return "EGL_BAD_SURFACE";
        case EGL_CONTEXT_LOST: return "EGL_CONTEXT_LOST";
        default: {
            char hex[16];
            std::snprintf(hex, sizeof hex, "0x%04X", static_cast<unsigned>(code));
            return hex;
        }
    }
}

std::string last_error() { return egl_error_name(eglGetError()); }

/// Whether the space-separated `list` (an EGL extension string, may be null) holds `name`.
bool has_extension(const char* list, std::string_view name) {
    if (list == nullptr) return false;
    std::string_view rest(list);
    while (!rest.empty()) {
        const std::size_t space = rest.find(' ');
        if (rest.substr(0, space) == name) return true;
        if (space == std::string_view::npos) break;
        rest.remove_prefix(space + 1);
    }
    return false;
}

// EGL gives every caller in the process the same display for the same platform and device, and
// eglTerminate ends every context on it. So the renderers count their contexts per display: the
// last one to go terminates it, and only when a renderer was the one to initialise it (a display
// that something else in the process had already initialised is left as it was found).
struct DisplayUse {
    int contexts = 0;
    bool terminate = false;
};

struct DisplayRegistry {
    std::mutex mutex;
    std::map<EGLDisplay, DisplayUse> uses;
};

DisplayRegistry& registry() {
    static DisplayRegistry r;
    return r;
}

/// eglInitialize, counted (see DisplayUse). False with the EGL error pending when it fails.
bool acquire_display(EGLDisplay display, EGLint& major, EGLint& minor) {
    DisplayRegistry& r = registry();
    const std::lock_guard lock(r.mutex);
    auto it = r.uses.find(display);
    if (it == r.uses.end()) {
        // eglQueryString answers only on an initialised display.
        const bool initialised_elsewhere = eglQueryString(display, EGL_VENDOR) != nullptr;
        if (!initialised_elsewhere) eglGetError();  // drop the EGL_NOT_INITIALIZED it left
        if (eglInitialize(display, &major, &minor) != EGL_TRUE) return false;
        r.uses.emplace(display, DisplayUse{1, !initialised_elsewhere});
        return true;
    }
    // Initialising again is allowed and gives the version.
    if (eglInitialize(display, &major, &minor) != EGL_TRUE) return false;
    ++it->second.contexts;
    return true;
}

void release_display(EGLDisplay display) {
    DisplayRegistry& r = registry();
    const std::lock_guard lock(r.mutex);
    auto it = r.uses.find(display);
    if (it == r.uses.end()) return;
    if (--it->second.contexts > 0) return;
    if (it->second.terminate) eglTerminate(display);
    r.uses.erase(it);
}

struct Opened {
    EGLContext context = EGL_NO_CONTEXT;
    EGLSurface surface = EGL_NO_SURFACE;
};

/// A 4.5 core context on the initialised `display`, made current. Returns why it failed (empty
/// on success); leaves nothing behind on failure.
std::string make_context(EGLDisplay display, EGLint major, EGLint minor, bool debug, Opened& out) {
    const char* extensions = eglQueryString(display, EGL_EXTENSIONS);
    const bool egl15 = major > 1 || (major == 1 && minor >= 5);
    const std::string version = std::to_string(major) + "." + std::to_string(minor);
    // Context versions and profiles are EGL 1.5 or EGL_KHR_create_context (same attribute values).
    if (!egl15 && !has_extension(extensions, "EGL_KHR_create_context"))
        return "EGL " + version + " without EGL_KHR_create_context";
    if (eglBindAPI(EGL_OPENGL_API) != EGL_TRUE) {
        const char* apis = eglQueryString(display, EGL_CLIENT_APIS);
        return std::string("no desktop OpenGL (client APIs: ") + (apis != nullptr ? apis : "?") + ")";
    }
    // Drawing goes to framebuffer objects: a surface is needed only to make the context current,
    // and not even that with EGL_KHR_surfaceless_context.
    const bool surfaceless = has_extension(extensions, "EGL_KHR_surfaceless_context");
    const EGLint config_attributes[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_SURFACE_TYPE,
                                        surfaceless ? 0 : EGL_PBUFFER_BIT, EGL_NONE};
    EGLConfig config = nullptr;
    EGLint configs = 0;
    if (eglChooseConfig(display, config_attributes, &config, 1, &configs) != EGL_TRUE || configs < 1)
        return std::string("no OpenGL config") + (surfaceless ? "" : " with pbuffers");

    std::vector<EGLint> attributes = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                                      EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT};
    if (debug) {
        if (egl15)
            attributes.insert(attributes.end(), {EGL_CONTEXT_OPENGL_DEBUG, EGL_TRUE});
        else
            attributes.insert(attributes.end(), {EGL_CONTEXT_FLAGS_KHR, EGL_CONTEXT_OPENGL_DEBUG_BIT_KHR});
    }
    attributes.push_back(EGL_NONE);
    const EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, attributes.data());
    if (context == EGL_NO_CONTEXT)
        return std::string("no OpenGL 4.5 core") + (debug ? " debug" : "") + " context (" + last_error() + ")";

    EGLSurface surface = EGL_NO_SURFACE;
    if (!surfaceless) {
        const EGLint pbuffer_attributes[] = {EGL_WIDTH, 1, EGL_HEIGHT, 1, EGL_NONE};
        surface = eglCreatePbufferSurface(display, config, pbuffer_attributes);
        if (surface == EGL_NO_SURFACE) {
            const std::string why = "no EGL_KHR_surfaceless_context and no pbuffer (" + last_error() + ")";
            eglDestroyContext(display, context);
            return why;
        }
    }
    if (eglMakeCurrent(display, surface, surface, context) != EGL_TRUE) {
        const std::string why = "eglMakeCurrent failed (" + last_error() + ")";
        if (surface != EGL_NO_SURFACE) eglDestroySurface(display, surface);
        eglDestroyContext(display, context);
        return why;
    }
    out = {context, surface};
    return {};
}

/// Initialises `display` and makes a context on it. Returns why it failed (empty on success).
std::string open_display(EGLDisplay display, bool debug, Opened& out) {
    if (display == EGL_NO_DISPLAY) return "no display (" + last_error() + ")";
    EGLint major = 0;
    EGLint minor = 0;
    if (!acquire_display(display, major, minor)) return "eglInitialize failed (" + last_error() + ")";
    std::string why = make_context(display, major, minor, debug, out);
    if (!why.empty()) release_display(display);
    return why;
}

/// "software" or the DRM device file of an EGL device, for messages.
std::string describe_device(EGLDeviceEXT device, PFNEGLQUERYDEVICESTRINGEXTPROC query_device_string) {
    if (query_device_string == nullptr) return {};
    const char* extensions = query_device_string(device, EGL_EXTENSIONS);
    if (has_extension(extensions, "EGL_MESA_device_software")) return " (software)";
    if (has_extension(extensions, "EGL_EXT_device_drm")) {
        const char* file = query_device_string(device, EGL_DRM_DEVICE_FILE_EXT);
        if (file != nullptr) return std::string(" (") + file + ")";
    }
    return {};
}

template <typename F>
F egl_function(const char* name) {
    // eglGetProcAddress returns a generic function pointer, cast to the real type as EGL intends.
    return reinterpret_cast<F>(eglGetProcAddress(name));
}

}  // namespace

EglContext::EglContext(bool debug) {
    std::vector<std::string> tried;
    const auto open = [&](EGLDisplay display, const char* platform, const std::string& label) {
        Opened opened;
        const std::string why = open_display(display, debug, opened);
        if (!why.empty()) {
            tried.push_back(label + ": " + why);
            return false;
        }
        display_ = display;
        context_ = opened.context;
        surface_ = opened.surface;
        platform_ = platform;
        return true;
    };

    // Client extensions (no display): null, with EGL_BAD_DISPLAY pending, before EGL 1.5.
    const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    if (client == nullptr) eglGetError();
    const auto get_platform_display = has_extension(client, "EGL_EXT_platform_base")
                                          ? egl_function<PFNEGLGETPLATFORMDISPLAYEXTPROC>("eglGetPlatformDisplayEXT")
                                          : nullptr;

    // 1. Devices: a GPU needs no display server this way.
    const bool enumeration =
        has_extension(client, "EGL_EXT_device_enumeration") || has_extension(client, "EGL_EXT_device_base");
    if (get_platform_display == nullptr) {
        tried.emplace_back("device platform: no EGL_EXT_platform_base");
    } else if (!enumeration || !has_extension(client, "EGL_EXT_platform_device")) {
        tried.emplace_back("device platform: no EGL_EXT_device_enumeration and EGL_EXT_platform_device");
    } else {
        const auto query_devices = egl_function<PFNEGLQUERYDEVICESEXTPROC>("eglQueryDevicesEXT");
        const auto query_device_string = egl_function<PFNEGLQUERYDEVICESTRINGEXTPROC>("eglQueryDeviceStringEXT");
        EGLint count = 0;
        std::vector<EGLDeviceEXT> devices;
        if (query_devices != nullptr && query_devices(0, nullptr, &count) == EGL_TRUE && count > 0) {
            devices.resize(static_cast<std::size_t>(count));
            if (query_devices(count, devices.data(), &count) != EGL_TRUE) count = 0;
            devices.resize(static_cast<std::size_t>(std::max(count, 0)));
        }
        if (devices.empty()) tried.emplace_back("device platform: no EGL devices");
        for (std::size_t k = 0; k < devices.size(); ++k) {
            const std::string label = "device " + std::to_string(k) + describe_device(devices[k], query_device_string);
            if (open(get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[k], nullptr), "device", label)) return;
        }
    }

    // 2. Mesa's surfaceless platform: render nodes or software, no window system.
    if (get_platform_display != nullptr && has_extension(client, "EGL_MESA_platform_surfaceless")) {
        if (open(get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, nullptr, nullptr), "surfaceless",
                 "surfaceless platform"))
            return;
    } else {
        tried.emplace_back("surfaceless platform: no EGL_MESA_platform_surfaceless");
    }

    // 3. Whatever the EGL implementation picks (EGL_PLATFORM in the environment, for Mesa).
    if (open(eglGetDisplay(EGL_DEFAULT_DISPLAY), "default", "default display")) return;

    std::string list;
    for (const std::string& t : tried) list += (list.empty() ? "" : "; ") + t;
    throw Error("egl renderer: no EGL display gives an OpenGL 4.5 core context (tried " + list + ")");
}

EglContext::~EglContext() {
    if (context_ == EGL_NO_CONTEXT) return;
    eglBindAPI(EGL_OPENGL_API);
    if (eglGetCurrentContext() == context_) eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display_, context_);
    if (surface_ != EGL_NO_SURFACE) eglDestroySurface(display_, surface_);
    // This thread's EGL state goes too, unless another renderer's context is current on it.
    if (eglGetCurrentContext() == EGL_NO_CONTEXT) eglReleaseThread();
    release_display(display_);
}

void EglContext::make_current() const {
    eglBindAPI(EGL_OPENGL_API);
    if (eglGetCurrentContext() == context_) return;
    if (eglMakeCurrent(display_, surface_, surface_, context_) != EGL_TRUE)
        throw Error("egl renderer: eglMakeCurrent failed (" + last_error() +
                    "); is the renderer's context current on another thread?");
}

void EglContext::release_current() const {
    eglBindAPI(EGL_OPENGL_API);
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
}

}  // namespace weft::render::detail
