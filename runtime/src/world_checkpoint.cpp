// World::save_state and World::load_state: checkpoints (weft/world.h; docs/design.md, "Checkpoints").
//
// The file: the 10 bytes "WEFTSTATE\0", uint32 version, uint64 payload size, uint64 FNV-1a hash of
// the payload, then the payload (little-endian): the backend's name, time (f64, s), steps (u64),
// the substep splitting's level and substeps since its last split (i32 each, SolverSettings::split_stretch),
// the cloth count, per cloth its vertex count, positions and velocities (f64 × 3 each), its pins
// (vertex, motion, optional position), the grab (optional), and the backend's solver state bytes.
#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "weft/atomic_file.h"
#include "weft/backend/backend.h"
#include "weft/backend/model.h"
#include "weft/error.h"
#include "weft/world.h"

namespace weft {
namespace {

static_assert(std::endian::native == std::endian::little, "checkpoints are little-endian; this writer stores native values");

constexpr std::array<char, 10> kMagic = {'W', 'E', 'F', 'T', 'S', 'T', 'A', 'T', 'E', '\0'};
constexpr std::uint32_t kVersion = 2;  // 2: the substep splitting's controller after the steps

std::uint64_t fnv1a(const std::string& bytes) {
    std::uint64_t h = 14695981039346656037ULL;
    for (const char c : bytes) {
        h ^= static_cast<unsigned char>(c);
        h *= 1099511628211ULL;
    }
    return h;
}

class Writer {
public:
    template <typename T>
    void put(T v) {
        bytes_.append(reinterpret_cast<const char*>(&v), sizeof(T));
    }
    void put(const std::string& s) {
        put(static_cast<std::uint32_t>(s.size()));
        bytes_ += s;
    }
    void put(const Vec3d& v) {
        put(v.x);
        put(v.y);
        put(v.z);
    }
    void put_bytes(const std::vector<std::uint8_t>& b) {
        put(static_cast<std::uint64_t>(b.size()));
        bytes_.append(reinterpret_cast<const char*>(b.data()), b.size());
    }
    [[nodiscard]] const std::string& bytes() const { return bytes_; }

private:
    std::string bytes_;
};

class Reader {
public:
    Reader(const std::string& bytes, std::string file) : bytes_(bytes), file_(std::move(file)) {}
    template <typename T>
    T get() {
        need(sizeof(T));
        T v;
        std::memcpy(&v, bytes_.data() + at_, sizeof(T));
        at_ += sizeof(T);
        return v;
    }
    std::string get_string() {
        const auto n = get<std::uint32_t>();
        need(n);
        std::string s = bytes_.substr(at_, n);
        at_ += n;
        return s;
    }
    Vec3d get_vec3() {
        Vec3d v;
        v.x = get<double>();
        v.y = get<double>();
        v.z = get<double>();
        return v;
    }
    std::vector<std::uint8_t> get_bytes() {
        const auto n = get<std::uint64_t>();
        need(n);
        std::vector<std::uint8_t> b(bytes_.begin() + static_cast<std::ptrdiff_t>(at_),
                                    bytes_.begin() + static_cast<std::ptrdiff_t>(at_ + n));
        at_ += n;
        return b;
    }
    [[nodiscard]] bool done() const { return at_ == bytes_.size(); }

private:
    void need(std::uint64_t n) const {
        if (n > bytes_.size() - at_) throw Error(file_ + ": the checkpoint ends early");
    }
    const std::string& bytes_;
    std::string file_;
    std::size_t at_ = 0;
};

struct ClothState {
    std::vector<Vec3d> x, v;
    std::vector<PinDesc> pins;
};

bool same_pins(const std::vector<PinDesc>& a, const std::vector<PinDesc>& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i)
        if (a[i].vertex != b[i].vertex || a[i].motion != b[i].motion || a[i].position.has_value() != b[i].position.has_value() ||
            (a[i].position && !(*a[i].position == *b[i].position)))
            return false;
    return true;
}

}  // namespace

void World::save_state(const std::filesystem::path& file) const {
    ensure_built();
    Writer w;
    w.put(std::string(backend_->name()));
    w.put(time_);
    w.put(static_cast<std::uint64_t>(steps_));
    w.put(static_cast<std::int32_t>(split_level_));
    w.put(static_cast<std::int32_t>(substeps_since_split_));
    w.put(static_cast<std::uint64_t>(model_->cloths.size()));
    for (std::size_t c = 0; c < model_->cloths.size(); ++c) {
        const std::vector<Vec3d> x = positions(c), v = velocities(c);
        w.put(static_cast<std::uint64_t>(x.size()));
        for (const Vec3d& p : x) w.put(p);
        for (const Vec3d& p : v) w.put(p);
        const std::vector<PinDesc>& pins = model_->cloths[c].pins;
        w.put(static_cast<std::uint64_t>(pins.size()));
        for (const PinDesc& p : pins) {
            w.put(p.vertex);
            w.put(static_cast<std::int32_t>(p.motion));
            w.put(static_cast<std::uint8_t>(p.position.has_value() ? 1 : 0));
            w.put(p.position.value_or(Vec3d{}));
        }
    }
    w.put(static_cast<std::uint8_t>(model_->grab.has_value() ? 1 : 0));
    if (model_->grab) {
        w.put(static_cast<std::uint64_t>(model_->grab->cloth));
        w.put(model_->grab->vertex);
        w.put(model_->grab->target);
        w.put(model_->grab->stiffness);
        w.put(model_->grab->damping);
    }
    w.put_bytes(backend_->solver_state());

    AtomicFile out(file);
    out.stream().write(kMagic.data(), kMagic.size());
    const std::uint32_t version = kVersion;
    const std::uint64_t size = w.bytes().size(), hash = fnv1a(w.bytes());
    out.stream().write(reinterpret_cast<const char*>(&version), sizeof(version));
    out.stream().write(reinterpret_cast<const char*>(&size), sizeof(size));
    out.stream().write(reinterpret_cast<const char*>(&hash), sizeof(hash));
    out.stream().write(w.bytes().data(), static_cast<std::streamsize>(w.bytes().size()));
    out.commit();
}

void World::load_state(const std::filesystem::path& file) {
    forget_audit();
    const std::string name = file.string();
    std::ifstream in(file, std::ios::binary);
    if (!in) throw Error("cannot read the checkpoint " + name);
    std::ostringstream all;
    all << in.rdbuf();
    const std::string bytes = all.str();
    constexpr std::size_t kHead = kMagic.size() + sizeof(std::uint32_t) + 2 * sizeof(std::uint64_t);
    if (bytes.size() < kHead || std::memcmp(bytes.data(), kMagic.data(), kMagic.size()) != 0)
        throw Error(name + ": not a Weft checkpoint");
    std::uint32_t version = 0;
    std::uint64_t size = 0, hash = 0;
    std::memcpy(&version, bytes.data() + kMagic.size(), sizeof(version));
    std::memcpy(&size, bytes.data() + kMagic.size() + sizeof(version), sizeof(size));
    std::memcpy(&hash, bytes.data() + kMagic.size() + sizeof(version) + sizeof(size), sizeof(hash));
    if (version != kVersion)
        throw Error(name + ": checkpoint version " + std::to_string(version) + " (this Weft reads " + std::to_string(kVersion) + ")");
    if (bytes.size() - kHead != size)
        throw Error(name + ": the checkpoint holds " + std::to_string(bytes.size() - kHead) + " bytes of the " + std::to_string(size) +
                    " its header declares (cut short?)");
    const std::string payload = bytes.substr(kHead);
    if (fnv1a(payload) != hash) throw Error(name + ": the checkpoint's checksum does not match (the file is corrupt)");

    // Read and check everything before changing the world.
    Reader r(payload, name);
    const std::string backend = r.get_string();
    if (backend != backend_name())
        throw Error(name + ": the checkpoint was made on the " + backend + " backend, this world runs on " +
                    std::string(backend_name()));
    const auto time = r.get<double>();
    const auto steps = r.get<std::uint64_t>();
    const auto split_level = r.get<std::int32_t>();
    const auto substeps_since_split = r.get<std::int32_t>();
    if (split_level < 0 || split_level > 30 || substeps_since_split < 0)
        throw Error(name + ": the checkpoint's substep splitting state (" + std::to_string(split_level) + ", " +
                    std::to_string(substeps_since_split) + ") is out of range");
    const auto cloths = r.get<std::uint64_t>();
    if (cloths != model_->cloths.size())
        throw Error(name + ": the checkpoint has " + std::to_string(cloths) + " cloths, this world " +
                    std::to_string(model_->cloths.size()));
    std::vector<ClothState> state(cloths);
    for (std::size_t c = 0; c < cloths; ++c) {
        const auto n = r.get<std::uint64_t>();
        const std::size_t want = model_->cloths[c].fabric->vertex_count();
        if (n != want)
            throw Error(name + ": cloth " + std::to_string(c) + " ('" + model_->cloths[c].name + "') has " + std::to_string(n) +
                        " vertices in the checkpoint and " + std::to_string(want) + " in this world");
        state[c].x.resize(n);
        state[c].v.resize(n);
        for (Vec3d& p : state[c].x) p = r.get_vec3();
        for (Vec3d& p : state[c].v) p = r.get_vec3();
        const auto pins = r.get<std::uint64_t>();
        if (pins > n) throw Error(name + ": cloth " + std::to_string(c) + " has " + std::to_string(pins) + " pins for " + std::to_string(n) + " vertices");
        for (std::uint64_t k = 0; k < pins; ++k) {
            PinDesc p;
            p.vertex = r.get<std::uint32_t>();
            p.motion = r.get<std::int32_t>();
            const bool has_position = r.get<std::uint8_t>() != 0;
            const Vec3d position = r.get_vec3();
            if (has_position) p.position = position;
            if (p.vertex >= n || p.motion >= static_cast<int>(model_->motions.size()) || p.motion < -1)
                throw Error(name + ": cloth " + std::to_string(c) + " pins vertex " + std::to_string(p.vertex) + " to motion " +
                            std::to_string(p.motion) + ", which this world does not have");
            state[c].pins.push_back(p);
        }
    }
    std::optional<VertexGrab> grab;
    if (r.get<std::uint8_t>() != 0) {
        VertexGrab g;
        g.cloth = static_cast<std::size_t>(r.get<std::uint64_t>());
        g.vertex = r.get<std::uint32_t>();
        g.target = r.get_vec3();
        g.stiffness = r.get<double>();
        g.damping = r.get<double>();
        if (g.cloth >= cloths || g.vertex >= state[g.cloth].x.size()) throw Error(name + ": the checkpoint's grab is out of range");
        grab = g;
    }
    const std::vector<std::uint8_t> solver = r.get_bytes();
    if (!r.done()) throw Error(name + ": the checkpoint has bytes after its end");

    // Apply, keeping what was there: the backend checks its own bytes (precision, vertex count) only
    // when it takes them, and a refusal there puts everything back.
    ensure_built();
    std::vector<ClothState> before(cloths);
    for (std::size_t c = 0; c < cloths; ++c) before[c] = {positions(c), velocities(c), model_->cloths[c].pins};
    const std::vector<std::uint8_t> solver_before = backend_->solver_state();
    const auto apply = [&](const std::vector<ClothState>& s, const std::vector<std::uint8_t>& solver_bytes) {
        bool pins_changed = false;
        for (std::size_t c = 0; c < cloths; ++c)
            if (!same_pins(model_->cloths[c].pins, s[c].pins)) {
                model_->cloths[c].pins = s[c].pins;
                pins_changed = true;
            }
        if (pins_changed) ++model_->topology_version;
        ensure_built();
        for (std::size_t c = 0; c < cloths; ++c) backend_->write_state(c, s[c].x, s[c].v);
        backend_->restore_solver_state(solver_bytes);
    };
    try {
        apply(state, solver);
    } catch (const Error& e) {
        apply(before, solver_before);
        throw Error(name + ": " + e.what());
    }
    model_->grab = grab;
    time_ = time;
    steps_ = static_cast<std::size_t>(steps);
    split_level_ = split_level;
    substeps_since_split_ = substeps_since_split;
}

}  // namespace weft
