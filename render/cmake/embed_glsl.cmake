# Writes INPUT as a C++ raw string literal into OUTPUT, with every `#include "file"` line replaced by
# that file's text (from INCLUDE_DIR): the OpenGL driver compiles the same sources glslc compiles
# for Vulkan, and GLSL has no #include of its own. The text is handled as one string (never as a
# CMake list: GLSL is full of semicolons), so it arrives byte for byte.
#   cmake -DINPUT=surface.frag -DINCLUDE_DIR=shaders -DOUTPUT=surface.frag.glsl.inc -P embed_glsl.cmake
file(READ "${INPUT}" text)
string(REGEX MATCHALL "#include \"[^\"]+\"" includes "${text}")
foreach(directive IN LISTS includes)
  string(REGEX REPLACE "#include \"([^\"]+)\"" "\\1" name "${directive}")
  file(READ "${INCLUDE_DIR}/${name}" included)
  string(REPLACE "${directive}" "${included}" text "${text}")
endforeach()
file(WRITE "${OUTPUT}.tmp" "R\"glsl(${text})glsl\"\n")
file(COPY_FILE "${OUTPUT}.tmp" "${OUTPUT}" ONLY_IF_DIFFERENT)
