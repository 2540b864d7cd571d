#version 450
// Overlay points from the cloth buffer itself (OverlayLines::points): an indexed point list over the
// cloth vertices, each a square draw.material.w pixels wide (the editor's contact and pin marks).
#include "common.glsl"

layout(location = 0) in vec3 in_position;

void main() {
    gl_Position = frame.view_projection * vec4(in_position, 1.0);
    // As the lines: a little towards the camera, so that the cloth a mark sits on does not hide it
    // and whatever stands in front of the cloth does.
    gl_Position.z -= 4.0e-4 * gl_Position.w;
    gl_PointSize = draw.material.w;
}
