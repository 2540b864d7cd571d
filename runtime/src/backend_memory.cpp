// Backend::memory_breakdown for backends that do not split their memory by purpose.
#include "weft/backend/backend.h"

namespace weft {

std::vector<std::pair<std::string, std::size_t>> Backend::memory_breakdown() const {
    return {{"state", memory_bytes()}};
}

}  // namespace weft
