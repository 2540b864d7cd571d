#version 450
// Cloth, colliders and ground: position and normal per vertex (the solver's output layout, 24 bytes).
#include "common.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;

layout(location = 0) out vec3 world_position;
layout(location = 1) out vec3 world_normal;

void main() {
    vec4 p = draw.model * vec4(in_position, 1.0);
    world_position = p.xyz;
    // Rigid transforms only (colliders): the rotation part carries the normal.
    world_normal = mat3(draw.model) * in_normal;
    gl_Position = frame.view_projection * p;
}
