#!/usr/bin/env bash
# Installs the Debian 12 packages that building and testing Weft needs, and only the missing ones.
# Idempotent: with everything installed it only checks, and changes nothing.
#   as root:   apt-get update (only when something is missing) + apt-get install
#   otherwise: prints the exact `sudo apt-get install ...` line and exits 1
# Set WEFT_SKIP_DEPS=1 to skip the check (e.g. on a machine managed some other way).
set -euo pipefail

# One group per part of the build, all listed in PACKAGE_GROUPS below.
BUILD_PACKAGES=(cmake ninja-build g++ pkg-config)
RUNTIME_PACKAGES=(libtbb-dev libtomlplusplus-dev libglm-dev)
ASSETS_PACKAGES=(libassimp-dev)
# `weft run --cache FILE.glb` writes glTF through TinyGLTF.
CACHE_PACKAGES=(libtinygltf-dev)
TEST_PACKAGES=(libgtest-dev libgmock-dev libbenchmark-dev python3)
# The libFuzzer targets (fuzz/, `make fuzz-smoke` inside `make test`): clang and its fuzzer and
# sanitizer runtimes.
FUZZ_PACKAGES=(clang libclang-rt-14-dev)
# The multi-GPU partition benchmark compares its cut with METIS (bench/partition_bench.cpp).
BENCH_PACKAGES=(libmetis-dev)
# The renderer (WEFT_RENDER): Vulkan loader, headers, glslc, lavapipe and the validation layers;
# EGL and OpenGL through GLVND with Mesa's llvmpipe; libpng for the captured frames; GLFW for the
# window of `weft view`, and Xvfb (xvfb-run needs xauth) to test it without a display.
RENDER_PACKAGES=(libvulkan-dev glslc mesa-vulkan-drivers vulkan-validationlayers libegl-dev libgl-dev libegl-mesa0
                 libgl1-mesa-dri libpng-dev libglfw3-dev xvfb xauth)
# The editor (WEFT_EDITOR, `weft edit`): Dear ImGui with its GLFW and Vulkan backends in one static
# library (its font atlas needs stb); GLFW and Vulkan come with the renderer's group.
EDITOR_PACKAGES=(libimgui-dev libstb-dev)
PACKAGE_GROUPS=(BUILD_PACKAGES RUNTIME_PACKAGES ASSETS_PACKAGES CACHE_PACKAGES TEST_PACKAGES FUZZ_PACKAGES BENCH_PACKAGES RENDER_PACKAGES EDITOR_PACKAGES)

if [[ "${WEFT_SKIP_DEPS:-0}" == "1" ]]; then
    echo "deps: skipped (WEFT_SKIP_DEPS=1)"
    exit 0
fi

if ! command -v dpkg-query >/dev/null 2>&1; then
    echo "deps: dpkg-query not found: this script knows Debian 12 packages only." >&2
    echo "deps: install the equivalents of these yourself, then set WEFT_SKIP_DEPS=1:" >&2
    for group in "${PACKAGE_GROUPS[@]}"; do
        declare -n list="$group"
        echo "  ${list[*]}" >&2
    done
    exit 1
fi

wanted=()
for group in "${PACKAGE_GROUPS[@]}"; do
    declare -n list="$group"
    wanted+=("${list[@]}")
done

missing=()
for package in "${wanted[@]}"; do
    status="$(dpkg-query -W -f='${Status}' "$package" 2>/dev/null || true)"
    if [[ "$status" != "install ok installed" ]]; then
        missing+=("$package")
    fi
done

if [[ ${#missing[@]} -eq 0 ]]; then
    echo "deps: all ${#wanted[@]} packages installed"
    exit 0
fi

echo "deps: missing ${#missing[@]} of ${#wanted[@]} packages: ${missing[*]}"
if [[ "$(id -u)" -ne 0 ]]; then
    echo "deps: not root; install them with:" >&2
    echo "  sudo apt-get update && sudo apt-get install -y --no-install-recommends ${missing[*]}" >&2
    exit 1
fi

export DEBIAN_FRONTEND=noninteractive
apt-get update
apt-get install -y --no-install-recommends "${missing[@]}"
echo "deps: installed ${missing[*]}"
