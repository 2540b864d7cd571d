#version 450
// Lighting that keeps folds readable: a key light with a shadow map (3×3 PCF), a sky/ground
// hemisphere fill, a soft wrap on cloth (light bleeding round a fold instead of a hard terminator)
// and a little specular sheen. Cloth is two-sided: the back face shows its own colour, lit with the
// flipped normal.
#include "common.glsl"

layout(location = 0) in vec3 world_position;
layout(location = 1) in vec3 world_normal;

layout(location = 0) out vec4 out_colour;

WEFT_SAMPLER(2) uniform sampler2DShadow shadow_map;

float shadow_factor(vec3 p, vec3 n) {
    // Offset along the normal by a texel: no acne on gently curved cloth.
    vec4 c = frame.light_projection * vec4(p + n * frame.sky_colour.w * 1.5, 1.0);
    vec3 s = c.xyz / c.w;
    vec2 uv = s.xy * 0.5 + 0.5;
    if (uv.x <= 0.0 || uv.x >= 1.0 || uv.y <= 0.0 || uv.y >= 1.0 || s.z >= 1.0) return 1.0;
    float texel = frame.camera_position.w;
    float lit = 0.0;
    for (int y = -1; y <= 1; ++y)
        for (int x = -1; x <= 1; ++x)
            lit += texture(shadow_map, vec3(uv + vec2(x, y) * texel, s.z - frame.ground_colour.w));
    return lit / 9.0;
}

vec3 to_srgb(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}

void main() {
    vec3 n = normalize(world_normal);
    vec3 base = draw.front_colour.rgb;
    if (!gl_FrontFacing) {
        n = -n;
        base = draw.back_colour.rgb;
    }
    if (draw.material.x > 0.0) {
        // Ground grid: thin lines every `spacing` metres, fading with distance.
        vec2 g = abs(fract(world_position.xz / draw.material.x + 0.5) - 0.5) * draw.material.x;
        vec2 width = fwidth(world_position.xz) * 1.2;
        float line = 1.0 - min(smoothstep(vec2(0.0), width, g).x, smoothstep(vec2(0.0), width, g).y);
        base = mix(base, draw.back_colour.rgb, line * 0.8);
    }
    vec3 l = -frame.light_direction.xyz;
    vec3 v = normalize(frame.camera_position.xyz - world_position);
    float ndl = dot(n, l);
    float wrap = draw.material.z > 0.5 ? 0.3 : 0.0;
    float diffuse = max((ndl + wrap) / (1.0 + wrap), 0.0);
    float shadow = shadow_factor(world_position, n);
    vec3 h = normalize(l + v);
    float shininess = mix(64.0, 8.0, draw.material.y);
    float specular = ndl > 0.0 ? pow(max(dot(n, h), 0.0), shininess) * (1.0 - draw.material.y) * 0.25 : 0.0;
    float up = n.y * 0.5 + 0.5;
    vec3 fill = mix(frame.ground_colour.rgb, frame.sky_colour.rgb, up) * frame.light_colour.w;
    vec3 colour = base * (fill + frame.light_colour.rgb * diffuse * shadow) + frame.light_colour.rgb * specular * shadow;
    out_colour = vec4(to_srgb(colour), 1.0);
}
