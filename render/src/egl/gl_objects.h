#pragma once
// OpenGL 4.5 core entry points and owning handles for the objects of the EGL renderer.
//
// GLVND's libOpenGL exports every core entry point, so the prototypes are declared directly (no
// loader library): the EGL renderer needs nothing beyond core 4.5.
#ifndef GL_GLEXT_PROTOTYPES
#define GL_GLEXT_PROTOTYPES 1
#endif
#include <GL/glcorearb.h>

#include <string>
#include <string_view>
#include <utility>

namespace weft::render::detail::gl {

/// One OpenGL object name, deleted by `Delete` when dropped. GL names belong to a context: the
/// owner makes that context current before its handles go (EglRenderer's destructor does).
template <void (*Delete)(GLuint)>
class Handle {
public:
    Handle() = default;
    explicit Handle(GLuint name) : name_(name) {}
    ~Handle() { reset(); }
    Handle(const Handle&) = delete;
    Handle& operator=(const Handle&) = delete;
    Handle(Handle&& other) noexcept : name_(std::exchange(other.name_, 0)) {}
    Handle& operator=(Handle&& other) noexcept {
        if (this != &other) {
            reset();
            name_ = std::exchange(other.name_, 0);
        }
        return *this;
    }

    [[nodiscard]] GLuint get() const { return name_; }
    [[nodiscard]] explicit operator bool() const { return name_ != 0; }
    void reset() {
        if (name_ != 0) Delete(std::exchange(name_, 0));
    }

private:
    GLuint name_ = 0;
};

inline void delete_buffer(GLuint name) { glDeleteBuffers(1, &name); }
inline void delete_vertex_array(GLuint name) { glDeleteVertexArrays(1, &name); }
inline void delete_texture(GLuint name) { glDeleteTextures(1, &name); }
inline void delete_renderbuffer(GLuint name) { glDeleteRenderbuffers(1, &name); }
inline void delete_framebuffer(GLuint name) { glDeleteFramebuffers(1, &name); }
inline void delete_shader(GLuint name) { glDeleteShader(name); }
inline void delete_program(GLuint name) { glDeleteProgram(name); }

using Buffer = Handle<delete_buffer>;
using VertexArray = Handle<delete_vertex_array>;
using Texture = Handle<delete_texture>;
using Renderbuffer = Handle<delete_renderbuffer>;
using Framebuffer = Handle<delete_framebuffer>;
using Shader = Handle<delete_shader>;
using Program = Handle<delete_program>;

inline Buffer create_buffer() {
    GLuint name = 0;
    glCreateBuffers(1, &name);
    return Buffer(name);
}
inline VertexArray create_vertex_array() {
    GLuint name = 0;
    glCreateVertexArrays(1, &name);
    return VertexArray(name);
}
inline Texture create_texture(GLenum target) {
    GLuint name = 0;
    glCreateTextures(target, 1, &name);
    return Texture(name);
}
inline Renderbuffer create_renderbuffer() {
    GLuint name = 0;
    glCreateRenderbuffers(1, &name);
    return Renderbuffer(name);
}
inline Framebuffer create_framebuffer() {
    GLuint name = 0;
    glCreateFramebuffers(1, &name);
    return Framebuffer(name);
}

/// Compiles `vertex_glsl` and `fragment_glsl` and links them into a program. Throws `weft::Error`
/// with the driver's log, naming the shader (`name`.vert, `name`.frag or the `name` program), when
/// compiling or linking fails.
[[nodiscard]] Program link_program(std::string_view name, const char* vertex_glsl, const char* fragment_glsl);

/// Throws `weft::Error` naming `where` and every pending OpenGL error (GL_INVALID_OPERATION, ...);
/// does nothing when there is none.
void check_errors(std::string_view where);

/// "GL_INVALID_ENUM" for an error code, the number in hex for one it does not know.
[[nodiscard]] std::string error_name(GLenum code);

}  // namespace weft::render::detail::gl
