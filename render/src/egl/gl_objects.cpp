// Shader compilation and error checks of the EGL renderer (see gl_objects.h).
#include "egl/gl_objects.h"

#include <cstdio>
#include <vector>

#include "weft/error.h"

namespace weft::render::detail::gl {
namespace {

std::string shader_log(GLuint shader) {
    GLint length = 0;
    glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
    std::vector<char> log(static_cast<std::size_t>(length > 0 ? length : 1), '\0');
    glGetShaderInfoLog(shader, static_cast<GLsizei>(log.size()), nullptr, log.data());
    return log.data();
}

std::string program_log(GLuint program) {
    GLint length = 0;
    glGetProgramiv(program, GL_INFO_LOG_LENGTH, &length);
    std::vector<char> log(static_cast<std::size_t>(length > 0 ? length : 1), '\0');
    glGetProgramInfoLog(program, static_cast<GLsizei>(log.size()), nullptr, log.data());
    return log.data();
}

Shader compile(GLenum stage, const std::string& name, const char* glsl) {
    if (glsl == nullptr) throw Error("egl renderer: no GLSL text for shader " + name);
    Shader shader(glCreateShader(stage));
    if (!shader) throw Error("egl renderer: glCreateShader failed for shader " + name);
    glShaderSource(shader.get(), 1, &glsl, nullptr);
    glCompileShader(shader.get());
    GLint ok = GL_FALSE;
    glGetShaderiv(shader.get(), GL_COMPILE_STATUS, &ok);
    if (ok != GL_TRUE) throw Error("egl renderer: compiling shader " + name + " failed:\n" + shader_log(shader.get()));
    return shader;
}

}  // namespace

Program link_program(std::string_view name, const char* vertex_glsl, const char* fragment_glsl) {
    const std::string base(name);
    const Shader vertex = compile(GL_VERTEX_SHADER, base + ".vert", vertex_glsl);
    const Shader fragment = compile(GL_FRAGMENT_SHADER, base + ".frag", fragment_glsl);
    Program program(glCreateProgram());
    if (!program) throw Error("egl renderer: glCreateProgram failed for the " + base + " program");
    glAttachShader(program.get(), vertex.get());
    glAttachShader(program.get(), fragment.get());
    glLinkProgram(program.get());
    // The program keeps its compiled code: the shader objects can go once it is linked.
    glDetachShader(program.get(), vertex.get());
    glDetachShader(program.get(), fragment.get());
    GLint ok = GL_FALSE;
    glGetProgramiv(program.get(), GL_LINK_STATUS, &ok);
    if (ok != GL_TRUE)
        throw Error("egl renderer: linking the " + base + " program (" + base + ".vert + " + base + ".frag) failed:\n" +
                    program_log(program.get()));
    return program;
}

std::string error_name(GLenum code) {
    switch (code) {
        case GL_INVALID_ENUM: return "GL_INVALID_ENUM";
        case GL_INVALID_VALUE: return "GL_INVALID_VALUE";
        case GL_INVALID_OPERATION: return "GL_INVALID_OPERATION";
        case GL_INVALID_FRAMEBUFFER_OPERATION: return "GL_INVALID_FRAMEBUFFER_OPERATION";
        case GL_OUT_OF_MEMORY: return "GL_OUT_OF_MEMORY";
        case GL_STACK_UNDERFLOW: return "GL_STACK_UNDERFLOW";
        case GL_STACK_OVERFLOW: return "GL_STACK_OVERFLOW";
        case GL_CONTEXT_LOST: return "GL_CONTEXT_LOST";
        default: {
            char hex[16];
            std::snprintf(hex, sizeof hex, "0x%04X", code);
            return hex;
        }
    }
}

void check_errors(std::string_view where) {
    std::string errors;
    // A lost context may report GL_CONTEXT_LOST on every call: read a bounded number of errors.
    for (int k = 0; k < 16; ++k) {
        const GLenum code = glGetError();
        if (code == GL_NO_ERROR) break;
        errors += (errors.empty() ? "" : ", ") + error_name(code);
    }
    if (!errors.empty()) throw Error("egl renderer: OpenGL error " + errors + " in " + std::string(where));
}

}  // namespace weft::render::detail::gl
