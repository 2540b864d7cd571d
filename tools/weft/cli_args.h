#pragma once
/// @file
/// Command-line parsing for `weft`: turns argv into an `Invocation` or throws `UsageError` with a
/// one-line message that names the offending flag or value. Parsing never touches the file system
/// or the runtime, so every case is unit-tested (tests/cli/cli_args_test.cpp).

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "weft/backend_options.h"

namespace weft::cli {

/// Exit codes of the `weft` command.
inline constexpr int kExitOk = 0;
inline constexpr int kExitError = 1;          ///< bad scene, unreadable mesh, unwritable output
inline constexpr int kExitUsage = 2;          ///< wrong flags or values
inline constexpr int kExitNonFinite = 3;      ///< the simulation produced NaN or Inf, or a solve ran away, at least once
inline constexpr int kExitCollision = 4;      ///< a collision stayed unresolved, or --check found intersections
inline constexpr int kExitStepFailed = 5;     ///< a step failed (a device fault, out of device memory): the frames before it are written
inline constexpr int kExitInterrupted = 130;  ///< Ctrl-C or SIGTERM (128 + SIGINT, as shells report Ctrl-C); stats still written

/// A command-line mistake. `what()` is one line without the program name; `command` names the
/// subcommand whose help the user should read ("" for the top level).
class UsageError : public std::runtime_error {
public:
    UsageError(std::string_view command, const std::string& message) : std::runtime_error(message), command_(command) {}
    [[nodiscard]] const std::string& command() const { return command_; }

private:
    std::string command_;
};

enum class MeshFormat : std::uint8_t { Ply, Obj };
[[nodiscard]] std::string_view extension(MeshFormat format);

/// What `run` and `bench` share: where the simulation runs and how the scene is overridden.
struct SimulationOptions {
    std::string backend = "auto";  ///< "auto": cuda when a GPU is present, else cpu
    int threads = 0;                     ///< 0 = all cores
    HostWait host_wait = HostWait::automatic;  ///< how the host waits for a GPU backend (--host-wait)
    int gpus = 0;                        ///< GPUs one world is split across (--gpus; cuda backend); 0: the scene's solver.gpus
    int device_memory_limit_mib = 0;     ///< --device-memory-limit: MiB the backend may hold per GPU; 0 = the device's
    std::vector<std::string> overrides;  ///< "dotted.key=value": a --preset's first, then --set in command-line order
    std::size_t preset_keys = 0;         ///< the first overrides are --preset's (a later --preset replaces them)
};

struct RunOptions {
    std::string scene;  ///< a path or a bare scene name
    SimulationOptions sim;
    std::optional<int> frames;      ///< empty: the scene's `frames`
    std::filesystem::path out_dir;  ///< empty: write no meshes
    MeshFormat format = MeshFormat::Ply;
    std::filesystem::path stats_file;  ///< empty: write no stats JSON
    bool quiet = false;
    bool check = false;  ///< exact intersection check after every frame (collision.check)
    std::string capture = "none";  ///< "egl", "vulkan" or "none": render every frame to DIR/frame_NNNN.png
    int capture_width = 1280;      ///< pixels
    int capture_height = 720;      ///< pixels
    bool meshes = true;            ///< with --out, write meshes (--capture alone writes only pictures)
    std::filesystem::path checkpoint_dir;  ///< `--checkpoint DIR`: DIR/frame_NNNNNN.state at the end (and every N frames); empty: none
    int checkpoint_every = 0;              ///< `--checkpoint-every N`: also every N frames (0: at the end only)
    std::filesystem::path resume_file;     ///< `--resume FILE`: start from a checkpoint of this scene
    std::filesystem::path cache_file;  ///< `--cache FILE.pc2|.glb`: PC2 point caches or a glTF binary (cache_writer.h); empty: none
};

struct BenchOptions {
    std::vector<std::string> scenes;
    SimulationOptions sim;
    std::filesystem::path json_file;  ///< empty: print the table only
    int warmup = 10;
    int frames = 100;
    std::vector<int> gpu_counts{0};  ///< --gpus 1,2: every scene on each count of GPUs (0: the scene's solver.gpus)
};

/// `weft view`: the scene simulated live in a window (builds with the renderer only).
struct ViewOptions {
    std::string scene;  ///< a path or a bare scene name
    SimulationOptions sim;
    std::optional<int> frames;         ///< exit after this many displayed frames; empty: when closed
    std::filesystem::path screenshot;  ///< empty: none; else the last displayed frame as PNG at exit
    int width = 1280;                  ///< window size, screen pixels
    int height = 720;
    double time_scale = 1.0;           ///< simulated seconds per wall second, [0.01, 100]
    bool validation = false;           ///< Vulkan validation layer, messages to stderr
};

/// `weft edit`: the scene in the window with the ImGui editor's panels (builds with the editor only).
struct EditOptions {
    std::string scene = "flag";  ///< a path or a bare scene name
    SimulationOptions sim;
    std::optional<int> frames;         ///< exit after this many displayed frames; empty: when closed
    std::filesystem::path screenshot;  ///< empty: none; else the last displayed frame (with the panels) at exit
    std::filesystem::path script;      ///< empty: interactive; else the script to run (docs/editor.md)
    int width = 1280;                  ///< window size, screen pixels
    int height = 720;
    double time_scale = 1.0;           ///< simulated seconds per wall second, [0.01, 100]
    bool validation = false;           ///< Vulkan validation layer; a message makes the run fail
    float ui_scale = 0.0F;             ///< the panels' size, [0.5, 4]; 0: the monitor's content scale
};

struct Invocation {
    enum class Command : std::uint8_t { Help, Version, Run, Bench, Info, View, Edit };
    Command command = Command::Help;
    std::string help_topic;  ///< Help: "" for the overview, a subcommand name, or "scene-keys"
    bool help_markdown = false;  ///< Help on scene-keys: the Markdown tables of docs/scene-format.md
    RunOptions run;
    BenchOptions bench;
    ViewOptions view;
    EditOptions edit;
};

/// Parses the arguments after the program name. Throws `UsageError`.
[[nodiscard]] Invocation parse_command_line(std::span<const std::string_view> args);

/// Parses a whole decimal integer in [min, max] for `flag`; throws `UsageError` (for `command`)
/// naming the flag and the text otherwise.
[[nodiscard]] int parse_int(std::string_view command, std::string_view flag, std::string_view text, int min, int max);
/// The same for a finite decimal number in [min, max].
[[nodiscard]] double parse_double(std::string_view command, std::string_view flag, std::string_view text, double min,
                                  double max);

}  // namespace weft::cli
