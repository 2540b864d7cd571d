// Names of the host-wait choices (weft/backend/backend.h), for flags, stats and messages.
#include <string>

#include "weft/backend/backend.h"
#include "weft/error.h"

namespace weft {

const char* host_wait_name(HostWait wait) {
    switch (wait) {
        case HostWait::automatic:
            return "auto";
        case HostWait::spin:
            return "spin";
        case HostWait::yield:
            return "yield";
        case HostWait::block:
            return "block";
    }
    return "auto";
}

HostWait parse_host_wait(std::string_view text) {
    for (const HostWait w : {HostWait::automatic, HostWait::spin, HostWait::yield, HostWait::block})
        if (text == host_wait_name(w)) return w;
    throw Error("host wait '" + std::string(text) + "': expected auto, spin, yield or block");
}

}  // namespace weft
