// Backend::share_output for backends that keep the cloth in host memory: no zero-copy output, the
// renderer uploads (weft/backend/interop.h). The fds passed in are closed so that they never leak
// (close_slot_handles, also used by every other side that gives up on handles it holds).
#include <unistd.h>

#include "weft/backend/backend.h"
#include "weft/world.h"

namespace weft {

void close_slot_handles(std::span<const SharedSlotHandle> slots) {
    for (const SharedSlotHandle& s : slots) {
        if (s.memory.fd >= 0) ::close(s.memory.fd);
        if (s.timeline.fd >= 0) ::close(s.timeline.fd);
    }
}

std::unique_ptr<SharedOutput> Backend::share_output(std::span<const SharedSlotHandle> slots, const DeviceUuid& /*device*/,
                                                    std::string& why) {
    close_slot_handles(slots);
    why = "the " + std::string(name()) + " backend keeps the cloth in host memory";
    return nullptr;
}

std::unique_ptr<SharedOutput> share_output(World& world, std::span<const SharedSlotHandle> slots,
                                           const DeviceUuid& device, std::string& why) {
    world.build();
    return world.backend().share_output(slots, device, why);
}

}  // namespace weft
