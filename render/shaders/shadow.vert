#version 450
// Depth from the key light: the shadow map's only pass (position only: the normal is not bound).
#include "common.glsl"

layout(location = 0) in vec3 in_position;

void main() {
    gl_Position = frame.light_projection * (draw.model * vec4(in_position, 1.0));
}
