// The editor's script runner (see script_runner.h).
#include "script_runner.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <system_error>

#include "weft/error.h"

namespace weft::editor {

void make_parent(const std::filesystem::path& file) {
    if (!file.has_parent_path()) return;
    std::error_code ec;
    std::filesystem::create_directories(file.parent_path(), ec);
    if (ec) throw Error("edit: cannot create " + file.parent_path().string() + ": " + ec.message());
}

ScriptRunner::Outcome ScriptRunner::run(Session& session, int shown, const Screenshot& shot, std::ostream& out,
                                        std::ostream& err) {
    while (next_ < script_.commands.size()) {
        ScriptCommand& c = script_.commands[next_];
        const std::string where = script_.name + ":" + std::to_string(c.line) + ": ";
        using K = ScriptCommand::Kind;
        switch (c.kind) {
            case K::frame:
                if (shown < c.frame) return Outcome::next_frame;
                ++next_;
                break;
            case K::set:
                if (!checked(session, next_, err)) return Outcome::failed;
                session.parameters().set_pending(c.key, c.number);
                ++next_;
                return Outcome::next_frame;
            case K::expect:
                if (!checked(session, next_, err)) return Outcome::failed;
                if (!expect(session, c, where, err)) return Outcome::failed;
                ++next_;
                break;
            case K::pause:
            case K::play:
                session.requests().paused = c.kind == K::pause;
                ++next_;
                return Outcome::next_frame;
            case K::step:
                ++session.requests().single_steps;
                ++next_;
                return Outcome::next_frame;
            case K::reset:
                session.requests().reset = true;
                ++next_;
                return Outcome::next_frame;
            case K::timescale:
                session.requests().time_scale = c.number;
                ++next_;
                return Outcome::next_frame;
            case K::screenshot:
                if (shown == 0) return Outcome::next_frame;  // nothing displayed yet
                make_parent(c.text);
                shot(std::filesystem::path(c.text));
                out << "screenshot " << c.text << std::endl;
                ++next_;
                break;
            case K::save:
                make_parent(c.text);
                session.save(c.text);
                out << "saved " << c.text << std::endl;
                ++next_;
                break;
            case K::open:
                session.requests().open = c.text;
                ++next_;
                return Outcome::next_frame;
            case K::record:
                session.requests().record = std::filesystem::path(c.text);
                ++next_;
                return Outcome::next_frame;
            case K::stop:
                session.requests().stop_recording = true;
                ++next_;
                return Outcome::next_frame;
            case K::cells: {
                ClothRecook change;
                change.cells = std::array<int, 2>{c.cells_x, c.cells_y};
                session.requests().recook = PlayRequests::Recook{c.key, change};
                ++next_;
                return Outcome::next_frame;
            }
            case K::cook: {
                ClothRecook change;
                if (c.text == "density") change.density = c.number;
                if (c.text == "scale") change.scale = c.number;
                if (c.text == "flat_rest_bending") change.flat_rest_bending = c.number != 0.0;
                session.requests().recook = PlayRequests::Recook{c.key, change};
                ++next_;
                return Outcome::next_frame;
            }
            case K::preset:
                session.requests().preset = PlayRequests::PresetChoice{c.key, c.text};
                ++next_;
                return Outcome::next_frame;
            case K::show: {
                DisplayOptions& d = session.display();
                bool& toggle = c.key == "wireframe" ? d.wireframe
                               : c.key == "normals" ? d.normals
                               : c.key == "contacts" ? d.contacts
                                                     : d.pins;
                toggle = c.number != 0.0;
                ++next_;
                return Outcome::next_frame;
            }
            case K::grab:
            case K::drag:
            case K::release:
            case K::pin: {
                using M = PlayRequests::MouseAction::Kind;
                const M kind = c.kind == K::grab ? M::grab : c.kind == K::drag ? M::drag : c.kind == K::pin ? M::pin : M::release;
                session.requests().mouse.push_back({kind, c.x, c.y});
                ++next_;
                return Outcome::next_frame;
            }
            case K::held: {
                const std::optional<double> d = session.grab_distance();
                if (!d || *d > c.x) {
                    err << "weft edit: " << where << "held " << c.x << ": "
                        << (d ? "the grabbed vertex is " + std::to_string(*d) + " m from the grab's target"
                              : std::string("nothing is grabbed"))
                        << std::endl;
                    return Outcome::failed;
                }
                out << "held: the grabbed vertex is " << *d << " m from the grab's target" << std::endl;
                ++expectations_;
                ++next_;
                break;
            }
            case K::quit:
                next_ = script_.commands.size();
                return Outcome::quit;
        }
    }
    return Outcome::quit;
}

bool ScriptRunner::checked(Session& session, std::size_t k, std::ostream& err) {
    ScriptCommand& c = script_.commands[k];
    if (c.checked) return true;
    try {
        check_command(script_.name, c, session.parameters());
        return true;
    } catch (const Error& e) {
        err << "weft edit: " << e.what() << " (scene " << session.scene().name << ")" << std::endl;
        return false;
    }
}

bool ScriptRunner::expect(Session& session, const ScriptCommand& c, const std::string& where, std::ostream& err) {
    const Parameter* p = session.parameters().find(c.key);
    const double have = p->get(session.world());
    const auto same = [](double a, double b) { return std::abs(a - b) <= 1e-9 * std::max(1.0, std::abs(b)); };
    if (!same(have, c.number)) {
        err << "weft edit: " << where << "expect " << c.key << " " << c.text << ": the world uses "
            << ParameterTable::format_value(*p, have) << std::endl;
        return false;
    }
    // Where the step reports the value, and a step ran since it was set: the step must agree.
    const FrameLoop& loop = session.loop();
    const std::optional<std::int64_t> at = session.applied_at(p->key);
    if (p->observed && loop.steps() > 0 && (!at || loop.steps() > *at)) {
        if (const std::optional<double> used = p->observed(loop.last_stats()); used && !same(*used, c.number)) {
            err << "weft edit: " << where << "expect " << c.key << " " << c.text << ": the last step used "
                << ParameterTable::format_value(*p, *used) << std::endl;
            return false;
        }
    }
    ++expectations_;
    return true;
}

}  // namespace weft::editor
