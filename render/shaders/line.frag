#version 450
// Overlay lines: one flat colour a draw (draw.front_colour, linear RGB), written as sRGB as the
// surface shader writes its colours.
#include "common.glsl"

layout(location = 0) out vec4 out_colour;

void main() {
    vec3 c = clamp(draw.front_colour.rgb, 0.0, 1.0);
    out_colour = vec4(mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c)), 1.0);
}
