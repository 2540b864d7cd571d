// ImGui in the live window (see imgui_layer.h).
#include "weft/editor/imgui_layer.h"

#include <vulkan/vulkan.h>

#include <algorithm>
#include <array>
#include <string>

#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_vulkan.h>

#include "weft/error.h"

namespace weft::editor {
namespace {

// ImGui's Vulkan backend reports failures through this hook; it cannot throw through C frames
// safely, so the first failure is kept and thrown after the call returns.
VkResult g_vulkan_error = VK_SUCCESS;
extern "C" void check_vk(VkResult result) {
    if (result < 0 && g_vulkan_error == VK_SUCCESS) g_vulkan_error = result;
}
void throw_if_failed(const char* what) {
    const VkResult r = g_vulkan_error;
    g_vulkan_error = VK_SUCCESS;
    if (r != VK_SUCCESS) throw Error(std::string("editor: ImGui's Vulkan backend failed in ") + what +
                                     " (VkResult " + std::to_string(static_cast<int>(r)) + ")");
}

}  // namespace

struct ImGuiLayer::Impl {
    render::Window& window;
    render::OverlayVulkan vulkan;
    std::string ini;  ///< ImGui keeps the pointer: the string must outlive the context
    VkDescriptorPool pool = VK_NULL_HANDLE;
    bool context = false, glfw = false, backend = false;
    bool frame_ended = false;  ///< ImGui::Render() ran since the last begin_frame

    float scale = 1.0F;

    Impl(render::Window& w, const std::filesystem::path& ini_file, float requested_scale)
        : window(w), vulkan(w.overlay_vulkan()) {
        try {
            start(ini_file, requested_scale);
        } catch (...) {
            stop();
            throw;
        }
    }
    ~Impl() { stop(); }
    Impl(const Impl&) = delete;
    Impl& operator=(const Impl&) = delete;

    void start(const std::filesystem::path& ini_file, float requested_scale) {
        IMGUI_CHECKVERSION();
        ImGui::CreateContext();
        context = true;
        ImGuiIO& io = ImGui::GetIO();
        ini = ini_file.string();
        io.IniFilename = ini.empty() ? nullptr : ini.c_str();
        ImGui::StyleColorsDark();
        // High-DPI screens: the font is rasterised at the scaled size (sharp, not a stretched
        // 13-pixel atlas) and every padding and spacing grows with it.
        scale = requested_scale;
        if (scale <= 0.0F) {
            float x = 1.0F, y = 1.0F;
            glfwGetWindowContentScale(vulkan.window, &x, &y);
            scale = std::clamp(std::max(x, y), 0.5F, 4.0F);
        }
        if (scale != 1.0F) {
            ImFontConfig font;
            font.SizePixels = 13.0F * scale;
            io.Fonts->AddFontDefault(&font);
            ImGui::GetStyle().ScaleAllSizes(scale);
        }
        // The callbacks chain to those the viewer installed (camera, keys), which ask wants_mouse().
        if (!ImGui_ImplGlfw_InitForVulkan(vulkan.window, true)) throw Error("editor: ImGui's GLFW backend did not start");
        glfw = true;

        // The font texture's sampler is ImGui's one descriptor: a small pool is plenty.
        const std::array<VkDescriptorPoolSize, 1> sizes{{{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 16}}};
        VkDescriptorPoolCreateInfo pool_info{};
        pool_info.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO;
        pool_info.flags = VK_DESCRIPTOR_POOL_CREATE_FREE_DESCRIPTOR_SET_BIT;
        pool_info.maxSets = 16;
        pool_info.poolSizeCount = static_cast<std::uint32_t>(sizes.size());
        pool_info.pPoolSizes = sizes.data();
        if (vkCreateDescriptorPool(vulkan.device, &pool_info, nullptr, &pool) != VK_SUCCESS)
            throw Error("editor: vkCreateDescriptorPool for ImGui failed");

        ImGui_ImplVulkan_InitInfo info{};
        info.Instance = vulkan.instance;
        info.PhysicalDevice = vulkan.physical_device;
        info.Device = vulkan.device;
        info.QueueFamily = vulkan.queue_family;
        info.Queue = vulkan.queue;
        info.PipelineCache = VK_NULL_HANDLE;
        info.DescriptorPool = pool;
        info.Subpass = 0;
        info.MinImageCount = vulkan.frames;
        info.ImageCount = vulkan.frames;  // per-frame vertex buffers: one frame in flight, so 2 suffice
        info.MSAASamples = VK_SAMPLE_COUNT_1_BIT;
        info.Allocator = nullptr;
        info.CheckVkResultFn = check_vk;
        if (!ImGui_ImplVulkan_Init(&info, vulkan.render_pass)) throw Error("editor: ImGui's Vulkan backend did not start");
        backend = true;
        throw_if_failed("ImGui_ImplVulkan_Init");
        vulkan.submit_and_wait([](VkCommandBuffer commands) { ImGui_ImplVulkan_CreateFontsTexture(commands); });
        ImGui_ImplVulkan_DestroyFontUploadObjects();
        throw_if_failed("the font upload");
    }

    void stop() noexcept {
        if (vulkan.device != VK_NULL_HANDLE) vkDeviceWaitIdle(vulkan.device);
        if (backend) ImGui_ImplVulkan_Shutdown();
        if (glfw) ImGui_ImplGlfw_Shutdown();
        if (context) ImGui::DestroyContext();
        if (pool != VK_NULL_HANDLE) vkDestroyDescriptorPool(vulkan.device, pool, nullptr);
        backend = glfw = context = false;
        pool = VK_NULL_HANDLE;
    }
};

ImGuiLayer::ImGuiLayer(render::Window& window, const std::filesystem::path& ini_file, float scale)
    : impl_(std::make_unique<Impl>(window, ini_file, scale)) {
    window.set_overlay(this);
}

ImGuiLayer::~ImGuiLayer() { impl_->window.set_overlay(nullptr); }

float ImGuiLayer::scale() const { return impl_->scale; }

void ImGuiLayer::begin_frame() {
    ImGui_ImplVulkan_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    impl_->frame_ended = false;
}

void ImGuiLayer::end_frame() {
    ImGui::Render();
    impl_->frame_ended = true;
}

void ImGuiLayer::record(VkCommandBuffer commands, VkExtent2D /*extent*/) {
    // A present without a finished ImGui frame (none begun yet) draws no panels.
    if (!impl_->frame_ended) return;
    ImDrawData* data = ImGui::GetDrawData();
    if (data != nullptr) ImGui_ImplVulkan_RenderDrawData(data, commands);
    throw_if_failed("ImGui_ImplVulkan_RenderDrawData");
}

// Ctrl and Shift turn the left button to the cloth (grab, pin): the camera must not orbit then.
bool ImGuiLayer::wants_mouse() const {
    const ImGuiIO& io = ImGui::GetIO();
    return io.WantCaptureMouse || io.KeyCtrl || io.KeyShift;
}

ImGuiLayer::Mouse ImGuiLayer::mouse() const {
    const ImGuiIO& io = ImGui::GetIO();
    Mouse m;
    m.x = static_cast<double>(io.MousePos.x * io.DisplayFramebufferScale.x);
    m.y = static_cast<double>(io.MousePos.y * io.DisplayFramebufferScale.y);
    m.on_panels = io.WantCaptureMouse;
    m.pressed = io.MouseClicked[0];
    m.down = io.MouseDown[0];
    m.released = io.MouseReleased[0];
    m.moved = io.MouseDelta.x != 0.0F || io.MouseDelta.y != 0.0F;
    m.ctrl = io.KeyCtrl;
    m.shift = io.KeyShift;
    return m;
}

bool ImGuiLayer::wants_keyboard() const { return ImGui::GetIO().WantCaptureKeyboard; }

}  // namespace weft::editor
