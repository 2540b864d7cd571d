#include "cli_args.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <optional>
#include <sstream>
#include <system_error>
#include <vector>

#include "weft/error.h"
#include "weft/presets.h"

#include "scene_keys_help.h"

namespace weft::cli {

std::string_view extension(MeshFormat format) { return format == MeshFormat::Obj ? ".obj" : ".ply"; }

namespace {

constexpr std::string_view kCommands[] = {"run", "bench", "view", "edit", "info", "help"};
/// What `weft help TOPIC` takes: a command, or the list of scene keys.
constexpr std::string_view kHelpTopics[] = {"run", "bench", "view", "edit", "info", "help", kSceneKeysTopic};

struct FlagSpec {
    std::string_view name;  ///< with the leading dashes
    bool takes_value;
};

// Appended piecewise: GCC 12 warns (-Wrestrict, a known false positive) on "literal" + string.
std::string quoted(std::string_view text) {
    std::string out;
    out.reserve(text.size() + 2);
    out.append(1, '\'').append(text).append(1, '\'');
    return out;
}

/// Levenshtein distance, for "did you mean" hints on misspelt flags and commands.
std::size_t edit_distance(std::string_view a, std::string_view b) {
    std::vector<std::size_t> row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
        std::size_t diagonal = row[0];
        row[0] = i;
        for (std::size_t j = 1; j <= b.size(); ++j) {
            const std::size_t up = row[j];
            row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
            diagonal = up;
        }
    }
    return row[b.size()];
}

std::string closest(std::string_view given, std::span<const std::string_view> candidates) {
    std::string_view best;
    std::size_t best_distance = 3;  // suggest only close matches
    for (const std::string_view candidate : candidates) {
        const std::size_t d = edit_distance(given, candidate);
        if (d < best_distance) {
            best_distance = d;
            best = candidate;
        }
    }
    return best.empty() ? std::string{} : " (did you mean " + quoted(best) + "?)";
}

/// Walks the arguments of one subcommand: flags (`--name value`, `--name=value`), `-h`/`--help`,
/// `--` (everything after is positional) and positionals.
class FlagParser {
public:
    FlagParser(std::string_view command, std::span<const std::string_view> args, std::span<const FlagSpec> flags)
        : command_(command), args_(args), flags_(flags) {}

    /// Calls on_flag(name, value) for each flag (value empty for switches) and returns the
    /// positionals. Returns std::nullopt when help was asked for.
    template <typename OnFlag>
    std::optional<std::vector<std::string_view>> parse(OnFlag&& on_flag) {
        std::vector<std::string_view> positionals;
        bool only_positionals = false;
        for (std::size_t i = 0; i < args_.size(); ++i) {
            const std::string_view arg = args_[i];
            if (only_positionals || arg.size() < 2 || arg[0] != '-') {
                positionals.push_back(arg);
                continue;
            }
            if (arg == "--") {
                only_positionals = true;
                continue;
            }
            if (arg == "-h" || arg == "--help") return std::nullopt;
            std::string_view name = arg;
            std::optional<std::string_view> inline_value;
            if (const auto eq = arg.find('='); eq != std::string_view::npos && arg.starts_with("--")) {
                name = arg.substr(0, eq);
                inline_value = arg.substr(eq + 1);
            }
            const FlagSpec* spec = find(name);
            if (spec == nullptr) {
                std::vector<std::string_view> names{"--help"};
                for (const FlagSpec& f : flags_) names.push_back(f.name);
                throw UsageError(command_, "unknown option " + quoted(name) + closest(name, names));
            }
            if (!spec->takes_value) {
                if (inline_value) throw UsageError(command_, std::string(name) + " takes no value");
                on_flag(name, std::string_view{});
                continue;
            }
            std::string_view value;
            if (inline_value) {
                value = *inline_value;
            } else if (i + 1 < args_.size() && !args_[i + 1].starts_with("--")) {
                value = args_[++i];
            } else {
                throw UsageError(command_, std::string(name) + " needs a value");
            }
            if (value.empty()) throw UsageError(command_, std::string(name) + " needs a non-empty value");
            on_flag(name, value);
        }
        return positionals;
    }

private:
    const FlagSpec* find(std::string_view name) const {
        for (const FlagSpec& f : flags_) {
            if (f.name == name) return &f;
        }
        return nullptr;
    }
    std::string_view command_;
    std::span<const std::string_view> args_;
    std::span<const FlagSpec> flags_;
};

std::string parse_override(std::string_view command, std::string_view value) {
    const auto eq = value.find('=');
    if (eq == std::string_view::npos || eq == 0 || eq + 1 == value.size()) {
        throw UsageError(command, "--set expects key=value (e.g. --set solver.substeps=4), got " + quoted(value));
    }
    return std::string(value);
}

/// Flags that `run` and `bench` share. Returns false if `name` is not one of them.
bool apply_simulation_flag(std::string_view command, SimulationOptions& sim, std::string_view name,
                           std::string_view value) {
    if (name == "--backend") {
        sim.backend = std::string(value);
    } else if (name == "--threads") {
        sim.threads = parse_int(command, name, value, 0, 4096);
    } else if (name == "--gpus") {
        sim.gpus = parse_int(command, name, value, 1, 64);
    } else if (name == "--device-memory-limit") {
        sim.device_memory_limit_mib = parse_int(command, name, value, 1, 64 * 1024 * 1024);
    } else if (name == "--host-wait") {
        try {
            sim.host_wait = parse_host_wait(value);
        } catch (const Error&) {
            throw UsageError(command, "--host-wait expects auto, spin, yield or block, got " + quoted(value));
        }
    } else if (name == "--set") {
        sim.overrides.push_back(parse_override(command, value));
    } else if (name == "--preset") {
        // Its keys first, so that every --set (before it on the line or after) wins over it.
        std::vector<std::string> preset;
        try {
            preset = solver_preset_overrides(value);
        } catch (const Error& e) {
            throw UsageError(command, std::string("--preset: ") + e.what());
        }
        sim.overrides.erase(sim.overrides.begin(), sim.overrides.begin() + static_cast<std::ptrdiff_t>(sim.preset_keys));
        sim.overrides.insert(sim.overrides.begin(), preset.begin(), preset.end());
        sim.preset_keys = preset.size();
    } else {
        return false;
    }
    return true;
}

constexpr FlagSpec kRunFlags[] = {{"--backend", true}, {"--threads", true}, {"--host-wait", true}, {"--gpus", true}, {"--device-memory-limit", true}, {"--set", true}, {"--preset", true},   {"--frames", true},
                                  {"--out", true},     {"--format", true},  {"--stats", true}, {"--quiet", false},
                                  {"--check", false},  {"--capture", true}, {"--size", true}, {"--cache", true},
                                  {"--checkpoint", true}, {"--checkpoint-every", true}, {"--resume", true}};

constexpr FlagSpec kViewFlags[] = {{"--backend", true}, {"--threads", true}, {"--host-wait", true}, {"--gpus", true},    {"--set", true}, {"--preset", true},
                                   {"--frames", true},  {"--screenshot", true}, {"--size", true},
                                   {"--time-scale", true}, {"--validation", false}};

constexpr FlagSpec kEditFlags[] = {{"--backend", true},    {"--threads", true}, {"--host-wait", true}, {"--gpus", true},    {"--set", true}, {"--preset", true},
                                   {"--frames", true},     {"--screenshot", true}, {"--size", true},
                                   {"--time-scale", true}, {"--validation", false}, {"--script", true},
                                   {"--ui-scale", true}};

/// `--screenshot FILE.png`.
std::filesystem::path parse_png(std::string_view cmd, std::string_view name, std::string_view value) {
    const std::filesystem::path path(value);
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (ext != ".png" || path.filename() == ".png")
        throw UsageError(cmd, std::string(name) + " expects a .png file name, got " + quoted(value));
    return path;
}

/// `--size WIDTHxHEIGHT`, each side in [16, 8192] pixels.
void parse_size(std::string_view cmd, std::string_view name, std::string_view value, int& width, int& height) {
    const auto x = value.find('x');
    if (x == std::string_view::npos)
        throw UsageError(cmd, std::string(name) + " expects WIDTHxHEIGHT in pixels, e.g. 1280x720, got " + quoted(value));
    width = parse_int(cmd, name, value.substr(0, x), 16, 8192);
    height = parse_int(cmd, name, value.substr(x + 1), 16, 8192);
}

constexpr FlagSpec kBenchFlags[] = {{"--backend", true}, {"--threads", true}, {"--host-wait", true}, {"--gpus", true}, {"--device-memory-limit", true}, {"--set", true}, {"--preset", true},
                                    {"--frames", true},  {"--warmup", true},  {"--json", true}};

Invocation help_for(std::string_view topic) {
    Invocation inv;
    inv.command = Invocation::Command::Help;
    inv.help_topic = std::string(topic);
    return inv;
}

Invocation parse_run(std::span<const std::string_view> args) {
    constexpr std::string_view cmd = "run";
    Invocation inv;
    inv.command = Invocation::Command::Run;
    RunOptions& run = inv.run;
    bool explicit_format = false;
    const auto positionals = FlagParser(cmd, args, kRunFlags).parse([&](std::string_view name, std::string_view value) {
        if (apply_simulation_flag(cmd, run.sim, name, value)) return;
        if (name == "--frames") {
            run.frames = parse_int(cmd, name, value, 0, 100'000'000);
        } else if (name == "--out") {
            run.out_dir = std::filesystem::path(value);
        } else if (name == "--format") {
            explicit_format = true;
            if (value == "ply")
                run.format = MeshFormat::Ply;
            else if (value == "obj")
                run.format = MeshFormat::Obj;
            else
                throw UsageError(cmd, "--format expects ply or obj, got " + quoted(value));
        } else if (name == "--stats") {
            run.stats_file = std::filesystem::path(value);
        } else if (name == "--quiet") {
            run.quiet = true;
        } else if (name == "--check") {
            run.check = true;
        } else if (name == "--capture") {
            if (value != "egl" && value != "vulkan" && value != "none")
                throw UsageError(cmd, "--capture expects egl, vulkan or none, got " + quoted(value));
            run.capture = std::string(value);
        } else if (name == "--size") {
            parse_size(cmd, name, value, run.capture_width, run.capture_height);
        } else if (name == "--checkpoint") {
            run.checkpoint_dir = std::filesystem::path(value);
        } else if (name == "--checkpoint-every") {
            run.checkpoint_every = parse_int(cmd, name, value, 1, 100'000'000);
        } else if (name == "--resume") {
            run.resume_file = std::filesystem::path(value);
        } else if (name == "--cache") {
            const std::filesystem::path path(value);
            std::string ext = path.extension().string();
            std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
            if ((ext != ".pc2" && ext != ".glb") || path.stem().empty())
                throw UsageError(cmd, "--cache expects a .pc2 (PC2 point cache) or .glb (glTF binary) file name, got " +
                                          quoted(value));
            run.cache_file = path;
        }
    });
    if (!positionals) return help_for(cmd);
    if (run.checkpoint_every > 0 && run.checkpoint_dir.empty())
        throw UsageError(cmd, "--checkpoint-every needs --checkpoint DIR for the files");
    if (run.capture != "none" && run.out_dir.empty())
        throw UsageError(cmd, "--capture " + run.capture + " needs --out DIR for the pictures");
    // Captured runs write pictures; meshes only when a mesh format was asked for as well.
    if (run.capture != "none") run.meshes = explicit_format;
    if (positionals->empty()) throw UsageError(cmd, "missing SCENE (a scene file or a name from assets/scenes)");
    if (positionals->size() > 1) {
        throw UsageError(cmd, "unexpected argument " + quoted((*positionals)[1]) +
                                  " (run takes one scene; 'weft bench' takes several)");
    }
    run.scene = std::string(positionals->front());
    return inv;
}

Invocation parse_bench(std::span<const std::string_view> args) {
    constexpr std::string_view cmd = "bench";
    Invocation inv;
    inv.command = Invocation::Command::Bench;
    BenchOptions& bench = inv.bench;
    const auto positionals =
        FlagParser(cmd, args, kBenchFlags).parse([&](std::string_view name, std::string_view value) {
            if (name == "--gpus") {  // a list here: each scene on each count
                bench.gpu_counts.clear();
                std::string_view rest = value;
                for (;;) {
                    const auto comma = rest.find(',');
                    bench.gpu_counts.push_back(parse_int(cmd, name, rest.substr(0, comma), 1, 64));
                    if (comma == std::string_view::npos) break;
                    rest = rest.substr(comma + 1);
                }
                return;
            }
            if (apply_simulation_flag(cmd, bench.sim, name, value)) return;
            if (name == "--frames") {
                bench.frames = parse_int(cmd, name, value, 1, 100'000'000);
            } else if (name == "--warmup") {
                bench.warmup = parse_int(cmd, name, value, 0, 100'000'000);
            } else if (name == "--json") {
                bench.json_file = std::filesystem::path(value);
            }
        });
    if (!positionals) return help_for(cmd);
    if (positionals->empty()) throw UsageError(cmd, "missing SCENE (one or more scene files or names)");
    for (const std::string_view scene : *positionals) bench.scenes.emplace_back(scene);
    return inv;
}

Invocation parse_view(std::span<const std::string_view> args) {
    constexpr std::string_view cmd = "view";
    Invocation inv;
    inv.command = Invocation::Command::View;
    ViewOptions& view = inv.view;
    const auto positionals = FlagParser(cmd, args, kViewFlags).parse([&](std::string_view name, std::string_view value) {
        if (apply_simulation_flag(cmd, view.sim, name, value)) return;
        if (name == "--frames") {
            view.frames = parse_int(cmd, name, value, 1, 100'000'000);
        } else if (name == "--screenshot") {
            const std::filesystem::path path(value);
            std::string ext = path.extension().string();
            std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
            if (ext != ".png" || path.filename() == ".png")
                throw UsageError(cmd, "--screenshot expects a .png file name, got " + quoted(value));
            view.screenshot = path;
        } else if (name == "--size") {
            parse_size(cmd, name, value, view.width, view.height);
        } else if (name == "--time-scale") {
            view.time_scale = parse_double(cmd, name, value, 0.01, 100.0);
        } else if (name == "--validation") {
            view.validation = true;
        }
    });
    if (!positionals) return help_for(cmd);
    if (positionals->empty()) throw UsageError(cmd, "missing SCENE (a scene file or a name from assets/scenes)");
    if (positionals->size() > 1)
        throw UsageError(cmd, "unexpected argument " + quoted((*positionals)[1]) + " (view shows one scene)");
    view.scene = std::string(positionals->front());
    return inv;
}

Invocation parse_edit(std::span<const std::string_view> args) {
    constexpr std::string_view cmd = "edit";
    Invocation inv;
    inv.command = Invocation::Command::Edit;
    EditOptions& edit = inv.edit;
    const auto positionals = FlagParser(cmd, args, kEditFlags).parse([&](std::string_view name, std::string_view value) {
        if (apply_simulation_flag(cmd, edit.sim, name, value)) return;
        if (name == "--frames") {
            edit.frames = parse_int(cmd, name, value, 1, 100'000'000);
        } else if (name == "--screenshot") {
            edit.screenshot = parse_png(cmd, name, value);
        } else if (name == "--script") {
            edit.script = std::filesystem::path(value);
        } else if (name == "--size") {
            parse_size(cmd, name, value, edit.width, edit.height);
        } else if (name == "--time-scale") {
            edit.time_scale = parse_double(cmd, name, value, 0.01, 100.0);
        } else if (name == "--validation") {
            edit.validation = true;
        } else if (name == "--ui-scale") {
            edit.ui_scale = static_cast<float>(parse_double(cmd, name, value, 0.5, 4.0));
        }
    });
    if (!positionals) return help_for(cmd);
    if (positionals->size() > 1)
        throw UsageError(cmd, "unexpected argument " + quoted((*positionals)[1]) + " (edit opens one scene)");
    if (!positionals->empty()) edit.scene = std::string(positionals->front());
    return inv;
}

Invocation parse_info(std::span<const std::string_view> args) {
    constexpr std::string_view cmd = "info";
    const auto positionals = FlagParser(cmd, args, {}).parse([](std::string_view, std::string_view) {});
    if (!positionals) return help_for(cmd);
    if (!positionals->empty()) throw UsageError(cmd, "unexpected argument " + quoted(positionals->front()));
    Invocation inv;
    inv.command = Invocation::Command::Info;
    return inv;
}

}  // namespace

int parse_int(std::string_view command, std::string_view flag, std::string_view text, int min, int max) {
    long long value = 0;
    const char* first = text.data();
    const char* last = text.data() + text.size();
    const auto [end, ec] = std::from_chars(first, last, value);
    if (text.empty() || ec == std::errc::invalid_argument || end != last) {
        throw UsageError(std::string(command), std::string(flag) + " expects an integer, got " + quoted(text));
    }
    if (ec == std::errc::result_out_of_range || value < min || value > max) {
        throw UsageError(std::string(command), std::string(flag) + " must be in [" + std::to_string(min) + ", " +
                                                   std::to_string(max) + "], got " + quoted(text));
    }
    return static_cast<int>(value);
}

double parse_double(std::string_view command, std::string_view flag, std::string_view text, double min,
                    double max) {
    double value = 0.0;
    const char* first = text.data();
    const char* last = text.data() + text.size();
    const auto [end, ec] = std::from_chars(first, last, value);
    if (text.empty() || ec == std::errc::invalid_argument || end != last || !std::isfinite(value)) {
        throw UsageError(std::string(command), std::string(flag) + " expects a number, got " + quoted(text));
    }
    if (ec == std::errc::result_out_of_range || value < min || value > max) {
        std::ostringstream range;
        range << std::string(flag) << " must be in [" << min << ", " << max << "], got " << quoted(text);
        throw UsageError(std::string(command), range.str());
    }
    return value;
}

Invocation parse_command_line(std::span<const std::string_view> args) {
    if (args.empty()) throw UsageError("", "no command given");
    const std::string_view first = args.front();
    const auto rest = args.subspan(1);
    if (first == "-h" || first == "--help") return help_for("");
    if (first == "--version" || first == "version") {
        if (!rest.empty()) throw UsageError("", "unexpected argument " + quoted(rest.front()) + " after --version");
        Invocation inv;
        inv.command = Invocation::Command::Version;
        return inv;
    }
    if (first == "help") {
        if (rest.empty()) return help_for("");
        const std::string_view topic = rest.front();
        if (std::find(std::begin(kHelpTopics), std::end(kHelpTopics), topic) == std::end(kHelpTopics)) {
            throw UsageError("", "no help for unknown command " + quoted(topic) + closest(topic, kHelpTopics));
        }
        // `weft help scene-keys --markdown`: the tables of docs/scene-format.md.
        const bool markdown = topic == kSceneKeysTopic && rest.size() == 2 && rest[1] == "--markdown";
        if (rest.size() > 1 && !markdown)
            throw UsageError("", "unexpected argument " + quoted(rest[1]) + " after 'help " + std::string(topic) + "'");
        Invocation inv = help_for(topic);
        inv.help_markdown = markdown;
        return inv;
    }
    if (first == "run") return parse_run(rest);
    if (first == "bench") return parse_bench(rest);
    if (first == "view") return parse_view(rest);
    if (first == "edit") return parse_edit(rest);
    if (first == "info") return parse_info(rest);
    if (first.starts_with('-')) {
        constexpr std::string_view kTopFlags[] = {"--help", "--version"};
        throw UsageError("", "unknown option " + quoted(first) + closest(first, kTopFlags) +
                                 "; options go after the command, e.g. 'weft run SCENE --frames 10'");
    }
    throw UsageError("", "unknown command " + quoted(first) + closest(first, kCommands));
}

}  // namespace weft::cli
