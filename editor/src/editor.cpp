// The editor's main loop (see editor.h).
#include "weft/backend/model.h"
#include "weft/editor/editor.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <sstream>
#include <system_error>
#include <utility>
#include <vector>

#include "weft/error.h"
#include "weft/render/cloth_feed.h"
#include "weft/render/frame_sequence.h"
#include "weft/render/image.h"
#include "weft/render/render_scene.h"
#include "weft/render/window.h"

#include "weft/editor/imgui_layer.h"
#include "weft/editor/panels.h"
#include "weft/editor/session.h"
#include "weft/editor/viewport_overlay.h"

#include "script_runner.h"

namespace weft::editor {
namespace {

using Clock = std::chrono::steady_clock;

double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

// The shape and sizes of every collider, in order: the render scene's collider meshes are made from them.
std::vector<double> collider_sizes(const World& world) {
    std::vector<double> sizes;
    for (const ColliderDesc& c : world.model().colliders)
        sizes.insert(sizes.end(), {static_cast<double>(c.shape), c.radius, c.half_height, c.half_extents.x,
                                   c.half_extents.y, c.half_extents.z});
    return sizes;
}

std::string title_of(const std::string& scene, double fps, Session& session) {
    std::ostringstream t;
    t << std::fixed << "weft edit " << scene << " \u2014 " << std::setprecision(1) << fps << " fps, t = "
      << std::setprecision(2) << session.world().time() << " s";
    if (session.loop().paused()) t << ", paused";
    return t.str();
}

}  // namespace

std::filesystem::path default_ini_file() {
    std::filesystem::path folder;
    if (const char* xdg = std::getenv("XDG_CONFIG_HOME"); xdg != nullptr && *xdg != '\0')
        folder = std::filesystem::path(xdg) / "weft";
    else if (const char* home = std::getenv("HOME"); home != nullptr && *home != '\0')
        folder = std::filesystem::path(home) / ".config" / "weft";
    else
        return {};
    std::error_code ec;
    std::filesystem::create_directories(folder, ec);
    if (ec) return {};
    return folder / "imgui.ini";
}

int run_editor(const SceneDesc& scene, std::unique_ptr<World> world, EditorOptions options, std::ostream& out,
               std::ostream& err) {
    if (!options.screenshot.empty()) make_parent(options.screenshot);
    std::string name = scene.name.empty() ? std::string("scene") : scene.name;
    auto session =
        std::make_unique<Session>(scene, options.backend, options.backend_options, std::move(world), options.time_scale);
    const bool scripted = options.script.has_value();
    if (scripted) check_script(*options.script, session->parameters());  // before any window opens

    render::RendererOptions renderer;
    renderer.width = options.width;
    renderer.height = options.height;
    renderer.validation = options.validation;
    render::Window window(renderer, "weft edit " + name);
    render::RenderScene render_scene = render::make_render_scene(session->world(), scene.camera);
    window.load(render_scene);
    // Scripted runs keep no layout: a test must not depend on what a person left behind.
    ImGuiLayer imgui(window, scripted ? std::filesystem::path{} : options.ini_file, options.ui_scale);

    std::optional<ScriptRunner> runner;
    if (scripted) runner.emplace(*options.script);
    // The cloth reaches the window zero-copy where the backend shares its GPU (cloth_feed.h); a
    // reset builds a new world, so the feed is let go first and linked to the new one after.
    std::unique_ptr<render::ClothFeed> feed;
    session->set_before_rebuild([&] { feed.reset(); });
    render::RenderFrame previous;
    bool have_previous = false;
    std::int64_t torn = 0;
    int shown = 0;
    int status = 0;
    const Clock::time_point start = Clock::now();
    Clock::time_point last = start, fps_at = start, first_shown = start;
    int fps_frames = 0;
    double fps = 0.0;
    auto shot = [&](const std::filesystem::path& file) { render::write_png(file, window.screenshot()); };
    std::optional<render::FrameSequence> recording;
    int drawn_resets = 0;  // Session::resets() of the world the window's scene was made from (-1: none)
    std::vector<double> drawn_sizes = collider_sizes(session->world());  // of the colliders the window draws
    // Ends the recording: the MP4 at the simulation's frame rate when ffmpeg is there.
    auto finish_recording = [&] {
        RecordingStatus& rec = session->recording();
        const render::FrameSequence::Video video = recording->encode_mp4(1.0 / session->world().settings().solver.dt);
        rec.active = false;
        rec.video = video.file.empty() ? "none (" + video.note + ")" : video.file.string();
        out << "recorded " << rec.frames << " frames to " << rec.folder.string() << "; video: " << rec.video << std::endl;
        recording.reset();
    };

    // A scripted run prints what the session says (a re-cook's time, a pin, a preset): the test's log.
    int said = 0;
    auto tell = [&] {
        if (runner && session->messages() != said) out << session->message() << std::endl;
        said = session->messages();
    };

    while (window.poll_events()) {
        // Keys of the viewer: the same requests as the play panel's buttons.
        const render::ViewerRequests keys = window.take_requests();
        PlayRequests& asked = session->requests();
        if (keys.toggle_pause) asked.paused = !session->loop().paused();
        asked.single_steps += keys.single_steps;
        if (keys.time_scale_steps != 0)
            asked.time_scale =
                std::clamp(session->loop().time_scale() * std::ldexp(1.0, keys.time_scale_steps), 0.01, 100.0);

        if (runner) {
            const ScriptRunner::Outcome o = runner->run(*session, shown, shot, out, err);
            if (o == ScriptRunner::Outcome::failed) {
                status = 1;
                break;
            }
            if (o == ScriptRunner::Outcome::quit) break;
        }

        imgui.begin_frame();
        draw_panels(*session, PanelLayout{static_cast<float>(window.width()), static_cast<float>(window.height()), fps,
                                          options.open_scene ? &options.scene_names : nullptr});
        tell();  // a preset, an unpin from the Pins panel
        // A preset a script asked for that cannot be applied: the script cannot check what it meant to.
        if (runner && session->message().rfind("preset failed", 0) == 0) {
            err << "weft edit: " << session->message() << std::endl;
            status = 1;
            break;
        }

        // A re-cook (Mesh panel, a preset's density, script): the fabric is cooked again, timed.
        if (const std::optional<PlayRequests::Recook> change = std::exchange(session->requests().recook, std::nullopt)) {
            try {
                (void)session->recook(change->cloth, change->change);
                tell();
            } catch (const std::exception& e) {
                session->set_message(std::string("re-cook failed: ") + e.what());
                err << "weft edit: " << e.what() << std::endl;
                if (runner) {
                    status = 1;
                    break;
                }
            }
        }
        // Scenes panel or script: another scene replaces the session, the render scene and the feed.
        if (std::optional<std::string> wanted = std::exchange(session->requests().open, std::nullopt)) {
            try {
                if (!options.open_scene) throw Error("this editor was started without a scene folder");
                OpenedScene opened = options.open_scene(*wanted);
                if (recording) finish_recording();  // the recording belongs to the scene it showed
                const double scale = session->loop().time_scale();
                const DisplayOptions display = session->display();
                feed.reset();  // before the old world goes: the backend writes the window's slots
                session = std::make_unique<Session>(opened.scene, options.backend, options.backend_options,
                                                    std::move(opened.world), scale);
                session->display() = display;
                session->set_before_rebuild([&] { feed.reset(); });
                name = opened.scene.name.empty() ? *wanted : opened.scene.name;
                drawn_resets = -1;  // a new world: the window loads its scene below
                session->set_message("opened " + name);
                said = session->messages();  // printed below, as "opened"
                out << "opened " << name << std::endl;
            } catch (const std::exception& e) {
                session->set_message(std::string("open failed: ") + e.what());
                err << "weft edit: open " << *wanted << ": " << e.what() << std::endl;
                if (runner) {  // a script that cannot open its scene cannot go on
                    status = 1;
                    break;
                }
            }
        }
        // A re-cook, a reset or an open made a new world, or a collider's size changed (the Colliders
        // panel; its mesh is made from the sizes): the window draws the new cloth buffer and colliders.
        if (std::vector<double> sizes = collider_sizes(session->world());
            session->resets() != drawn_resets || sizes != drawn_sizes) {
            drawn_resets = session->resets();
            drawn_sizes = std::move(sizes);
            feed.reset();  // the window's buffers are made again: the backend lets go of them first
            render_scene = render::make_render_scene(session->world(), session->scene().camera);
            window.load(render_scene);
        }

        // The mouse on the cloth: Ctrl+drag grabs the vertex under the cursor and pulls it with a
        // spring, Shift+click pins or unpins it (docs/editor.md, "Mouse"); scripts ask the same.
        using MouseKind = PlayRequests::MouseAction::Kind;
        if (!scripted) {
            const ImGuiLayer::Mouse m = imgui.mouse();
            std::vector<PlayRequests::MouseAction>& actions = session->requests().mouse;
            if (m.pressed && !m.on_panels && m.ctrl) actions.push_back({MouseKind::grab, m.x, m.y});
            else if (m.pressed && !m.on_panels && m.shift) actions.push_back({MouseKind::pin, m.x, m.y});
            else if (session->grab_anchor() && m.down && m.moved) actions.push_back({MouseKind::drag, m.x, m.y});
            if (session->grab_anchor() && m.released) actions.push_back({MouseKind::release, m.x, m.y});
        }
        for (const PlayRequests::MouseAction& a : std::exchange(session->requests().mouse, {})) {
            const render::Camera& camera = window.camera();
            const int w = window.width(), h = window.height();
            if (a.kind == MouseKind::drag) {
                if (session->grab_anchor()) session->drag_to(drag_target(camera, w, h, a.x, a.y, *session->grab_anchor()));
                continue;
            }
            if (a.kind == MouseKind::release) {
                session->release_grab();
                tell();
                continue;
            }
            const std::optional<VertexPick> pick = pick_vertex(session->world(), camera, w, h, a.x, a.y);
            if (!pick) {
                session->set_message("no cloth under the cursor");
                if (runner) {  // a script that grabs or pins nothing cannot check what it meant to
                    err << "weft edit: no cloth vertex within 12 pixels of (" << a.x << ", " << a.y << ")" << std::endl;
                    status = 1;
                    break;
                }
                continue;
            }
            if (a.kind == MouseKind::grab)
                session->grab(*pick);
            else
                (void)session->toggle_pin(pick->cloth, pick->vertex);
            tell();
        }
        if (status != 0) break;

        // Scripted: exactly the wall time of one step per frame (at the current scale), so that the
        // run steps once per displayed frame whatever the machine's speed.
        const Clock::time_point now = Clock::now();
        if (!feed) {
            feed = std::make_unique<render::ClothFeed>(session->world(), window.renderer(), render_scene);
            have_previous = false;  // the frame before belongs to the old feed: not checked
        }
        render::RenderFrame frame = feed->simulate([&] {
            FrameLoop& loop = session->loop();
            const double wall = shown == 0 ? 0.0
                                : scripted ? session->world().settings().solver.dt / loop.time_scale()
                                           : seconds(now - last);
            (void)loop.advance(wall);
            for (const StepStats& step : loop.frame_stats()) session->history().record(step);  // every step of the frame
        });
        if (shown > 0) session->history().frame_ms.push(1000.0 * seconds(now - last));
        last = now;
        // The View panel: the wireframe, normals, contacts and pins drawn by the renderer from the
        // cloth buffer, depth-tested; the grab's spring by ImGui; then the ImGui frame ends.
        frame.lines = overlay_lines(session->world(), session->display());
        ViewportOverlay overlay =
            build_viewport_overlay(session->world(), window.camera(), window.width(), window.height(), session->display());
        frame.lines.points = std::move(overlay.points);
        draw_viewport_overlay(overlay);
        imgui.end_frame();
        window.present(frame);
        // present() waited for the frame before: its stamps are in transfer() now.
        if (have_previous && !feed->check(previous, window.transfer())) ++torn;
        previous = std::move(frame);
        have_previous = true;
        // Recording: start and stop as asked (panel or script), then this frame as displayed.
        RecordingStatus& rec = session->recording();
        PlayRequests& wants = session->requests();
        if (wants.stop_recording && recording) {
            finish_recording();
        }
        wants.stop_recording = false;
        if (std::optional<std::filesystem::path> folder = std::exchange(wants.record, std::nullopt)) {
            if (recording) finish_recording();
            try {
                recording.emplace(*folder);
                rec = RecordingStatus{true, *folder, 0, {}};
                out << "recording to " << folder->string() << std::endl;
            } catch (const std::exception& e) {
                session->set_message(std::string("record failed: ") + e.what());
                err << "weft edit: record " << folder->string() << ": " << e.what() << std::endl;
            }
        }
        if (recording) {
            recording->write(rec.frames, window.screenshot());
            ++rec.frames;
        }
        if (++shown == 1) first_shown = Clock::now();
        ++fps_frames;
        if (keys.screenshot) {
            const std::filesystem::path file = options.screenshot.empty() ? "weft_edit.png" : options.screenshot;
            shot(file);
            out << "screenshot " << file.string() << std::endl;
        }
        const Clock::time_point after = Clock::now();
        if (seconds(after - fps_at) >= 0.5) {
            fps = fps_frames / seconds(after - fps_at);
            fps_frames = 0;
            fps_at = after;
            window.set_title(title_of(name, fps, *session));
        }
        if (options.frames && shown >= *options.frames) break;
    }
    if (recording) finish_recording();
    // A script that ends waiting for a frame the --frames limit cut off still gets its last word.
    if (runner && status == 0 && shown > 0) {
        if (runner->run(*session, shown, shot, out, err) == ScriptRunner::Outcome::failed) status = 1;
    }
    const double shown_seconds = seconds(Clock::now() - first_shown);
    if (!options.screenshot.empty() && shown > 0) {
        shot(options.screenshot);
        out << "screenshot " << options.screenshot.string() << std::endl;
    }
    const double mean_fps = shown > 1 && shown_seconds > 0.0 ? (shown - 1) / shown_seconds : 0.0;
    out << std::fixed << std::setprecision(1) << "weft edit: " << shown << (shown == 1 ? " frame" : " frames")
        << " of " << name << " at " << window.width() << "x" << window.height() << ", " << mean_fps << " fps, "
        << std::setprecision(2) << "simulated " << session->world().time() << " s in " << session->loop().steps()
        << " steps, on " << window.device_description() << "; cloth by " << (feed ? feed->describe() : "-")
        << ", " << torn << " frames torn; panels at scale " << std::setprecision(2) << imgui.scale() << std::endl;
    if (runner && status == 0)
        out << "script " << options.script->name << ": " << options.script->commands.size() << " commands, "
            << runner->expectations() << " expectations met" << std::endl;
    if (options.validation && window.validation_messages() > 0) {
        err << "weft: " << window.validation_messages() << " Vulkan validation messages" << std::endl;
        status = 1;
    }
    if (torn > 0) {
        err << "weft: " << torn << " frames drew from a cloth slot holding parts of two states" << std::endl;
        status = 1;
    }
    session->set_before_rebuild({});
    return status;
}

}  // namespace weft::editor
