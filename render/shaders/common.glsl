// Shared by every Weft shader, compiled twice: by glslc for Vulkan (VULKAN defined) and, with its
// includes inlined at build time, by the OpenGL 4.5 driver of the EGL capture path. Both paths use
// the same matrices (depth 0..1: glClipControl on GL) and the same std140 blocks, so the two render
// the same image up to rasterisation rounding.
#ifdef VULKAN
#define WEFT_BLOCK(b) layout(set = 0, binding = b, std140)
#define WEFT_SAMPLER(b) layout(set = 0, binding = b)
#define WEFT_VERTEX_INDEX gl_VertexIndex
#else
#define WEFT_BLOCK(b) layout(binding = b, std140)
#define WEFT_SAMPLER(b) layout(binding = b)
#define WEFT_VERTEX_INDEX gl_VertexID
#endif

// Per frame (render/src/frame_uniforms.h, FrameUniforms).
WEFT_BLOCK(0) uniform Frame {
    mat4 view_projection;   // world → clip (camera)
    mat4 light_projection;  // world → clip of the shadow map (orthographic, along the key light)
    vec4 camera_position;   // xyz, m; w: shadow map texel size in texture coordinates (1 / size)
    vec4 light_direction;   // xyz: unit vector the light travels along
    vec4 light_colour;      // rgb, w: ambient strength
    vec4 sky_colour;        // rgb: hemisphere fill from above; w: shadow map texel size in the world, m
    vec4 ground_colour;     // rgb: hemisphere fill from below; w: depth bias of the shadow test
} frame;

// Per draw (DrawUniforms).
WEFT_BLOCK(1) uniform Draw {
    mat4 model;          // local → world
    vec4 front_colour;   // rgb, linear; the side the triangle's normal points to
    vec4 back_colour;    // rgb, linear
    vec4 material;       // x: grid spacing (m) for the ground, 0 otherwise; y: roughness; z: 1 for cloth;
                         // w: overlay normals' length (m), line.vert; a point's size (pixels), point.vert
} draw;
