// The launch record of cuda_check.h: counts of checked launches by name while it is on.
#include <mutex>
#include <utility>

#include "cuda_check.h"

namespace weft::cuda {
namespace {

std::mutex& record_mutex() {
    static std::mutex m;
    return m;
}

std::map<std::string, long long>& record() {
    static std::map<std::string, long long> counts;
    return counts;
}

}  // namespace

void note_launch(const char* file, const char* name) {
    std::string key(file);
    if (const std::size_t src = key.rfind("src/"); src != std::string::npos) key.erase(0, src + 4);
    key += ": ";
    key += name;
    const std::lock_guard lock(record_mutex());  // the multi-GPU detection launches from several threads
    ++record()[key];
}

void start_launch_record() {
    const std::lock_guard lock(record_mutex());
    record().clear();
    launch_record_on.store(true);
}

std::map<std::string, long long> stop_launch_record() {
    launch_record_on.store(false);
    const std::lock_guard lock(record_mutex());
    return std::exchange(record(), {});
}

}  // namespace weft::cuda
