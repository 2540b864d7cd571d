// The Vulkan renderer: a shadow map pass, a multisampled surface pass resolved to one sample, and
// the frame's ending (a copy of the picture to the host, or a blit into a window's swapchain image),
// recorded into one command buffer per frame whose submission signals a fence.
//
// This file holds what every frame shares: targets, pipelines, the scene's buffers (load), the
// recording of the passes and the submission. How a frame ends lives beside it:
//   - vulkan_renderer_capture.cpp: the copy of the picture to the host (submit, collect, read_back);
//   - vulkan_renderer_present.cpp: the blit into a window's swapchain image (draw_to_swapchain), not
//     waited for: the next frame waits for its fence first;
//   - vulkan_renderer_export.cpp: the cloth slots handed to CUDA (export_cloth, read_cloth, the
//     queue-family ownership transfers, skip_frame).
//
// Geometry: the cloth vertex buffer (device-local, RenderScene::cloth_vertices × 24 bytes) is filled
// each frame from a persistently mapped staging buffer, or left as it is when the frame brings no
// vertices (the zero-copy path writes it on the device). The colliders' meshes and every index live
// in one static buffer uploaded by load(). Uniforms: the Frame block, then one Draw block per draw
// at the device's uniform offset alignment, selected by a dynamic offset.
#include "vulkan/vulkan_renderer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "weft/error.h"

#include "frame_uniforms.h"
#include "shaders.h"
#include "vulkan/vulkan_check.h"
#include "vulkan/vulkan_context.h"
#include "vulkan/vulkan_pipelines.h"
#include "vulkan/vulkan_resources.h"

namespace weft::render::detail {
namespace {

VkDeviceSize align_up(VkDeviceSize n, VkDeviceSize alignment) { return (n + alignment - 1) / alignment * alignment; }

// The first of `candidates` whose optimal tiling has every feature of `features`.
VkFormat first_format(VkPhysicalDevice device, std::initializer_list<VkFormat> candidates,
                      VkFormatFeatureFlags features) {
    for (const VkFormat f : candidates) {
        VkFormatProperties p{};
        vkGetPhysicalDeviceFormatProperties(device, f, &p);
        if ((p.optimalTilingFeatures & features) == features) return f;
    }
    return VK_FORMAT_UNDEFINED;
}

// The most samples up to `requested` that colour and depth attachments both support (1 always is).
VkSampleCountFlagBits sample_count(const VkPhysicalDeviceLimits& limits, int requested) {
    const VkSampleCountFlags supported = limits.framebufferColorSampleCounts & limits.framebufferDepthSampleCounts;
    for (int s = requested; s > 1; s /= 2)
        if ((supported & static_cast<VkSampleCountFlags>(s)) != 0) return static_cast<VkSampleCountFlagBits>(s);
    return VK_SAMPLE_COUNT_1_BIT;
}

// The clear colour goes to the UNORM target as it is, so it is encoded like the shader's output.
float to_srgb(float c) {
    c = std::clamp(c, 0.0F, 1.0F);
    return c < 0.0031308F ? c * 12.92F : 1.055F * std::pow(c, 1.0F / 2.4F) - 0.055F;
}

}  // namespace

VulkanRenderer::VulkanRenderer(const RendererOptions& options, const SurfaceRequest* surface)
    : options_(options), context_(options.validation, surface) {
    try {
        extent_ = {static_cast<std::uint32_t>(options.width), static_cast<std::uint32_t>(options.height)};
        const auto shadow_size = static_cast<std::uint32_t>(options.shadow_map_size);
        shadow_extent_ = {shadow_size, shadow_size};
        const VkPhysicalDeviceLimits& limits = context_.properties().limits;
        if (extent_.width > limits.maxFramebufferWidth || extent_.height > limits.maxFramebufferHeight ||
            shadow_size > limits.maxImageDimension2D || shadow_size > limits.maxFramebufferWidth)
            throw Error("vulkan renderer: " + std::to_string(extent_.width) + "×" + std::to_string(extent_.height) +
                        " pixels or a shadow map of " + std::to_string(shadow_size) + "² exceed the limits of " +
                        context_.description());
        samples_ = sample_count(limits, options.samples);
        create_targets();
        create_pipelines();
        create_descriptors();
    } catch (...) {
        destroy();
        throw;
    }
}

VulkanRenderer::~VulkanRenderer() { destroy(); }

void VulkanRenderer::create_targets() {
    const VkPhysicalDevice physical = context_.physical_device();
    const VkDevice device = context_.device();
    // Every device has D16 with these features; the others give the shadow test more precision.
    depth_format_ = first_format(physical, {VK_FORMAT_D32_SFLOAT, VK_FORMAT_X8_D24_UNORM_PACK32, VK_FORMAT_D16_UNORM},
                                 VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT);
    shadow_format_ = first_format(physical, {VK_FORMAT_D32_SFLOAT, VK_FORMAT_X8_D24_UNORM_PACK32, VK_FORMAT_D16_UNORM},
                                  VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT);
    if (depth_format_ == VK_FORMAT_UNDEFINED || shadow_format_ == VK_FORMAT_UNDEFINED)
        throw Error("vulkan renderer: no depth format to render and sample on " + context_.description());
    VkFormatProperties shadow_props{};
    vkGetPhysicalDeviceFormatProperties(physical, shadow_format_, &shadow_props);
    // Linear filtering of a compare sampler blends the 2×2 test results: softer PCF where allowed.
    shadow_filter_ = (shadow_props.optimalTilingFeatures & VK_FORMAT_FEATURE_SAMPLED_IMAGE_FILTER_LINEAR_BIT) != 0
                         ? VK_FILTER_LINEAR
                         : VK_FILTER_NEAREST;

    shadow_map_ = create_image(context_, shadow_extent_, shadow_format_, VK_SAMPLE_COUNT_1_BIT,
                               VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT,
                               VK_IMAGE_ASPECT_DEPTH_BIT);
    VkSamplerCreateInfo sampler{};
    sampler.sType = VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO;
    sampler.magFilter = shadow_filter_;
    sampler.minFilter = shadow_filter_;
    sampler.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
    // Outside the map nothing casts a shadow: the border reads as the far plane.
    sampler.addressModeU = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_BORDER;
    sampler.addressModeV = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_BORDER;
    sampler.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_BORDER;
    sampler.borderColor = VK_BORDER_COLOR_FLOAT_OPAQUE_WHITE;
    sampler.compareEnable = VK_TRUE;
    sampler.compareOp = VK_COMPARE_OP_LESS_OR_EQUAL;  // lit where the reference is no deeper than the map
    sampler.maxLod = 0.0F;
    WEFT_VK_CHECK(vkCreateSampler(device, &sampler, nullptr, &shadow_sampler_));

    shadow_pass_ = create_shadow_pass(device, shadow_format_);
    surface_pass_ = create_surface_pass(device, kColourFormat, depth_format_, samples_);
    VkFramebufferCreateInfo fb{};
    fb.sType = VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO;
    fb.renderPass = shadow_pass_;
    fb.attachmentCount = 1;
    fb.pAttachments = &shadow_map_.view;
    fb.width = shadow_extent_.width;
    fb.height = shadow_extent_.height;
    fb.layers = 1;
    WEFT_VK_CHECK(vkCreateFramebuffer(device, &fb, nullptr, &shadow_framebuffer_));

    VkCommandBufferAllocateInfo alloc{};
    alloc.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO;
    alloc.commandPool = context_.command_pool();
    alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    alloc.commandBufferCount = 1;
    WEFT_VK_CHECK(vkAllocateCommandBuffers(device, &alloc, &commands_));
    VkFenceCreateInfo fence{};
    fence.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO;
    WEFT_VK_CHECK(vkCreateFence(device, &fence, nullptr, &fence_));
    create_size_targets();
}

void VulkanRenderer::create_size_targets() {
    const VkDevice device = context_.device();
    // TRANSFER_SRC: copied to the host (capture, screenshots) or blitted to the window.
    resolved_ =
        create_image(context_, extent_, kColourFormat, VK_SAMPLE_COUNT_1_BIT,
                     VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT, VK_IMAGE_ASPECT_COLOR_BIT);
    if (samples_ != VK_SAMPLE_COUNT_1_BIT)
        colour_ = create_image(context_, extent_, kColourFormat, samples_,
                               VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSIENT_ATTACHMENT_BIT,
                               VK_IMAGE_ASPECT_COLOR_BIT);
    depth_ = create_image(context_, extent_, depth_format_, samples_,
                          VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSIENT_ATTACHMENT_BIT,
                          VK_IMAGE_ASPECT_DEPTH_BIT);
    const std::array<VkImageView, 3> views =
        samples_ != VK_SAMPLE_COUNT_1_BIT ? std::array<VkImageView, 3>{colour_.view, depth_.view, resolved_.view}
                                          : std::array<VkImageView, 3>{resolved_.view, depth_.view, VK_NULL_HANDLE};
    VkFramebufferCreateInfo fb{};
    fb.sType = VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO;
    fb.layers = 1;
    fb.renderPass = surface_pass_;
    fb.attachmentCount = samples_ != VK_SAMPLE_COUNT_1_BIT ? 3U : 2U;
    fb.pAttachments = views.data();
    fb.width = extent_.width;
    fb.height = extent_.height;
    WEFT_VK_CHECK(vkCreateFramebuffer(device, &fb, nullptr, &surface_framebuffer_));

    readback_ = create_buffer(context_, VkDeviceSize{extent_.width} * extent_.height * 4,
                              VK_BUFFER_USAGE_TRANSFER_DST_BIT, MemoryUse::readback);
    if (overlay_pass_ != VK_NULL_HANDLE) create_overlay_framebuffer();
}

void VulkanRenderer::destroy_size_targets() noexcept {
    const VkDevice device = context_.device();
    for (VkPipeline p : {surface_pipeline_, wireframe_pipeline_, normals_pipeline_, points_pipeline_})
        if (p != VK_NULL_HANDLE) vkDestroyPipeline(device, p, nullptr);
    wireframe_pipeline_ = normals_pipeline_ = points_pipeline_ = VK_NULL_HANDLE;
    if (surface_framebuffer_ != VK_NULL_HANDLE) vkDestroyFramebuffer(device, surface_framebuffer_, nullptr);
    if (overlay_framebuffer_ != VK_NULL_HANDLE) vkDestroyFramebuffer(device, overlay_framebuffer_, nullptr);
    surface_pipeline_ = VK_NULL_HANDLE;
    surface_framebuffer_ = VK_NULL_HANDLE;
    overlay_framebuffer_ = VK_NULL_HANDLE;
    destroy_buffer(device, readback_);
    destroy_image(device, resolved_);
    destroy_image(device, depth_);
    destroy_image(device, colour_);
}

void VulkanRenderer::resize(int width, int height) {
    if (width < 1 || height < 1 || width > 16384 || height > 16384)
        throw Error("vulkan renderer: resize to " + std::to_string(width) + "×" + std::to_string(height) +
                    " pixels, outside 1..16384 per side");
    const VkPhysicalDeviceLimits& limits = context_.properties().limits;
    if (static_cast<std::uint32_t>(width) > limits.maxFramebufferWidth ||
        static_cast<std::uint32_t>(height) > limits.maxFramebufferHeight)
        throw Error("vulkan renderer: " + std::to_string(width) + "×" + std::to_string(height) +
                    " pixels exceed the limits of " + context_.description());
    if (width == options_.width && height == options_.height) return;
    wait_frame();
    destroy_size_targets();
    have_picture_ = false;
    options_.width = width;
    options_.height = height;
    extent_ = {static_cast<std::uint32_t>(width), static_cast<std::uint32_t>(height)};
    create_size_targets();
    create_surface_pipeline();
}

VkFormat VulkanRenderer::colour_format() { return kColourFormat; }

void VulkanRenderer::set_camera(const Camera& camera) { scene_.camera = camera; }

void VulkanRenderer::wait_frame() {
    if (!in_flight_) return;
    WEFT_VK_CHECK(vkWaitForFences(context_.device(), 1, &fence_, VK_TRUE, UINT64_MAX));
    WEFT_VK_CHECK(vkResetFences(context_.device(), 1, &fence_));
    in_flight_ = false;
    if (frame_reads_stamps_) {
        invalidate(context_, stamp_readback_);
        std::uint64_t stamps[2]{};
        std::memcpy(stamps, stamp_readback_.mapped, sizeof stamps);
        transfer_.stamp_first = stamps[0];
        transfer_.stamp_last = stamps[1];
    }
}

void VulkanRenderer::create_pipelines() {
    const VkDevice device = context_.device();
    // common.glsl: binding 0 Frame, 1 Draw (one set of uniforms per draw, picked by a dynamic
    // offset), 2 the shadow map.
    const std::array<VkDescriptorSetLayoutBinding, 3> bindings{{
        {0, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, nullptr},
        {1, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER_DYNAMIC, 1, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT,
         nullptr},
        {2, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, VK_SHADER_STAGE_FRAGMENT_BIT, nullptr},
    }};
    VkDescriptorSetLayoutCreateInfo set{};
    set.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO;
    set.bindingCount = static_cast<std::uint32_t>(bindings.size());
    set.pBindings = bindings.data();
    WEFT_VK_CHECK(vkCreateDescriptorSetLayout(device, &set, nullptr, &set_layout_));
    VkPipelineLayoutCreateInfo layout{};
    layout.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO;
    layout.setLayoutCount = 1;
    layout.pSetLayouts = &set_layout_;
    WEFT_VK_CHECK(vkCreatePipelineLayout(device, &layout, nullptr, &pipeline_layout_));

    PipelineDesc shadow;
    shadow.pass = shadow_pass_;
    shadow.layout = pipeline_layout_;
    shadow.vertex = shadow_vertex_shader();
    shadow.fragment = shadow_fragment_shader();
    shadow.normals = false;
    shadow.extent = shadow_extent_;
    // Not flipped: the surface shader samples at uv = ndc.xy·0.5 + 0.5, so NDC y = −1 must land
    // on row 0 of the map, as it does with a positive viewport (and on OpenGL).
    shadow.flip_y = false;
    shadow.colour = false;
    // The surface shader offsets its lookups along the normal and subtracts a bias: no slope bias here.
    shadow.depth_compare = VK_COMPARE_OP_LESS;
    shadow_pipeline_ = create_pipeline(device, shadow);

    create_surface_pipeline();
}

void VulkanRenderer::create_surface_pipeline() {
    PipelineDesc surface;
    surface.pass = surface_pass_;
    surface.layout = pipeline_layout_;
    surface.vertex = surface_vertex_shader();
    surface.fragment = surface_fragment_shader();
    surface.extent = extent_;
    surface.flip_y = true;
    surface.samples = samples_;
    surface.depth_compare = VK_COMPARE_OP_LESS;
    surface_pipeline_ = create_pipeline(context_.device(), surface);
    // The overlay lines: tested against the surface's depth, not written (lines do not hide lines).
    PipelineDesc lines = surface;
    lines.vertex = line_vertex_shader();
    lines.fragment = line_fragment_shader();
    lines.topology = VK_PRIMITIVE_TOPOLOGY_LINE_LIST;
    lines.depth_compare = VK_COMPARE_OP_LESS_OR_EQUAL;
    lines.depth_write = false;
    wireframe_pipeline_ = create_pipeline(context_.device(), lines);
    lines.per_instance = true;
    normals_pipeline_ = create_pipeline(context_.device(), lines);
    PipelineDesc points = lines;
    points.vertex = point_vertex_shader();
    points.per_instance = false;
    points.normals = false;
    points.topology = VK_PRIMITIVE_TOPOLOGY_POINT_LIST;
    points_pipeline_ = create_pipeline(context_.device(), points);
}

void VulkanRenderer::create_descriptors() {
    const VkDevice device = context_.device();
    const std::array<VkDescriptorPoolSize, 3> sizes{{
        {VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1},
        {VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER_DYNAMIC, 1},
        {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1},
    }};
    VkDescriptorPoolCreateInfo pool{};
    pool.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO;
    pool.maxSets = 1;
    pool.poolSizeCount = static_cast<std::uint32_t>(sizes.size());
    pool.pPoolSizes = sizes.data();
    WEFT_VK_CHECK(vkCreateDescriptorPool(device, &pool, nullptr, &descriptor_pool_));
    VkDescriptorSetAllocateInfo alloc{};
    alloc.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO;
    alloc.descriptorPool = descriptor_pool_;
    alloc.descriptorSetCount = 1;
    alloc.pSetLayouts = &set_layout_;
    WEFT_VK_CHECK(vkAllocateDescriptorSets(device, &alloc, &descriptor_set_));

    // The shadow map is fixed; the uniform buffers follow in load(), sized by the scene.
    const VkDescriptorImageInfo image{shadow_sampler_, shadow_map_.view,
                                      VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL};
    VkWriteDescriptorSet write{};
    write.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET;
    write.dstSet = descriptor_set_;
    write.dstBinding = 2;
    write.descriptorCount = 1;
    write.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    write.pImageInfo = &image;
    vkUpdateDescriptorSets(device, 1, &write, 0, nullptr);
}

void VulkanRenderer::load(const RenderScene& scene) {
    // Once the frame in flight (a window's) is done, nothing of the previous scene is in use.
    wait_frame();
    destroy_scene();
    scene_ = scene;
    const VkDevice device = context_.device();

    // Static geometry: every collider's vertices (drawn with a vertex offset each), then the cloth
    // indices and the colliders' indices (4-byte aligned, as the index buffer offset must be).
    std::vector<RenderVertex> vertices;
    std::vector<std::uint32_t> indices(scene_.cloth_indices);
    // A deforming collider's vertices live in their own host-visible buffer instead.
    for (const ColliderDraw& c : scene_.colliders) {
        collider_first_vertex_.push_back(static_cast<std::int32_t>(c.deforms ? c.first_deforming_vertex : vertices.size()));
        collider_first_index_.push_back(static_cast<std::uint32_t>(indices.size()));
        if (!c.deforms) vertices.insert(vertices.end(), c.mesh.vertices.begin(), c.mesh.vertices.end());
        indices.insert(indices.end(), c.mesh.indices.begin(), c.mesh.indices.end());
    }
    edges_first_index_ = static_cast<std::uint32_t>(indices.size());
    indices.insert(indices.end(), scene_.cloth_edges.begin(), scene_.cloth_edges.end());
    if (scene_.deforming_vertices > 0) {
        deforming_ = create_buffer(context_, VkDeviceSize{scene_.deforming_vertices} * sizeof(RenderVertex),
                                   VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, MemoryUse::upload);
        for (const ColliderDraw& c : scene_.colliders)
            if (c.deforms)
                std::memcpy(static_cast<RenderVertex*>(deforming_.mapped) + c.first_deforming_vertex, c.mesh.vertices.data(),
                            c.mesh.vertices.size() * sizeof(RenderVertex));
    }
    const VkDeviceSize vertex_bytes = vertices.size() * sizeof(RenderVertex);
    const VkDeviceSize index_bytes = indices.size() * sizeof(std::uint32_t);
    index_offset_ = vertex_bytes;
    // The vertices, then the frame stamps (weft/backend/interop.h).
    const VkDeviceSize cloth_bytes =
        scene_.cloth_vertices > 0 ? VkDeviceSize{scene_.cloth_vertices} * sizeof(RenderVertex) + kSlotStampBytes : 0;

    if (vertex_bytes + index_bytes > 0)
        static_geometry_ = create_buffer(
            context_, vertex_bytes + index_bytes,
            VK_BUFFER_USAGE_VERTEX_BUFFER_BIT | VK_BUFFER_USAGE_INDEX_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
            MemoryUse::device_local);
    if (cloth_bytes > 0) {
        slots_.resize(1);
        slots_[0].buffer = create_buffer(
            context_, cloth_bytes,
            VK_BUFFER_USAGE_VERTEX_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
            MemoryUse::device_local);
        cloth_staging_ = create_buffer(context_, cloth_bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, MemoryUse::upload);
        stamp_readback_ = create_buffer(context_, kSlotStampBytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, MemoryUse::readback);
    }
    if (vertex_bytes + index_bytes > 0 || cloth_bytes > 0) {
        DeviceBuffer staging;
        if (vertex_bytes + index_bytes > 0) {
            staging = create_buffer(context_, vertex_bytes + index_bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                                    MemoryUse::upload);
            std::memcpy(staging.mapped, vertices.data(), vertex_bytes);
            std::memcpy(static_cast<std::byte*>(staging.mapped) + vertex_bytes, indices.data(), index_bytes);
        }
        try {
            context_.submit_and_wait([&](VkCommandBuffer commands) {
                if (staging.buffer != VK_NULL_HANDLE) {
                    const VkBufferCopy copy{0, 0, vertex_bytes + index_bytes};
                    vkCmdCopyBuffer(commands, staging.buffer, static_geometry_.buffer, 1, &copy);
                }
                // Zeros until the first frame fills it: defined contents for a frame without vertices.
                if (!slots_.empty()) vkCmdFillBuffer(commands, slots_[0].buffer.buffer, 0, VK_WHOLE_SIZE, 0);
                // The fence wait orders the host, not later submissions: make the writes visible to
                // the vertex input of every frame.
                VkMemoryBarrier barrier{};
                barrier.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER;
                barrier.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
                barrier.dstAccessMask = VK_ACCESS_VERTEX_ATTRIBUTE_READ_BIT | VK_ACCESS_INDEX_READ_BIT;
                vkCmdPipelineBarrier(commands, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_VERTEX_INPUT_BIT, 0, 1,
                                     &barrier, 0, nullptr, 0, nullptr);
            });
        } catch (...) {
            destroy_buffer(device, staging);
            throw;
        }
        destroy_buffer(device, staging);
    }

    // Uniforms: offsets of dynamic uniform buffers must be multiples of the device's alignment.
    const VkDeviceSize alignment =
        std::max<VkDeviceSize>(context_.properties().limits.minUniformBufferOffsetAlignment, 16);
    const std::size_t draw_count = scene_.cloths.size() + scene_.colliders.size() + kOverlayDraws;
    draw_base_ = align_up(sizeof(FrameUniforms), alignment);
    draw_stride_ = align_up(sizeof(DrawUniforms), alignment);
    uniforms_ = create_buffer(context_, draw_base_ + std::max<std::size_t>(draw_count, 1) * draw_stride_,
                              VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, MemoryUse::upload);
    const VkDescriptorBufferInfo frame_info{uniforms_.buffer, 0, sizeof(FrameUniforms)};
    const VkDescriptorBufferInfo draw_info{uniforms_.buffer, draw_base_, sizeof(DrawUniforms)};
    std::array<VkWriteDescriptorSet, 2> writes{};
    for (std::size_t w = 0; w < writes.size(); ++w) {
        writes[w].sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET;
        writes[w].dstSet = descriptor_set_;
        writes[w].dstBinding = static_cast<std::uint32_t>(w);
        writes[w].descriptorCount = 1;
        writes[w].descriptorType =
            w == 0 ? VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER : VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER_DYNAMIC;
        writes[w].pBufferInfo = w == 0 ? &frame_info : &draw_info;
    }
    vkUpdateDescriptorSets(device, static_cast<std::uint32_t>(writes.size()), writes.data(), 0, nullptr);
    transfer_ = {"host upload", 0};
    loaded_ = true;
}

bool VulkanRenderer::record_frame(const RenderFrame& frame, bool& external,
                                  const std::function<void(VkCommandBuffer)>& finish) {
    if (!loaded_) throw Error("vulkan renderer: draw() before load()");
    const bool upload = !frame.cloth.empty();
    if (upload && frame.cloth.size() != scene_.cloth_vertices)
        throw Error("vulkan renderer: the frame has " + std::to_string(frame.cloth.size()) +
                    " cloth vertices, the scene's cloth buffer " + std::to_string(scene_.cloth_vertices));
    if ((frame.wait_value != 0 || frame.signal_value != 0) && !exported_)
        throw Error("vulkan renderer: a frame with timeline values, but the cloth buffer is not exported");
    if (frame.cloth_slot < 0 || frame.cloth_slot >= std::max(static_cast<int>(slots_.size()), 1))
        throw Error("vulkan renderer: cloth slot " + std::to_string(frame.cloth_slot) + " does not exist (" +
                    std::to_string(slots_.size()) + (exported_ ? " exported)" : ", none exported)"));
    if (frame.signal_value != 0 && frame.signal_value <= slots_[static_cast<std::size_t>(frame.cloth_slot)].last_signal)
        throw Error("vulkan renderer: timeline signal value " + std::to_string(frame.signal_value) +
                    " is not above the last one signalled on slot " + std::to_string(frame.cloth_slot) + ", " +
                    std::to_string(slots_[static_cast<std::size_t>(frame.cloth_slot)].last_signal));
    check_overlay_points(frame.lines, scene_.cloth_vertices, "vulkan renderer");
    // The previous frame must be done with the mapped buffers and the command buffer.
    wait_frame();
    frame_slot_ = frame.cloth_slot;
    frame_reads_stamps_ = !slots_.empty();

    if (!frame.collider_vertices.empty()) {  // characters playing a clip: their new pose
        if (frame.collider_vertices.size() != scene_.deforming_vertices)
            throw Error("vulkan renderer: the frame has " + std::to_string(frame.collider_vertices.size()) +
                        " deforming collider vertices, the scene " + std::to_string(scene_.deforming_vertices));
        std::memcpy(deforming_.mapped, frame.collider_vertices.data(), frame.collider_vertices.size_bytes());
    }
    if (upload) {
        std::memcpy(cloth_staging_.mapped, frame.cloth.data(), frame.cloth.size_bytes());
        const std::uint64_t stamps[2] = {frame.stamp, frame.stamp};
        std::memcpy(static_cast<std::byte*>(cloth_staging_.mapped) + frame.cloth.size_bytes(), stamps, sizeof stamps);
    }
    const FrameUniforms frame_u = frame_uniforms(scene_, options_.width, options_.height, options_.shadow_map_size);
    const std::vector<DrawUniforms> draws = draw_uniforms(scene_, frame);
    auto* uniform_bytes = static_cast<std::byte*>(uniforms_.mapped);
    std::memcpy(uniform_bytes, &frame_u, sizeof frame_u);
    for (std::size_t i = 0; i < draws.size(); ++i)
        std::memcpy(uniform_bytes + draw_base_ + i * draw_stride_, &draws[i], sizeof(DrawUniforms));
    std::array<DrawUniforms, kOverlayDraws> lines = overlay_uniforms(frame.lines);
    // Points wider than a pixel need the device's largePoints (enabled where it has it).
    const float largest_point = context_.large_points() ? context_.properties().limits.pointSizeRange[1] : 1.0F;
    for (std::size_t i = 2; i < lines.size(); ++i) lines[i].material.w = std::min(lines[i].material.w, largest_point);
    for (std::size_t i = 0; i < lines.size(); ++i)
        std::memcpy(uniform_bytes + draw_base_ + (draws.size() + i) * draw_stride_, &lines[i], sizeof(DrawUniforms));
    frame_lines_ = frame.lines;
    std::size_t point_count = 0;
    for (const OverlayPoints& list : frame.lines.points) point_count += list.vertices.size();
    if (point_count > 0) {
        const VkDeviceSize bytes = VkDeviceSize{point_count} * sizeof(std::uint32_t);
        if (points_.size < bytes) {  // the previous frame is done (wait_frame above): safe to replace
            destroy_buffer(context_.device(), points_);
            points_ = create_buffer(context_, std::max<VkDeviceSize>(bytes, 4096), VK_BUFFER_USAGE_INDEX_BUFFER_BIT,
                                    MemoryUse::upload);
        }
        auto* at = static_cast<std::uint32_t*>(points_.mapped);
        for (const OverlayPoints& list : frame.lines.points) at = std::copy(list.vertices.begin(), list.vertices.end(), at);
    }

    WEFT_VK_CHECK(vkResetCommandBuffer(commands_, 0));
    VkCommandBufferBeginInfo begin{};
    begin.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO;
    begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    // Drawn from what the external writer left in the exported buffer: no upload, and the reads are
    // ordered by the timeline (wait for the writer's value, signal ours when done).
    external = exported_ && !upload;
    // Exported slots belong to the external writer between frames: an upload frame takes them too.
    WEFT_VK_CHECK(vkBeginCommandBuffer(commands_, &begin));
    record(commands_, draws, upload);
    finish(commands_);
    if (frame_reads_stamps_) record_stamp_copy(commands_);
    if (exported_) external_barrier(commands_, frame_slot_, false);
    WEFT_VK_CHECK(vkEndCommandBuffer(commands_));
    return upload;
}

void VulkanRenderer::submit_frame(const RenderFrame& frame, VkSemaphore wait_binary, VkSemaphore signal_binary,
                                  bool with_commands) {
    // Waits: the writer's timeline value (before vertex input), the acquired swapchain image (before
    // the blit). Signals: the timeline, the window's "rendered" semaphore. Binary semaphores take no
    // value, but with a timeline in the submission every semaphore gets an entry (ignored for them).
    std::array<VkSemaphore, 2> waits{}, signals{};
    std::array<VkPipelineStageFlags, 2> wait_stages{};
    std::array<std::uint64_t, 2> wait_values{}, signal_values{};
    std::uint32_t wait_count = 0, signal_count = 0;
    ClothSlot* slot = slots_.empty() ? nullptr : &slots_[static_cast<std::size_t>(frame.cloth_slot)];
    if (frame.wait_value != 0) {
        // Every stage that reads the slot waits: the vertex input of the draws and the transfer
        // that copies its stamps (the acquire barrier chains from the same stages).
        waits[wait_count] = slot->timeline;
        wait_stages[wait_count] = kSlotReadStages;
        wait_values[wait_count++] = frame.wait_value;
    }
    if (wait_binary != VK_NULL_HANDLE) {
        waits[wait_count] = wait_binary;
        wait_stages[wait_count++] = VK_PIPELINE_STAGE_TRANSFER_BIT;
    }
    if (frame.signal_value != 0) {
        signals[signal_count] = slot->timeline;
        signal_values[signal_count++] = frame.signal_value;
    }
    if (signal_binary != VK_NULL_HANDLE) signals[signal_count++] = signal_binary;

    VkSubmitInfo submit{};
    submit.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO;
    submit.commandBufferCount = with_commands ? 1U : 0U;
    submit.pCommandBuffers = with_commands ? &commands_ : nullptr;
    submit.waitSemaphoreCount = wait_count;
    submit.pWaitSemaphores = waits.data();
    submit.pWaitDstStageMask = wait_stages.data();
    submit.signalSemaphoreCount = signal_count;
    submit.pSignalSemaphores = signals.data();
    VkTimelineSemaphoreSubmitInfo timeline{};
    timeline.sType = VK_STRUCTURE_TYPE_TIMELINE_SEMAPHORE_SUBMIT_INFO;
    timeline.waitSemaphoreValueCount = wait_count;
    timeline.pWaitSemaphoreValues = wait_values.data();
    timeline.signalSemaphoreValueCount = signal_count;
    timeline.pSignalSemaphoreValues = signal_values.data();
    if (frame.wait_value != 0 || frame.signal_value != 0) submit.pNext = &timeline;
    WEFT_VK_CHECK(vkQueueSubmit(context_.queue(), 1, &submit, fence_));
    in_flight_ = true;
    if (frame.signal_value != 0) slot->last_signal = frame.signal_value;
}

void VulkanRenderer::record(VkCommandBuffer commands, const std::vector<DrawUniforms>& draws, bool upload) const {
    const VkBuffer cloth = slots_.empty() ? VK_NULL_HANDLE : slots_[static_cast<std::size_t>(frame_slot_)].buffer.buffer;
    if (exported_) external_barrier(commands, frame_slot_, true);
    if (upload) {
        const VkBufferCopy copy{0, 0, cloth_staging_.size};
        vkCmdCopyBuffer(commands, cloth_staging_.buffer, cloth, 1, &copy);
        VkBufferMemoryBarrier barrier{};
        barrier.sType = VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER;
        barrier.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
        barrier.dstAccessMask = VK_ACCESS_VERTEX_ATTRIBUTE_READ_BIT | VK_ACCESS_TRANSFER_READ_BIT;
        barrier.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
        barrier.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
        barrier.buffer = cloth;
        barrier.offset = 0;
        barrier.size = VK_WHOLE_SIZE;
        vkCmdPipelineBarrier(commands, VK_PIPELINE_STAGE_TRANSFER_BIT,
                             VK_PIPELINE_STAGE_VERTEX_INPUT_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 1,
                             &barrier, 0, nullptr);
    }

    VkClearValue depth_clear{};
    depth_clear.depthStencil = {1.0F, 0};
    VkRenderPassBeginInfo pass{};
    pass.sType = VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO;
    pass.renderPass = shadow_pass_;
    pass.framebuffer = shadow_framebuffer_;
    pass.renderArea = {{0, 0}, shadow_extent_};
    pass.clearValueCount = 1;
    pass.pClearValues = &depth_clear;
    vkCmdBeginRenderPass(commands, &pass, VK_SUBPASS_CONTENTS_INLINE);
    vkCmdBindPipeline(commands, VK_PIPELINE_BIND_POINT_GRAPHICS, shadow_pipeline_);
    draw_all(commands, draws, true);
    vkCmdEndRenderPass(commands);

    const glm::vec3& bg = scene_.background;
    std::array<VkClearValue, 3> clears{};
    clears[0].color = {{to_srgb(bg.r), to_srgb(bg.g), to_srgb(bg.b), 1.0F}};
    clears[1].depthStencil = {1.0F, 0};
    clears[2].color = clears[0].color;
    pass.renderPass = surface_pass_;
    pass.framebuffer = surface_framebuffer_;
    pass.renderArea = {{0, 0}, extent_};
    pass.clearValueCount = samples_ != VK_SAMPLE_COUNT_1_BIT ? 3U : 2U;
    pass.pClearValues = clears.data();
    vkCmdBeginRenderPass(commands, &pass, VK_SUBPASS_CONTENTS_INLINE);
    vkCmdBindPipeline(commands, VK_PIPELINE_BIND_POINT_GRAPHICS, surface_pipeline_);
    draw_all(commands, draws, false);
    draw_lines(commands, draws.size());
    vkCmdEndRenderPass(commands);

}

void VulkanRenderer::record_stamp_copy(VkCommandBuffer commands) const {
    // Read after the draws: stamps that match the frame's (first and last) prove the draws saw one
    // whole state, since the writer stamps before its first vertex and after its last.
    const DeviceBuffer& slot = slots_[static_cast<std::size_t>(frame_slot_)].buffer;
    const VkBufferCopy copy{slot.size - kSlotStampBytes, 0, kSlotStampBytes};
    vkCmdCopyBuffer(commands, slot.buffer, stamp_readback_.buffer, 1, &copy);
    to_host_barrier(commands, stamp_readback_.buffer);
}

void VulkanRenderer::draw_all(VkCommandBuffer commands, const std::vector<DrawUniforms>& draws,
                              bool casters_only) const {
    const VkDeviceSize zero = 0;
    if (static_geometry_.buffer != VK_NULL_HANDLE)
        vkCmdBindIndexBuffer(commands, static_geometry_.buffer, index_offset_, VK_INDEX_TYPE_UINT32);
    const std::size_t cloths = scene_.cloths.size();
    VkBuffer bound = VK_NULL_HANDLE;
    for (std::size_t i = 0; i < draws.size(); ++i) {
        // The ground (the only draw with grid lines) receives shadows but casts none: drawing it into
        // the map would only cost fill and invite acne.
        if (casters_only && draws[i].material.x > 0.0F) continue;
        const bool cloth = i < cloths;
        const std::uint32_t count = cloth
                                        ? scene_.cloths[i].index_count
                                        : static_cast<std::uint32_t>(scene_.colliders[i - cloths].mesh.indices.size());
        if (count == 0) continue;
        const VkBuffer vertices = cloth ? slots_[static_cast<std::size_t>(frame_slot_)].buffer.buffer
                                  : scene_.colliders[i - cloths].deforms ? deforming_.buffer
                                                                         : static_geometry_.buffer;
        if (vertices != bound) {
            vkCmdBindVertexBuffers(commands, 0, 1, &vertices, &zero);
            bound = vertices;
        }
        const auto offset = static_cast<std::uint32_t>(i * draw_stride_);
        vkCmdBindDescriptorSets(commands, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline_layout_, 0, 1, &descriptor_set_, 1,
                                &offset);
        if (cloth)
            vkCmdDrawIndexed(commands, count, 1, scene_.cloths[i].first_index, 0, 0);
        else
            vkCmdDrawIndexed(commands, count, 1, collider_first_index_[i - cloths], collider_first_vertex_[i - cloths],
                             0);
    }
}

void VulkanRenderer::draw_lines(VkCommandBuffer commands, std::size_t scene_draws) const {
    if (slots_.empty()) return;  // no cloth
    const VkBuffer cloth = slots_[static_cast<std::size_t>(frame_slot_)].buffer.buffer;
    const VkDeviceSize zero = 0;
    const auto bind = [&](VkPipeline pipeline, std::size_t draw) {
        vkCmdBindPipeline(commands, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline);
        vkCmdBindVertexBuffers(commands, 0, 1, &cloth, &zero);
        const auto offset = static_cast<std::uint32_t>(draw * draw_stride_);
        vkCmdBindDescriptorSets(commands, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline_layout_, 0, 1, &descriptor_set_, 1,
                                &offset);
    };
    if (frame_lines_.wireframe && !scene_.cloth_edges.empty()) {
        bind(wireframe_pipeline_, scene_draws);
        vkCmdBindIndexBuffer(commands, static_geometry_.buffer, index_offset_, VK_INDEX_TYPE_UINT32);
        vkCmdDrawIndexed(commands, static_cast<std::uint32_t>(scene_.cloth_edges.size()), 1, edges_first_index_, 0, 0);
    }
    if (frame_lines_.normal_length > 0.0F && scene_.cloth_vertices > 0) {
        bind(normals_pipeline_, scene_draws + 1);
        vkCmdDraw(commands, 2, scene_.cloth_vertices, 0, 0);  // two ends an instance, one instance a vertex
    }
    std::uint32_t first = 0;
    for (std::size_t p = 0; p < frame_lines_.points.size(); ++p) {
        const auto count = static_cast<std::uint32_t>(frame_lines_.points[p].vertices.size());
        if (count == 0) continue;
        bind(points_pipeline_, scene_draws + 2 + p);
        vkCmdBindIndexBuffer(commands, points_.buffer, 0, VK_INDEX_TYPE_UINT32);
        vkCmdDrawIndexed(commands, count, 1, first, 0, 0);
        first += count;
    }
}

void VulkanRenderer::destroy_scene() noexcept {
    const VkDevice device = context_.device();
    destroy_buffer(device, static_geometry_);
    destroy_buffer(device, deforming_);
    // Exported slots go with their scene: a writer that imported them must import the new ones
    // (export_cloth after the next load()).
    for (ClothSlot& slot : slots_) {
        destroy_buffer(device, slot.buffer);
        if (slot.timeline != VK_NULL_HANDLE) vkDestroySemaphore(device, slot.timeline, nullptr);
    }
    slots_.clear();
    destroy_buffer(device, cloth_staging_);
    destroy_buffer(device, stamp_readback_);
    destroy_buffer(device, uniforms_);
    destroy_buffer(device, points_);
    exported_ = false;
    frame_slot_ = 0;
    frame_reads_stamps_ = false;
    submitted_ = false;
    collider_first_index_.clear();
    collider_first_vertex_.clear();
    loaded_ = false;
}

void VulkanRenderer::destroy() noexcept {
    const VkDevice device = context_.device();
    if (device == VK_NULL_HANDLE) return;
    // A draw that threw between submit and wait may have left work in flight.
    vkQueueWaitIdle(context_.queue());
    destroy_scene();
    if (fence_ != VK_NULL_HANDLE) vkDestroyFence(device, fence_, nullptr);
    if (commands_ != VK_NULL_HANDLE) vkFreeCommandBuffers(device, context_.command_pool(), 1, &commands_);
    if (descriptor_pool_ != VK_NULL_HANDLE) vkDestroyDescriptorPool(device, descriptor_pool_, nullptr);
    destroy_size_targets();
    if (shadow_pipeline_ != VK_NULL_HANDLE) vkDestroyPipeline(device, shadow_pipeline_, nullptr);
    if (pipeline_layout_ != VK_NULL_HANDLE) vkDestroyPipelineLayout(device, pipeline_layout_, nullptr);
    if (set_layout_ != VK_NULL_HANDLE) vkDestroyDescriptorSetLayout(device, set_layout_, nullptr);
    if (shadow_framebuffer_ != VK_NULL_HANDLE) vkDestroyFramebuffer(device, shadow_framebuffer_, nullptr);
    if (surface_pass_ != VK_NULL_HANDLE) vkDestroyRenderPass(device, surface_pass_, nullptr);
    if (overlay_pass_ != VK_NULL_HANDLE) vkDestroyRenderPass(device, overlay_pass_, nullptr);
    overlay_pass_ = VK_NULL_HANDLE;
    if (shadow_pass_ != VK_NULL_HANDLE) vkDestroyRenderPass(device, shadow_pass_, nullptr);
    if (shadow_sampler_ != VK_NULL_HANDLE) vkDestroySampler(device, shadow_sampler_, nullptr);
    destroy_image(device, shadow_map_);
    fence_ = VK_NULL_HANDLE;
    in_flight_ = false;
    commands_ = VK_NULL_HANDLE;
    descriptor_pool_ = VK_NULL_HANDLE;
    descriptor_set_ = VK_NULL_HANDLE;
    surface_pipeline_ = shadow_pipeline_ = VK_NULL_HANDLE;
    pipeline_layout_ = VK_NULL_HANDLE;
    set_layout_ = VK_NULL_HANDLE;
    surface_framebuffer_ = shadow_framebuffer_ = VK_NULL_HANDLE;
    surface_pass_ = shadow_pass_ = VK_NULL_HANDLE;
    shadow_sampler_ = VK_NULL_HANDLE;
}

std::unique_ptr<Renderer> create_vulkan_renderer(const RendererOptions& options) {
    return std::make_unique<VulkanRenderer>(options);
}

}  // namespace weft::render::detail
