// Argument parsing of the `weft` command: every mistake is a UsageError whose one-line message
// names the flag or value at fault.
#include <gtest/gtest.h>

#include <algorithm>
#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

#include "weft/error.h"
#include "weft/presets.h"

#include "cli_args.h"
#include "usage.h"

namespace weft::cli {
namespace {

Invocation parse(std::initializer_list<std::string_view> args) {
    const std::vector<std::string_view> v(args);
    return parse_command_line(v);
}

/// The UsageError message for `args`, or "<no error>".
std::string error_of(std::initializer_list<std::string_view> args) {
    try {
        (void)parse(args);
    } catch (const UsageError& e) {
        EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << "message must be one line";
        return e.what();
    }
    return "<no error>";
}

std::string command_of(std::initializer_list<std::string_view> args) {
    try {
        (void)parse(args);
    } catch (const UsageError& e) {
        return e.command();
    }
    return "<no error>";
}

TEST(CliArgs, RunDefaults) {
    const Invocation inv = parse({"run", "flag"});
    ASSERT_EQ(inv.command, Invocation::Command::Run);
    EXPECT_EQ(inv.run.scene, "flag");
    EXPECT_EQ(inv.run.sim.backend, "auto");
    EXPECT_EQ(inv.run.sim.threads, 0);
    EXPECT_FALSE(inv.run.frames.has_value());
    EXPECT_TRUE(inv.run.out_dir.empty());
    EXPECT_TRUE(inv.run.stats_file.empty());
    EXPECT_EQ(inv.run.format, MeshFormat::Ply);
    EXPECT_FALSE(inv.run.quiet);
}

TEST(CliArgs, CaptureNeedsOutAndKnowsItsRenderers) {
    const Invocation inv = parse({"run", "flag", "--capture", "egl", "--out", "pics", "--size", "640x360"});
    EXPECT_EQ(inv.run.capture, "egl");
    EXPECT_EQ(inv.run.capture_width, 640);
    EXPECT_EQ(inv.run.capture_height, 360);
    EXPECT_FALSE(inv.run.meshes) << "--capture alone writes pictures, not meshes";
    EXPECT_TRUE(parse({"run", "flag", "--capture=vulkan", "--out", "p", "--format", "ply"}).run.meshes);
    EXPECT_TRUE(parse({"run", "flag", "--out", "p"}).run.meshes);
    EXPECT_EQ(parse({"run", "flag"}).run.capture, "none");
    EXPECT_EQ(error_of({"run", "flag", "--capture", "egl"}), "--capture egl needs --out DIR for the pictures");
    EXPECT_EQ(error_of({"run", "flag", "--capture", "opengl", "--out", "p"}),
              "--capture expects egl, vulkan or none, got 'opengl'");
    EXPECT_EQ(error_of({"run", "flag", "--size", "640", "--out", "p"}),
              "--size expects WIDTHxHEIGHT in pixels, e.g. 1280x720, got '640'");
    EXPECT_NE(error_of({"run", "flag", "--size", "8x8"}).find("--size"), std::string::npos);
    EXPECT_NE(error_of({"run", "flag", "--size", "640xabc"}).find("--size"), std::string::npos);
}

TEST(CliArgs, RunAllFlags) {
    const Invocation inv =
        parse({"run", "--frames", "12", "scenes/x.toml", "--out=out/x", "--format", "obj", "--stats", "s.json", "--set",
               "solver.substeps=4", "--set=wind.velocity=[1, 0, 0]", "--threads", "3", "--backend", "cpu", "--quiet"});
    ASSERT_EQ(inv.command, Invocation::Command::Run);
    EXPECT_EQ(inv.run.scene, "scenes/x.toml");
    EXPECT_EQ(inv.run.frames, 12);
    EXPECT_EQ(inv.run.out_dir, "out/x");
    EXPECT_EQ(inv.run.format, MeshFormat::Obj);
    EXPECT_EQ(inv.run.stats_file, "s.json");
    ASSERT_EQ(inv.run.sim.overrides.size(), 2u);
    EXPECT_EQ(inv.run.sim.overrides[0], "solver.substeps=4");
    EXPECT_EQ(inv.run.sim.overrides[1], "wind.velocity=[1, 0, 0]");  // only the first '=' splits
    EXPECT_EQ(inv.run.sim.threads, 3);
    EXPECT_TRUE(inv.run.quiet);
}

TEST(CliArgs, HostWait) {
    EXPECT_EQ(parse({"run", "flag"}).run.sim.host_wait, HostWait::automatic);
    EXPECT_EQ(parse({"run", "flag", "--host-wait", "block"}).run.sim.host_wait, HostWait::block);
    EXPECT_EQ(parse({"bench", "flag", "--host-wait=spin"}).bench.sim.host_wait, HostWait::spin);
    EXPECT_EQ(parse({"view", "flag", "--host-wait", "yield"}).view.sim.host_wait, HostWait::yield);
    EXPECT_EQ(error_of({"run", "flag", "--host-wait", "sleep"}),
              "--host-wait expects auto, spin, yield or block, got 'sleep'");
    // The names round-trip, and an unknown one is named in the error.
    for (const HostWait w : {HostWait::automatic, HostWait::spin, HostWait::yield, HostWait::block})
        EXPECT_EQ(parse_host_wait(host_wait_name(w)), w);
    try {
        (void)parse_host_wait("busy");
        ADD_FAILURE() << "parse_host_wait accepted 'busy'";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("'busy'"), std::string::npos) << e.what();
    }
}

TEST(CliArgs, Gpus) {
    EXPECT_EQ(parse({"run", "flag"}).run.sim.gpus, 0);  // the scene's solver.gpus
    EXPECT_EQ(parse({"run", "flag", "--gpus", "2"}).run.sim.gpus, 2);
    EXPECT_EQ(parse({"view", "flag", "--gpus=4"}).view.sim.gpus, 4);
    EXPECT_EQ(parse({"bench", "flag"}).bench.gpu_counts, (std::vector<int>{0}));
    EXPECT_EQ(parse({"bench", "flag", "--gpus", "1,2"}).bench.gpu_counts, (std::vector<int>{1, 2}));
    EXPECT_NE(error_of({"run", "flag", "--gpus", "0"}).find("--gpus"), std::string::npos);
    EXPECT_NE(error_of({"bench", "flag", "--gpus", "1,,2"}).find("--gpus"), std::string::npos);
    EXPECT_NE(error_of({"bench", "flag", "--gpus", "1,x"}).find("'x'"), std::string::npos);
}

// A solver preset is a set of scene overrides under the --set keys, wherever it stands on the line;
// a second --preset replaces the first; an unknown one names the presets.
TEST(CliArgs, PresetGoesUnderTheSetKeys) {
    const Invocation inv = parse({"run", "flag", "--set", "solver.substeps=3", "--preset", "accurate"});
    const std::vector<std::string>& o = inv.run.sim.overrides;
    ASSERT_GE(o.size(), 2u);
    EXPECT_EQ(o.back(), "solver.substeps=3") << "the --set comes after the preset's keys, so it wins";
    EXPECT_NE(std::find(o.begin(), o.end(), "solver.cg_tolerance=1e-06"), o.end());
    EXPECT_NE(std::find(o.begin(), o.end(), "solver.precision=\"double\""), o.end());
    const Invocation twice = parse({"bench", "flag", "--preset", "accurate", "--preset", "interactive"});
    EXPECT_EQ(twice.bench.sim.overrides, solver_preset_overrides("interactive"));
    const std::string e = error_of({"run", "flag", "--preset", "quick"});
    EXPECT_NE(e.find("unknown solver preset 'quick'"), std::string::npos) << e;
    EXPECT_NE(e.find("interactive"), std::string::npos) << e;
}

TEST(CliArgs, FramesZeroWritesInitialStateOnly) { EXPECT_EQ(parse({"run", "flag", "--frames", "0"}).run.frames, 0); }

TEST(CliArgs, DoubleDashEndsOptions) {
    EXPECT_EQ(parse({"run", "--", "--odd-name.toml"}).run.scene, "--odd-name.toml");
}

TEST(CliArgs, UnknownFlagIsNamedWithSuggestion) {
    const std::string e = error_of({"run", "flag", "--frmes", "3"});
    EXPECT_NE(e.find("'--frmes'"), std::string::npos) << e;
    EXPECT_NE(e.find("did you mean '--frames'"), std::string::npos) << e;
    EXPECT_EQ(command_of({"run", "flag", "--frmes", "3"}), "run");
}

TEST(CliArgs, MissingValueNamesFlag) {
    EXPECT_NE(error_of({"run", "flag", "--frames"}).find("--frames needs a value"), std::string::npos);
    EXPECT_NE(error_of({"run", "flag", "--out", "--quiet"}).find("--out needs a value"), std::string::npos);
    EXPECT_NE(error_of({"run", "flag", "--stats="}).find("--stats"), std::string::npos);
}

TEST(CliArgs, NonNumericAndOutOfRangeNumbers) {
    std::string e = error_of({"run", "flag", "--frames", "abc"});
    EXPECT_NE(e.find("--frames"), std::string::npos) << e;
    EXPECT_NE(e.find("'abc'"), std::string::npos) << e;
    e = error_of({"run", "flag", "--frames", "12x"});
    EXPECT_NE(e.find("'12x'"), std::string::npos) << e;
    e = error_of({"run", "flag", "--frames", "-1"});
    EXPECT_NE(e.find("--frames must be in [0,"), std::string::npos) << e;
    e = error_of({"run", "flag", "--threads", "99999999999999999999"});
    EXPECT_NE(e.find("--threads"), std::string::npos) << e;
    e = error_of({"bench", "flag", "--frames", "0"});
    EXPECT_NE(e.find("--frames must be in [1,"), std::string::npos) << e;
    e = error_of({"bench", "flag", "--warmup", "1.5"});
    EXPECT_NE(e.find("--warmup"), std::string::npos) << e;
}

TEST(CliArgs, BadFormatAndOverride) {
    EXPECT_NE(error_of({"run", "flag", "--format", "stl"}).find("--format expects ply or obj, got 'stl'"),
              std::string::npos);
    EXPECT_NE(error_of({"run", "flag", "--set", "substeps"}).find("--set expects key=value"), std::string::npos);
    EXPECT_NE(error_of({"run", "flag", "--set", "=4"}).find("--set"), std::string::npos);
    EXPECT_NE(error_of({"run", "flag", "--set", "solver.substeps="}).find("--set"), std::string::npos);
}

TEST(CliArgs, SwitchWithValueIsAnError) {
    EXPECT_NE(error_of({"run", "flag", "--quiet=yes"}).find("--quiet takes no value"), std::string::npos);
}

TEST(CliArgs, SceneCount) {
    EXPECT_NE(error_of({"run"}).find("missing SCENE"), std::string::npos);
    EXPECT_NE(error_of({"run", "a", "b"}).find("'b'"), std::string::npos);
    EXPECT_NE(error_of({"bench"}).find("missing SCENE"), std::string::npos);
}

TEST(CliArgs, Bench) {
    const Invocation inv =
        parse({"bench", "flag", "hanging", "--json", "b.json", "--warmup", "2", "--frames", "5", "--set", "a.b=1"});
    ASSERT_EQ(inv.command, Invocation::Command::Bench);
    EXPECT_EQ(inv.bench.scenes, (std::vector<std::string>{"flag", "hanging"}));
    EXPECT_EQ(inv.bench.json_file, "b.json");
    EXPECT_EQ(inv.bench.warmup, 2);
    EXPECT_EQ(inv.bench.frames, 5);
    EXPECT_EQ(inv.bench.sim.overrides, (std::vector<std::string>{"a.b=1"}));
    const Invocation defaults = parse({"bench", "flag"});
    EXPECT_EQ(defaults.bench.warmup, 10);
    EXPECT_EQ(defaults.bench.frames, 100);
    // run-only flags are not bench flags
    EXPECT_NE(error_of({"bench", "flag", "--out", "x"}).find("'--out'"), std::string::npos);
}

TEST(CliArgs, ViewDefaultsAndFlags) {
    const Invocation defaults = parse({"view", "flag"});
    ASSERT_EQ(defaults.command, Invocation::Command::View);
    EXPECT_EQ(defaults.view.scene, "flag");
    EXPECT_EQ(defaults.view.sim.backend, "auto");
    EXPECT_FALSE(defaults.view.frames.has_value());
    EXPECT_TRUE(defaults.view.screenshot.empty());
    EXPECT_EQ(defaults.view.width, 1280);
    EXPECT_EQ(defaults.view.height, 720);
    EXPECT_EQ(defaults.view.time_scale, 1.0);
    EXPECT_FALSE(defaults.view.validation);

    const Invocation inv = parse({"view", "flag", "--backend", "cpu", "--set", "a.b=1", "--frames", "20", "--screenshot",
                                  "out/v.PNG", "--size=320x240", "--time-scale", "0.5", "--validation", "--threads",
                                  "2"});
    EXPECT_EQ(inv.view.sim.backend, "cpu");
    EXPECT_EQ(inv.view.sim.threads, 2);
    EXPECT_EQ(inv.view.sim.overrides, (std::vector<std::string>{"a.b=1"}));
    EXPECT_EQ(inv.view.frames, 20);
    EXPECT_EQ(inv.view.screenshot, "out/v.PNG");
    EXPECT_EQ(inv.view.width, 320);
    EXPECT_EQ(inv.view.height, 240);
    EXPECT_EQ(inv.view.time_scale, 0.5);
    EXPECT_TRUE(inv.view.validation);
    EXPECT_EQ(parse({"view", "--help"}).help_topic, "view");
    EXPECT_EQ(parse({"help", "view"}).help_topic, "view");
}

TEST(CliArgs, EditDefaultsAndFlags) {
    const Invocation defaults = parse({"edit"});
    ASSERT_EQ(defaults.command, Invocation::Command::Edit);
    EXPECT_EQ(defaults.edit.scene, "flag");  // the scene to start from when none is named
    EXPECT_TRUE(defaults.edit.script.empty());
    EXPECT_FALSE(defaults.edit.frames.has_value());
    EXPECT_EQ(defaults.edit.width, 1280);

    const Invocation inv = parse({"edit", "twist", "--backend", "cpu", "--script", "s.txt", "--frames", "30",
                                  "--screenshot", "out/e.png", "--size", "800x600", "--time-scale", "2",
                                  "--validation", "--set", "a.b=1"});
    EXPECT_EQ(inv.edit.scene, "twist");
    EXPECT_EQ(inv.edit.sim.backend, "cpu");
    EXPECT_EQ(inv.edit.script, "s.txt");
    EXPECT_EQ(inv.edit.frames, 30);
    EXPECT_EQ(inv.edit.screenshot, "out/e.png");
    EXPECT_EQ(inv.edit.width, 800);
    EXPECT_EQ(inv.edit.height, 600);
    EXPECT_EQ(inv.edit.time_scale, 2.0);
    EXPECT_TRUE(inv.edit.validation);
    EXPECT_EQ(inv.edit.sim.overrides, (std::vector<std::string>{"a.b=1"}));
    EXPECT_EQ(parse({"help", "edit"}).help_topic, "edit");

    std::string e = error_of({"edit", "flag", "drape"});
    EXPECT_NE(e.find("unexpected argument 'drape' (edit opens one scene)"), std::string::npos) << e;
    e = error_of({"edit", "--screenshot", "shot.jpg"});
    EXPECT_NE(e.find("--screenshot expects a .png file name"), std::string::npos) << e;
    e = error_of({"edit", "--scrip", "s.txt"});
    EXPECT_NE(e.find("did you mean '--script'"), std::string::npos) << e;
}

TEST(CliArgs, ViewMistakesNameTheFlag) {
    std::string e = error_of({"view"});
    EXPECT_NE(e.find("missing SCENE"), std::string::npos) << e;
    EXPECT_EQ(command_of({"view"}), "view");
    e = error_of({"view", "flag", "drape"});
    EXPECT_NE(e.find("unexpected argument 'drape'"), std::string::npos) << e;
    e = error_of({"view", "flag", "--frames", "0"});
    EXPECT_NE(e.find("--frames must be in [1, "), std::string::npos) << e;
    e = error_of({"view", "flag", "--screenshot", "shot.jpg"});
    EXPECT_NE(e.find("--screenshot expects a .png file name, got 'shot.jpg'"), std::string::npos) << e;
    e = error_of({"view", "flag", "--screenshot", ".png"});
    EXPECT_NE(e.find("--screenshot expects a .png"), std::string::npos) << e;
    e = error_of({"view", "flag", "--size", "320"});
    EXPECT_NE(e.find("--size expects WIDTHxHEIGHT"), std::string::npos) << e;
    e = error_of({"view", "flag", "--size", "8x8"});
    EXPECT_NE(e.find("--size must be in [16, 8192], got '8'"), std::string::npos) << e;
    e = error_of({"view", "flag", "--time-scale", "fast"});
    EXPECT_NE(e.find("--time-scale expects a number, got 'fast'"), std::string::npos) << e;
    e = error_of({"view", "flag", "--time-scale", "1000"});
    EXPECT_NE(e.find("--time-scale must be in [0.01, 100], got '1000'"), std::string::npos) << e;
    e = error_of({"view", "flag", "--time-scale", "0.001"});
    EXPECT_NE(e.find("--time-scale must be in"), std::string::npos) << e;
    e = error_of({"view", "flag", "--time-scale", "nan"});
    EXPECT_NE(e.find("--time-scale expects a number"), std::string::npos) << e;
    e = error_of({"view", "flag", "--validation=yes"});
    EXPECT_NE(e.find("--validation takes no value"), std::string::npos) << e;
    e = error_of({"view", "flag", "--out", "x"});
    EXPECT_NE(e.find("unknown option '--out'"), std::string::npos) << e;
    e = error_of({"view", "flag", "--time-sacle", "2"});
    EXPECT_NE(e.find("did you mean '--time-scale'"), std::string::npos) << e;
    e = error_of({"veiw", "flag"});
    EXPECT_NE(e.find("did you mean 'view'"), std::string::npos) << e;
}

TEST(CliArgs, ParseDouble) {
    EXPECT_EQ(parse_double("view", "--time-scale", "2", 0.01, 100.0), 2.0);
    EXPECT_EQ(parse_double("view", "--time-scale", "0.01", 0.01, 100.0), 0.01);
    EXPECT_EQ(parse_double("view", "--time-scale", "1e1", 0.01, 100.0), 10.0);
    EXPECT_THROW((void)parse_double("view", "--time-scale", "", 0.01, 100.0), UsageError);
    EXPECT_THROW((void)parse_double("view", "--time-scale", "2x", 0.01, 100.0), UsageError);
    EXPECT_THROW((void)parse_double("view", "--time-scale", "inf", 0.01, 100.0), UsageError);
    EXPECT_THROW((void)parse_double("view", "--time-scale", "-1", 0.01, 100.0), UsageError);
}

TEST(CliArgs, TopLevel) {
    EXPECT_EQ(parse({"--help"}).command, Invocation::Command::Help);
    EXPECT_EQ(parse({"-h"}).command, Invocation::Command::Help);
    EXPECT_EQ(parse({"help"}).help_topic, "");
    EXPECT_EQ(parse({"help", "bench"}).help_topic, "bench");
    EXPECT_EQ(parse({"run", "--help"}).help_topic, "run");
    EXPECT_EQ(parse({"bench", "x", "-h"}).help_topic, "bench");
    EXPECT_EQ(parse({"--version"}).command, Invocation::Command::Version);
    EXPECT_EQ(parse({"info"}).command, Invocation::Command::Info);

    EXPECT_NE(error_of({}).find("no command"), std::string::npos);
    std::string e = error_of({"rnu", "flag"});
    EXPECT_NE(e.find("unknown command 'rnu'"), std::string::npos) << e;
    EXPECT_NE(e.find("did you mean 'run'"), std::string::npos) << e;
    EXPECT_EQ(command_of({"rnu"}), "");
    e = error_of({"--frames", "3"});
    EXPECT_NE(e.find("'--frames'"), std::string::npos) << e;
    EXPECT_NE(error_of({"help", "nope"}).find("'nope'"), std::string::npos);
    EXPECT_NE(error_of({"info", "extra"}).find("'extra'"), std::string::npos);
    EXPECT_NE(error_of({"info", "--verbose"}).find("'--verbose'"), std::string::npos);
}

TEST(CliArgs, ParseInt) {
    EXPECT_EQ(parse_int("run", "--frames", "42", 0, 100), 42);
    EXPECT_EQ(parse_int("run", "--frames", "0", 0, 100), 0);
    EXPECT_THROW((void)parse_int("run", "--frames", "", 0, 100), UsageError);
    EXPECT_THROW((void)parse_int("run", "--frames", " 4", 0, 100), UsageError);
    EXPECT_THROW((void)parse_int("run", "--frames", "+4", 0, 100), UsageError);
    EXPECT_THROW((void)parse_int("run", "--frames", "101", 0, 100), UsageError);
    EXPECT_THROW((void)parse_int("run", "--frames", "0x10", 0, 100), UsageError);
}

TEST(CliArgs, HelpTextsCoverEveryFlag) {
    for (const std::string_view flag :
         {"--backend", "--threads", "--frames", "--out", "--format", "--stats", "--set", "--quiet"}) {
        EXPECT_NE(usage_text("run").find(flag), std::string_view::npos) << flag;
    }
    for (const std::string_view flag : {"--backend", "--threads", "--frames", "--warmup", "--json", "--set"}) {
        EXPECT_NE(usage_text("bench").find(flag), std::string_view::npos) << flag;
    }
    for (const std::string_view flag : {"--backend", "--threads", "--set", "--frames", "--screenshot", "--size",
                                        "--time-scale", "--validation"}) {
        EXPECT_NE(usage_text("view").find(flag), std::string_view::npos) << flag;
    }
    EXPECT_NE(usage_text("").find("weft view SCENE"), std::string_view::npos);
    EXPECT_EQ(usage_hint("run"), "Try 'weft run --help'.");
    EXPECT_EQ(usage_hint(""), "Try 'weft help'.");
}

}  // namespace
}  // namespace weft::cli
