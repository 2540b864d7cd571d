// Render passes and graphics pipelines (see vulkan_pipelines.h).
#include "vulkan/vulkan_pipelines.h"

#include <array>
#include <cstddef>

#include "weft/render/render_scene.h"

#include "vulkan/vulkan_check.h"

namespace weft::render::detail {
namespace {

VkShaderModule create_module(VkDevice device, const ShaderCode& code) {
    VkShaderModuleCreateInfo info{};
    info.sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO;
    info.codeSize = code.spirv.size_bytes();
    info.pCode = code.spirv.data();
    VkShaderModule module = VK_NULL_HANDLE;
    WEFT_VK_CHECK(vkCreateShaderModule(device, &info, nullptr, &module));
    return module;
}

VkRenderPass create_pass(VkDevice device, const VkRenderPassCreateInfo& info) {
    VkRenderPass pass = VK_NULL_HANDLE;
    WEFT_VK_CHECK(vkCreateRenderPass(device, &info, nullptr, &pass));
    return pass;
}

}  // namespace

VkRenderPass create_shadow_pass(VkDevice device, VkFormat depth) {
    VkAttachmentDescription attachment{};
    attachment.format = depth;
    attachment.samples = VK_SAMPLE_COUNT_1_BIT;
    attachment.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    attachment.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    attachment.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
    attachment.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    attachment.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;  // cleared every frame
    attachment.finalLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL;
    const VkAttachmentReference depth_ref{0, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
    VkSubpassDescription subpass{};
    subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
    subpass.pDepthStencilAttachment = &depth_ref;

    constexpr VkPipelineStageFlags tests =
        VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
    std::array<VkSubpassDependency, 2> dependencies{};
    // The previous frame's surface pass sampled the map: finish reading before clearing it.
    dependencies[0] = {VK_SUBPASS_EXTERNAL,
                       0,
                       VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT,
                       tests,
                       0,
                       VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
                       0};
    // This frame's surface pass samples it: depth writes visible to its fragment shaders.
    dependencies[1] = {0,
                       VK_SUBPASS_EXTERNAL,
                       tests,
                       VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT,
                       VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
                       VK_ACCESS_SHADER_READ_BIT,
                       0};

    VkRenderPassCreateInfo info{};
    info.sType = VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO;
    info.attachmentCount = 1;
    info.pAttachments = &attachment;
    info.subpassCount = 1;
    info.pSubpasses = &subpass;
    info.dependencyCount = static_cast<std::uint32_t>(dependencies.size());
    info.pDependencies = dependencies.data();
    return create_pass(device, info);
}

VkRenderPass create_surface_pass(VkDevice device, VkFormat colour, VkFormat depth, VkSampleCountFlagBits samples) {
    const bool resolve = samples != VK_SAMPLE_COUNT_1_BIT;
    std::array<VkAttachmentDescription, 3> attachments{};
    VkAttachmentDescription& c = attachments[0];
    c.format = colour;
    c.samples = samples;
    c.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    // Multisampled colour is only needed until it is resolved.
    c.storeOp = resolve ? VK_ATTACHMENT_STORE_OP_DONT_CARE : VK_ATTACHMENT_STORE_OP_STORE;
    c.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
    c.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    c.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    c.finalLayout = resolve ? VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL : VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
    VkAttachmentDescription& d = attachments[1];
    d.format = depth;
    d.samples = samples;
    d.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    d.storeOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    d.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
    d.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    d.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    d.finalLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
    VkAttachmentDescription& r = attachments[2];
    r.format = colour;
    r.samples = VK_SAMPLE_COUNT_1_BIT;
    r.loadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;  // every pixel is resolved
    r.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    r.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
    r.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    r.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    r.finalLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;

    const VkAttachmentReference colour_ref{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    const VkAttachmentReference depth_ref{1, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
    const VkAttachmentReference resolve_ref{2, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    VkSubpassDescription subpass{};
    subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
    subpass.colorAttachmentCount = 1;
    subpass.pColorAttachments = &colour_ref;
    subpass.pResolveAttachments = resolve ? &resolve_ref : nullptr;
    subpass.pDepthStencilAttachment = &depth_ref;

    constexpr VkPipelineStageFlags writes = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT |
                                            VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT |
                                            VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
    std::array<VkSubpassDependency, 2> dependencies{};
    // The previous frame wrote these attachments and copied the single-sample colour to the host:
    // both finish before this frame writes them again.
    dependencies[0] = {VK_SUBPASS_EXTERNAL,
                       0,
                       VK_PIPELINE_STAGE_TRANSFER_BIT | writes,
                       writes,
                       VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
                       VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT |
                           VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
                       0};
    // The copy to the host reads the resolved (or single-sample) colour.
    dependencies[1] = {0,
                       VK_SUBPASS_EXTERNAL,
                       VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
                       VK_PIPELINE_STAGE_TRANSFER_BIT,
                       VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT,
                       VK_ACCESS_TRANSFER_READ_BIT,
                       0};

    VkRenderPassCreateInfo info{};
    info.sType = VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO;
    info.attachmentCount = resolve ? 3U : 2U;
    info.pAttachments = attachments.data();
    info.subpassCount = 1;
    info.pSubpasses = &subpass;
    info.dependencyCount = static_cast<std::uint32_t>(dependencies.size());
    info.pDependencies = dependencies.data();
    return create_pass(device, info);
}

VkRenderPass create_overlay_pass(VkDevice device, VkFormat colour) {
    VkAttachmentDescription c{};
    c.format = colour;
    c.samples = VK_SAMPLE_COUNT_1_BIT;
    c.loadOp = VK_ATTACHMENT_LOAD_OP_LOAD;  // drawn over the scene's picture
    c.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    c.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
    c.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    c.initialLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;  // where the surface pass left it
    c.finalLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;    // where the blit and the read-back expect it
    const VkAttachmentReference colour_ref{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    VkSubpassDescription subpass{};
    subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
    subpass.colorAttachmentCount = 1;
    subpass.pColorAttachments = &colour_ref;

    std::array<VkSubpassDependency, 2> dependencies{};
    // The surface pass wrote (resolved) the picture; a previous read-back may still be reading it.
    dependencies[0] = {VK_SUBPASS_EXTERNAL,
                       0,
                       VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                       VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
                       VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT,
                       VK_ACCESS_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT,
                       0};
    // The blit to the swapchain image and the copy to the host read the result.
    dependencies[1] = {0,
                       VK_SUBPASS_EXTERNAL,
                       VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
                       VK_PIPELINE_STAGE_TRANSFER_BIT,
                       VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT,
                       VK_ACCESS_TRANSFER_READ_BIT,
                       0};
    VkRenderPassCreateInfo info{};
    info.sType = VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO;
    info.attachmentCount = 1;
    info.pAttachments = &c;
    info.subpassCount = 1;
    info.pSubpasses = &subpass;
    info.dependencyCount = static_cast<std::uint32_t>(dependencies.size());
    info.pDependencies = dependencies.data();
    return create_pass(device, info);
}

VkPipeline create_pipeline(VkDevice device, const PipelineDesc& desc) {
    std::array<VkShaderModule, 2> modules{};
    VkPipeline pipeline = VK_NULL_HANDLE;
    try {
        modules[0] = create_module(device, desc.vertex);
        modules[1] = create_module(device, desc.fragment);
        std::array<VkPipelineShaderStageCreateInfo, 2> stages{};
        for (std::size_t s = 0; s < stages.size(); ++s) {
            stages[s].sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
            stages[s].stage = s == 0 ? VK_SHADER_STAGE_VERTEX_BIT : VK_SHADER_STAGE_FRAGMENT_BIT;
            stages[s].module = modules[s];
            stages[s].pName = "main";
        }

        // One binding for every draw: the cloth buffer and the colliders' buffer share the layout.
        const VkVertexInputBindingDescription binding{
            0, sizeof(RenderVertex), desc.per_instance ? VK_VERTEX_INPUT_RATE_INSTANCE : VK_VERTEX_INPUT_RATE_VERTEX};
        const std::array<VkVertexInputAttributeDescription, 2> attributes{{
            {0, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(RenderVertex, position)},
            {1, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(RenderVertex, normal)},
        }};
        VkPipelineVertexInputStateCreateInfo vertex_input{};
        vertex_input.sType = VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO;
        vertex_input.vertexBindingDescriptionCount = 1;
        vertex_input.pVertexBindingDescriptions = &binding;
        vertex_input.vertexAttributeDescriptionCount = desc.normals ? 2U : 1U;
        vertex_input.pVertexAttributeDescriptions = attributes.data();

        VkPipelineInputAssemblyStateCreateInfo assembly{};
        assembly.sType = VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO;
        assembly.topology = desc.topology;

        const auto w = static_cast<float>(desc.extent.width), h = static_cast<float>(desc.extent.height);
        const VkViewport viewport =
            desc.flip_y ? VkViewport{0.0F, h, w, -h, 0.0F, 1.0F} : VkViewport{0.0F, 0.0F, w, h, 0.0F, 1.0F};
        const VkRect2D scissor{{0, 0}, desc.extent};
        VkPipelineViewportStateCreateInfo viewport_state{};
        viewport_state.sType = VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO;
        viewport_state.viewportCount = 1;
        viewport_state.pViewports = &viewport;
        viewport_state.scissorCount = 1;
        viewport_state.pScissors = &scissor;

        VkPipelineRasterizationStateCreateInfo raster{};
        raster.sType = VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO;
        raster.polygonMode = VK_POLYGON_MODE_FILL;
        // Cloth is two-sided (the fragment shader colours the back by gl_FrontFacing), and the shadow
        // map needs both sides of it.
        raster.cullMode = VK_CULL_MODE_NONE;
        // Vulkan's winding is taken in framebuffer coordinates (y down). With the flipped viewport
        // the picture is upright, so a triangle counter-clockwise on screen is counter-clockwise in
        // OpenGL's window coordinates too: the same triangles face front on both APIs.
        raster.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
        raster.lineWidth = 1.0F;

        VkPipelineMultisampleStateCreateInfo multisample{};
        multisample.sType = VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO;
        multisample.rasterizationSamples = desc.samples;

        VkPipelineDepthStencilStateCreateInfo depth{};
        depth.sType = VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO;
        depth.depthTestEnable = VK_TRUE;
        depth.depthWriteEnable = desc.depth_write ? VK_TRUE : VK_FALSE;
        depth.depthCompareOp = desc.depth_compare;

        VkPipelineColorBlendAttachmentState blend_attachment{};
        blend_attachment.colorWriteMask =
            VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT | VK_COLOR_COMPONENT_B_BIT | VK_COLOR_COMPONENT_A_BIT;
        VkPipelineColorBlendStateCreateInfo blend{};
        blend.sType = VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO;
        blend.attachmentCount = desc.colour ? 1U : 0U;
        blend.pAttachments = &blend_attachment;

        VkGraphicsPipelineCreateInfo info{};
        info.sType = VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO;
        info.stageCount = static_cast<std::uint32_t>(stages.size());
        info.pStages = stages.data();
        info.pVertexInputState = &vertex_input;
        info.pInputAssemblyState = &assembly;
        info.pViewportState = &viewport_state;
        info.pRasterizationState = &raster;
        info.pMultisampleState = &multisample;
        info.pDepthStencilState = &depth;
        info.pColorBlendState = &blend;
        info.layout = desc.layout;
        info.renderPass = desc.pass;
        info.subpass = 0;
        WEFT_VK_CHECK(vkCreateGraphicsPipelines(device, VK_NULL_HANDLE, 1, &info, nullptr, &pipeline));
    } catch (...) {
        for (VkShaderModule m : modules)
            if (m != VK_NULL_HANDLE) vkDestroyShaderModule(device, m, nullptr);
        throw;
    }
    // A pipeline keeps what it needs of its modules.
    for (VkShaderModule m : modules) vkDestroyShaderModule(device, m, nullptr);
    return pipeline;
}

}  // namespace weft::render::detail
