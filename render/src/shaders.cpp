// The build-time shader outputs as arrays and strings (see shaders.h).
#include "shaders.h"

namespace weft::render::detail {
namespace {

const std::uint32_t kSurfaceVertSpirv[] =
#include "surface.vert.spv.inc"
    ;
const std::uint32_t kSurfaceFragSpirv[] =
#include "surface.frag.spv.inc"
    ;
const std::uint32_t kShadowVertSpirv[] =
#include "shadow.vert.spv.inc"
    ;
const std::uint32_t kShadowFragSpirv[] =
#include "shadow.frag.spv.inc"
    ;
const std::uint32_t kLineVertSpirv[] =
#include "line.vert.spv.inc"
    ;
const std::uint32_t kLineFragSpirv[] =
#include "line.frag.spv.inc"
    ;
const std::uint32_t kPointVertSpirv[] =
#include "point.vert.spv.inc"
    ;
const char* const kPointVertGlsl =
#include "point.vert.glsl.inc"
    ;
const char* const kLineVertGlsl =
#include "line.vert.glsl.inc"
    ;
const char* const kLineFragGlsl =
#include "line.frag.glsl.inc"
    ;
const char* const kSurfaceVertGlsl =
#include "surface.vert.glsl.inc"
    ;
const char* const kSurfaceFragGlsl =
#include "surface.frag.glsl.inc"
    ;
const char* const kShadowVertGlsl =
#include "shadow.vert.glsl.inc"
    ;
const char* const kShadowFragGlsl =
#include "shadow.frag.glsl.inc"
    ;

}  // namespace

ShaderCode surface_vertex_shader() { return {kSurfaceVertSpirv, kSurfaceVertGlsl}; }
ShaderCode surface_fragment_shader() { return {kSurfaceFragSpirv, kSurfaceFragGlsl}; }
ShaderCode shadow_vertex_shader() { return {kShadowVertSpirv, kShadowVertGlsl}; }
ShaderCode shadow_fragment_shader() { return {kShadowFragSpirv, kShadowFragGlsl}; }
ShaderCode line_vertex_shader() { return {kLineVertSpirv, kLineVertGlsl}; }
ShaderCode line_fragment_shader() { return {kLineFragSpirv, kLineFragGlsl}; }
ShaderCode point_vertex_shader() { return {kPointVertSpirv, kPointVertGlsl}; }

}  // namespace weft::render::detail
