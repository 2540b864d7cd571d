// Backend::memory_breakdown for backends that do not split their memory by purpose.
#include "weft/backend/backend.h"

#include <string>

#include "weft/error.h"

namespace weft {

std::vector<std::pair<std::string, std::size_t>> Backend::memory_breakdown() const {
    return {{"state", memory_bytes()}};
}

void Backend::restore_solver_state(std::span<const std::uint8_t> bytes) {
    if (!bytes.empty())
        throw Error(std::string("backend ") + std::string(name()) + ": the checkpoint carries solver state (" +
                    std::to_string(bytes.size()) + " bytes) this backend does not keep");
}

}  // namespace weft
