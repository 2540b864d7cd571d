#version 450
// Overlay lines from the cloth buffer itself (OverlayLines): the wireframe (an indexed line list
// over the cloth vertices, draw.material.w = 0) and the normals (two vertices an instance, one
// instance a cloth vertex: the second end draw.material.w metres along the normal).
#include "common.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;

void main() {
    float along = (WEFT_VERTEX_INDEX % 2) == 1 ? draw.material.w : 0.0;
    float length_n = length(in_normal);
    vec3 p = in_position + (length_n > 0.0 ? along / length_n : 0.0) * in_normal;
    gl_Position = frame.view_projection * vec4(p, 1.0);
    // Lines lie on the surface they outline: drawn a little towards the camera so that the depth
    // test hides what is behind the cloth, not the lines on it (clip depth is 0..1 on both APIs).
    gl_Position.z -= 2.0e-4 * gl_Position.w;
}
