// The live window (window.h): GLFW opens it and makes its Vulkan surface, the Vulkan renderer draws
// each frame and blits it into a swapchain image, which is then presented.
//
// Per frame: wait for the previous frame's fence (one frame in flight: the renderer has one command
// buffer and one set of mapped buffers), acquire an image (signalling `acquired_`), submit the
// passes and the blit (waiting for `acquired_` before the blit, signalling the image's "rendered"
// semaphore), present after "rendered". The CPU does not wait for the frame it has just submitted,
// so whatever the caller does until the next present (the simulation) overlaps the drawing.
#include <vulkan/vulkan.h>

// glfwCreateWindowSurface is declared only with the Vulkan header included first.
#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "weft/error.h"
#include "weft/render/window.h"
#include "weft/render/window_overlay.h"

#include "vulkan/vulkan_check.h"
#include "vulkan/vulkan_renderer.h"
#include "vulkan/vulkan_swapchain.h"
#include "window/window_input.h"

namespace weft::render {
namespace {

std::string g_glfw_error;  // the last error GLFW reported (its callback has no user data)

extern "C" void on_glfw_error(int code, const char* description) {
    g_glfw_error = std::to_string(code) + ": " + (description != nullptr ? description : "?");
}

// glfwInit and glfwTerminate for the process, counted so that windows may come and go.
int g_glfw_users = 0;

void acquire_glfw() {
    if (g_glfw_users == 0) {
        glfwSetErrorCallback(on_glfw_error);
        g_glfw_error.clear();
        if (glfwInit() != GLFW_TRUE)
            throw Error("window: no display: set DISPLAY or run under xvfb-run (GLFW error " +
                        (g_glfw_error.empty() ? std::string("unknown") : g_glfw_error) + ")");
    }
    ++g_glfw_users;
}

void release_glfw() noexcept {
    if (--g_glfw_users == 0) glfwTerminate();
}

struct GlfwUser {
    GlfwUser() { acquire_glfw(); }
    ~GlfwUser() { release_glfw(); }
    GlfwUser(const GlfwUser&) = delete;
    GlfwUser& operator=(const GlfwUser&) = delete;
};

struct GlfwWindow {
    GLFWwindow* handle = nullptr;
    GlfwWindow(int width, int height, const std::string& title) {
        glfwDefaultWindowHints();
        glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);  // Vulkan draws, not OpenGL
        glfwWindowHint(GLFW_RESIZABLE, GLFW_TRUE);
        handle = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
        if (handle == nullptr) throw Error("window: glfwCreateWindow failed (GLFW error " + g_glfw_error + ")");
    }
    ~GlfwWindow() { glfwDestroyWindow(handle); }
    GlfwWindow(const GlfwWindow&) = delete;
    GlfwWindow& operator=(const GlfwWindow&) = delete;
};

detail::SurfaceRequest surface_request(GLFWwindow* window) {
    if (glfwVulkanSupported() != GLFW_TRUE)
        throw Error("window: GLFW found no Vulkan loader (Debian package libvulkan1) (GLFW error " + g_glfw_error +
                    ")");
    std::uint32_t count = 0;
    const char** names = glfwGetRequiredInstanceExtensions(&count);
    if (names == nullptr)
        throw Error("window: GLFW knows no Vulkan surface extensions for this window system (GLFW error " +
                    g_glfw_error + ")");
    detail::SurfaceRequest request;
    for (std::uint32_t i = 0; i < count; ++i)
        if (names[i] != nullptr) request.instance_extensions.emplace_back(names[i]);
    request.create_surface = [window](VkInstance instance) {
        VkSurfaceKHR surface = VK_NULL_HANDLE;
        WEFT_VK_CHECK(glfwCreateWindowSurface(instance, window, nullptr, &surface));
        return surface;
    };
    return request;
}

VkExtent2D framebuffer_size(GLFWwindow* window) {
    int width = 0;
    int height = 0;
    glfwGetFramebufferSize(window, &width, &height);
    return {static_cast<std::uint32_t>(std::max(width, 0)), static_cast<std::uint32_t>(std::max(height, 0))};
}

}  // namespace

struct Window::Impl {
    // Declared in the order they are made; destroyed in reverse: input, swapchain and renderer (with
    // the device, the surface and the instance) go before the window and GLFW.
    GlfwUser glfw;
    GlfwWindow window;
    detail::WindowInput input;
    detail::SurfaceRequest request;  ///< the window's surface extensions and glfwCreateWindowSurface
    detail::VulkanRenderer renderer;
    std::unique_ptr<detail::Swapchain> swapchain;
    VkSemaphore acquired = VK_NULL_HANDLE;
    WindowOverlay* overlay = nullptr;  ///< not owned (set_overlay)
    bool recreate = false;
    bool presented = false;

    Impl(const RendererOptions& options, const std::string& title)
        : window(options.width, options.height, title),
          input(window.handle),
          request(surface_request(window.handle)),
          renderer(checked(options), &request) {
        const VkExtent2D size = framebuffer_size(window.handle);
        swapchain = std::make_unique<detail::Swapchain>(renderer.context(), size);
        VkSemaphoreCreateInfo info{};
        info.sType = VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO;
        WEFT_VK_CHECK(vkCreateSemaphore(renderer.context().device(), &info, nullptr, &acquired));
        const VkExtent2D e = swapchain->extent();
        renderer.resize(static_cast<int>(e.width), static_cast<int>(e.height));
    }
    ~Impl() {
        const VkDevice device = renderer.context().device();
        vkDeviceWaitIdle(device);
        swapchain.reset();
        if (acquired != VK_NULL_HANDLE) vkDestroySemaphore(device, acquired, nullptr);
    }
    Impl(const Impl&) = delete;
    Impl& operator=(const Impl&) = delete;

    static const RendererOptions& checked(const RendererOptions& options) {
        if (options.width < 16 || options.height < 16 || options.width > 16384 || options.height > 16384)
            throw Error("window: size " + std::to_string(options.width) + "×" + std::to_string(options.height) +
                        " is outside 16..16384 pixels per side");
        if (options.samples != 1 && options.samples != 2 && options.samples != 4 && options.samples != 8)
            throw Error("window: " + std::to_string(options.samples) + " MSAA samples (expected 1, 2, 4 or 8)");
        if (options.shadow_map_size < 16 || options.shadow_map_size > 16384)
            throw Error("window: shadow map size " + std::to_string(options.shadow_map_size) + " is outside 16..16384");
        return options;
    }
    void recreate_swapchain() {
        swapchain->recreate(framebuffer_size(window.handle));
        const VkExtent2D e = swapchain->extent();
        renderer.resize(static_cast<int>(e.width), static_cast<int>(e.height));
        recreate = false;
    }

    void present(const RenderFrame& frame) {
        const VkExtent2D size = framebuffer_size(window.handle);
        if (size.width == 0 || size.height == 0) {  // minimised: nothing to show
            renderer.skip_frame(frame);
            return;
        }
        if (input.take_resized()) recreate = true;
        if (recreate) recreate_swapchain();
        renderer.set_camera(input.camera().camera());
        // The previous frame waited on `acquired` and used the command buffer: both free after this.
        renderer.wait_frame();
        std::uint32_t index = 0;
        detail::Swapchain::Status acquired_status = swapchain->acquire(acquired, index);
        if (acquired_status == detail::Swapchain::Status::out_of_date) {
            recreate_swapchain();
            acquired_status = swapchain->acquire(acquired, index);
            if (acquired_status == detail::Swapchain::Status::out_of_date) {
                recreate = true;  // still changing size: try again next frame
                renderer.skip_frame(frame);
                return;
            }
        }
        detail::SwapchainTarget target;
        target.image = swapchain->image(index);
        target.extent = swapchain->extent();
        target.acquired = acquired;
        target.rendered = swapchain->rendered(index);
        if (overlay != nullptr) {
            (void)renderer.overlay_pass();
            target.overlay = [this](VkCommandBuffer commands, VkExtent2D extent) { overlay->record(commands, extent); };
        }
        renderer.draw_to_swapchain(frame, target);
        presented = true;
        const detail::Swapchain::Status presented_status = swapchain->present(index);
        if (acquired_status != detail::Swapchain::Status::ok || presented_status != detail::Swapchain::Status::ok)
            recreate = true;
    }
};

Window::Window(const RendererOptions& options, const std::string& title)
    : impl_(std::make_unique<Impl>(options, title)) {}

Window::~Window() = default;

std::string Window::device_description() const { return impl_->renderer.device_description(); }

void Window::load(const RenderScene& scene) {
    impl_->renderer.load(scene);
    impl_->input.camera() = detail::OrbitCamera(scene.camera);
}

bool Window::poll_events() {
    glfwPollEvents();
    // Minimised: a zero-sized framebuffer has nothing to draw; sleep until that changes.
    while (glfwWindowShouldClose(impl_->window.handle) == GLFW_FALSE && !impl_->input.quit()) {
        const VkExtent2D size = framebuffer_size(impl_->window.handle);
        if (size.width != 0 && size.height != 0) break;
        glfwWaitEvents();
    }
    return glfwWindowShouldClose(impl_->window.handle) == GLFW_FALSE && !impl_->input.quit();
}

ViewerRequests Window::take_requests() { return impl_->input.take_requests(); }

void Window::present(const RenderFrame& frame) { impl_->present(frame); }

Image Window::screenshot() {
    if (!impl_->presented) throw Error("window: screenshot() before the first present()");
    return impl_->renderer.read_back();
}

void Window::set_title(const std::string& title) { glfwSetWindowTitle(impl_->window.handle, title.c_str()); }

const Camera& Window::camera() const { return impl_->input.camera().camera(); }

void Window::reset_camera() { impl_->input.camera().reset(); }

void Window::set_camera(const Camera& camera) { impl_->input.camera() = detail::OrbitCamera(camera); }

GameInput Window::game_input() const {
    GLFWwindow* w = impl_->window.handle;
    const auto held = [w](int a, int b) { return glfwGetKey(w, a) == GLFW_PRESS || glfwGetKey(w, b) == GLFW_PRESS; };
    GameInput in;
    in.forward = (held(GLFW_KEY_W, GLFW_KEY_UP) ? 1.0F : 0.0F) - (held(GLFW_KEY_S, GLFW_KEY_DOWN) ? 1.0F : 0.0F);
    in.turn = (held(GLFW_KEY_D, GLFW_KEY_RIGHT) ? 1.0F : 0.0F) - (held(GLFW_KEY_A, GLFW_KEY_LEFT) ? 1.0F : 0.0F);
    in.jump = glfwGetKey(w, GLFW_KEY_SPACE) == GLFW_PRESS;
    in.run = held(GLFW_KEY_LEFT_SHIFT, GLFW_KEY_RIGHT_SHIFT);
    GLFWgamepadstate pad{};
    if (glfwJoystickIsGamepad(GLFW_JOYSTICK_1) == GLFW_TRUE && glfwGetGamepadState(GLFW_JOYSTICK_1, &pad) == GLFW_TRUE) {
        in.gamepad = true;
        constexpr float kDeadZone = 0.2F;
        const float x = pad.axes[GLFW_GAMEPAD_AXIS_LEFT_X], y = -pad.axes[GLFW_GAMEPAD_AXIS_LEFT_Y];  // stick up is −1
        if (std::abs(y) > kDeadZone) in.forward = std::clamp(in.forward + y, -1.0F, 1.0F);
        if (std::abs(x) > kDeadZone) in.turn = std::clamp(in.turn + x, -1.0F, 1.0F);
        in.jump = in.jump || pad.buttons[GLFW_GAMEPAD_BUTTON_A] == GLFW_PRESS;
        in.run = in.run || pad.buttons[GLFW_GAMEPAD_BUTTON_RIGHT_BUMPER] == GLFW_PRESS;
    }
    return in;
}

int Window::width() const { return impl_->renderer.width(); }

int Window::height() const { return impl_->renderer.height(); }

void Window::set_overlay(WindowOverlay* overlay) {
    impl_->overlay = overlay;
    impl_->input.set_overlay(overlay);
}

OverlayVulkan Window::overlay_vulkan() {
    detail::VulkanRenderer& renderer = impl_->renderer;
    const detail::VulkanContext& context = renderer.context();
    OverlayVulkan out;
    out.instance = context.instance();
    out.physical_device = context.physical_device();
    out.device = context.device();
    out.queue_family = context.queue_family();
    out.queue = context.queue();
    out.render_pass = renderer.overlay_pass();
    out.format = detail::VulkanRenderer::colour_format();
    out.frames = 2;
    out.window = impl_->window.handle;
    out.submit_and_wait = [&context](const std::function<void(VkCommandBuffer)>& record) {
        context.submit_and_wait(record);
    };
    return out;
}

Renderer& Window::renderer() { return impl_->renderer; }

int Window::validation_messages() const { return impl_->renderer.validation_messages(); }

TransferStats Window::transfer() const { return impl_->renderer.transfer(); }

}  // namespace weft::render
