#version 450
// Depth only; a fragment stage is kept because OpenGL core needs one.
void main() {}
