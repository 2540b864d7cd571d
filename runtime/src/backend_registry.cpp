// The backend factory: "cpu" is built in; other backends register themselves at start-up.
#include <algorithm>
#include <mutex>
#include <string>

#include "cpu/cpu_backend.h"
#include "weft/backend/backend.h"
#include "weft/error.h"

namespace weft {
namespace {

struct Entry {
    std::string name;
    std::string description;
    BackendFactory factory;
};

struct Registry {
    std::mutex mutex;
    std::vector<Entry> entries;
    Registry() {
        entries.push_back({"cpu", "multi-threaded CPU backend (TBB), float or double; the accuracy reference",
                           [](const BackendOptions& o) { return cpu::make_cpu_backend(o); }});
    }
};

Registry& registry() {
    static Registry r;
    return r;
}

}  // namespace

void register_backend(std::string name, std::string description, BackendFactory factory) {
    Registry& r = registry();
    std::lock_guard lock(r.mutex);
    auto it = std::find_if(r.entries.begin(), r.entries.end(), [&](const Entry& e) { return e.name == name; });
    if (it != r.entries.end()) {
        it->description = std::move(description);
        it->factory = std::move(factory);
    } else {
        r.entries.push_back({std::move(name), std::move(description), std::move(factory)});
    }
}

std::unique_ptr<Backend> create_backend(std::string_view name, const BackendOptions& options) {
    Registry& r = registry();
    BackendFactory factory;
    {
        std::lock_guard lock(r.mutex);
        for (const Entry& e : r.entries)
            if (e.name == name) factory = e.factory;
    }
    if (!factory) {
        std::string known;
        for (const std::string& n : backend_names()) known += (known.empty() ? "" : ", ") + n;
        throw Error("unknown backend '" + std::string(name) + "' (compiled backends: " + known + ")");
    }
    return factory(options);
}

std::vector<std::string> backend_names() {
    Registry& r = registry();
    std::lock_guard lock(r.mutex);
    std::vector<std::string> names;
    for (const Entry& e : r.entries) names.push_back(e.name);
    return names;
}

std::string backend_description(std::string_view name) {
    Registry& r = registry();
    std::lock_guard lock(r.mutex);
    for (const Entry& e : r.entries)
        if (e.name == name) return e.description;
    return {};
}

}  // namespace weft
