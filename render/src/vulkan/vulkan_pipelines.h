#pragma once
// The two render passes (shadow map, surface) and the graphics pipelines that draw into them, from
// the SPIR-V of render/shaders/.
#include <vulkan/vulkan.h>

#include "shaders.h"

namespace weft::render::detail {

/// The depth-only pass of the shadow map: cleared, stored, and left in
/// VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL for the surface pass to sample (its outgoing
/// dependency makes the depth writes visible to fragment shaders).
[[nodiscard]] VkRenderPass create_shadow_pass(VkDevice device, VkFormat depth);

/// The surface pass: attachment 0 colour and 1 depth with `samples` per pixel, and with more than
/// one sample attachment 2, the single-sample resolve target. The single-sample colour (attachment 0
/// or 2) ends in VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, ready to be copied to the host.
[[nodiscard]] VkRenderPass create_surface_pass(VkDevice device, VkFormat colour, VkFormat depth,
                                               VkSampleCountFlagBits samples);

/// The overlay pass of the window (window_overlay.h): one single-sample `colour` attachment, the
/// resolved picture, loaded as the surface pass left it (VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL),
/// drawn over and left in the same layout for the blit to the swapchain and the copy to the host.
[[nodiscard]] VkRenderPass create_overlay_pass(VkDevice device, VkFormat colour);

struct PipelineDesc {
    VkRenderPass pass = VK_NULL_HANDLE;
    VkPipelineLayout layout = VK_NULL_HANDLE;
    ShaderCode vertex, fragment;
    /// Location 1 (the normal) read from the 24-byte vertex as well as location 0 (the position).
    bool normals = true;
    VkExtent2D extent{};
    /// A viewport of negative height: clip y up, as in OpenGL, and rows top to bottom in the image.
    bool flip_y = false;
    VkSampleCountFlagBits samples = VK_SAMPLE_COUNT_1_BIT;
    VkCompareOp depth_compare = VK_COMPARE_OP_LESS;
    bool colour = true;  ///< writes a colour attachment (the shadow pass has none)
    VkPrimitiveTopology topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
    /// The vertex buffer advances once an instance, not once a vertex (the overlay's normals).
    bool per_instance = false;
    bool depth_write = true;
};

/// A pipeline over RenderVertex (stride 24; triangles unless `topology` says otherwise), no culling,
/// depth test on (and write unless `depth_write` is off).
[[nodiscard]] VkPipeline create_pipeline(VkDevice device, const PipelineDesc& desc);

}  // namespace weft::render::detail
