// `weft view SCENE`: the scene simulated live in a window (weft/render/window.h), driven by
// weft::FrameLoop with the wall time between displayed frames.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

#include "weft/error.h"

#include "commands.h"
#include "world_setup.h"

#if WEFT_HAVE_RENDER
#include "weft/frame_loop.h"
#include "weft/render/cloth_feed.h"
#include "weft/render/render_scene.h"
#include "weft/render/window.h"
#endif

namespace weft::cli {

#if WEFT_HAVE_RENDER
namespace {

using Clock = std::chrono::steady_clock;

double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

std::string title_of(const std::string& scene, double fps, const FrameLoop& loop, const World& world) {
    std::ostringstream t;
    t << std::fixed << "weft view " << scene << " \u2014 " << std::setprecision(1) << fps
      << " fps, t = " << std::setprecision(2) << world.time() << " s";
    if (loop.paused()) t << ", paused";
    if (loop.time_scale() != 1.0) t << ", \u00d7" << std::defaultfloat << std::setprecision(3) << loop.time_scale();
    return t.str();
}

// S without --screenshot: the first free weft_view_NNNN.png in the working folder.
std::filesystem::path next_screenshot_name() {
    for (int i = 0; i < 10000; ++i) {
        char name[32];
        std::snprintf(name, sizeof name, "weft_view_%04d.png", i);
        if (!std::filesystem::exists(name)) return name;
    }
    return "weft_view.png";
}

}  // namespace

int view_command(const ViewOptions& options, std::ostream& out, std::ostream& err) {
    require_backend("view", options.sim.backend);
    if (!options.screenshot.empty() && options.screenshot.has_parent_path()) {
        std::error_code ec;
        std::filesystem::create_directories(options.screenshot.parent_path(), ec);
        if (ec)
            throw Error("view: cannot create " + options.screenshot.parent_path().string() +
                        " for --screenshot: " + ec.message());
    }
    LoadedScene loaded = load_world(options.scene, options.sim);
    World& world = *loaded.world;
    const std::string name = loaded.desc.name.empty() ? options.scene : loaded.desc.name;

    render::RendererOptions renderer;
    renderer.width = options.width;
    renderer.height = options.height;
    renderer.validation = options.validation;
    render::Window window(renderer, "weft view " + name);
    const render::RenderScene scene = render::make_render_scene(world, loaded.desc.camera);
    window.load(scene);

    FrameLoop::Options loop_options;
    loop_options.time_scale = options.time_scale;
    FrameLoop loop(world, loop_options);
    // Zero-copy where the backend shares the window's GPU; the steps of each frame run while the
    // window draws the one before (weft/render/cloth_feed.h).
    render::ClothFeed feed(world, window.renderer(), scene);
    render::RenderFrame previous;

    int shown = 0;
    const Clock::time_point start = Clock::now();
    Clock::time_point last = start, title_at = start, first_shown = start;
    int title_frames = 0;
    double fps = 0.0;
    while (window.poll_events()) {
        const render::ViewerRequests asked = window.take_requests();
        if (asked.toggle_pause) loop.set_paused(!loop.paused());
        if (asked.single_steps > 0 && loop.paused()) loop.request_single_step();
        if (asked.time_scale_steps != 0)
            loop.set_time_scale(std::clamp(loop.time_scale() * std::ldexp(1.0, asked.time_scale_steps), 0.01, 100.0));

        // The first frame shows the initial state; after it the world runs at wall-clock time.
        const Clock::time_point now = Clock::now();
        render::RenderFrame frame = feed.simulate([&] { (void)loop.advance(shown == 0 ? 0.0 : seconds(now - last)); });
        last = now;
        window.present(frame);
        // present() waited for the frame before: its stamps are in transfer() now.
        if (shown > 0) (void)feed.check(previous, window.transfer());
        previous = std::move(frame);
        if (++shown == 1) first_shown = Clock::now();
        ++title_frames;

        if (asked.screenshot) {
            const std::filesystem::path file = options.screenshot.empty() ? next_screenshot_name() : options.screenshot;
            render::write_png(file, window.screenshot());
            out << "screenshot " << file.string() << std::endl;
        }
        const Clock::time_point after = Clock::now();
        if (seconds(after - title_at) >= 0.5) {
            fps = title_frames / seconds(after - title_at);
            title_frames = 0;
            title_at = after;
            window.set_title(title_of(name, fps, loop, world));
        }
        if (options.frames && shown >= *options.frames) break;
    }
    const double shown_seconds = seconds(Clock::now() - first_shown);
    if (!options.screenshot.empty() && shown > 0) render::write_png(options.screenshot, window.screenshot());

    // Frames after the first (which includes start-up work) over the time since it.
    const double mean_fps = shown > 1 && shown_seconds > 0.0 ? (shown - 1) / shown_seconds : 0.0;
    out << std::fixed << std::setprecision(1) << "weft view: " << shown << (shown == 1 ? " frame" : " frames") << " of "
        << name << " at " << window.width() << "x" << window.height() << ", " << mean_fps << " fps, "
        << std::setprecision(2) << "simulated " << world.time() << " s in " << loop.steps() << " steps ("
        << loop.dropped_steps() << " dropped), on " << window.device_description() << "; cloth by " << feed.describe()
        << ", " << feed.torn_frames() << " of " << feed.checked_frames() << " frames torn" << std::endl;
    if (!options.screenshot.empty() && shown > 0) out << "screenshot " << options.screenshot.string() << std::endl;
    if (feed.torn_frames() > 0) {
        err << "weft: " << feed.torn_frames() << " frames drew from a cloth slot holding parts of two states" << std::endl;
        return kExitError;
    }
    if (options.validation && window.validation_messages() > 0) {
        err << "weft: " << window.validation_messages() << " Vulkan validation messages" << std::endl;
        return kExitError;
    }
    return kExitOk;
}

#else

int view_command(const ViewOptions& /*options*/, std::ostream& /*out*/, std::ostream& /*err*/) {
    throw Error(
        "view: this build has no renderer (configure with -DWEFT_RENDER=ON and the Vulkan, EGL, libpng and "
        "GLFW packages of tools/deps.sh)");
}

#endif

}  // namespace weft::cli
