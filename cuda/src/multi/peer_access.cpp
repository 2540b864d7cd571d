// Peer access between two CUDA devices (multi/peer_access.h).
#include "multi/peer_access.h"

#include <cuda_runtime_api.h>

#include <mutex>
#include <set>
#include <string>
#include <utility>

#include "cuda_check.h"
#include "weft/error.h"

namespace weft::cuda::multi {

void enable_peer_access(int device, int peer) {
    if (device == peer) return;
    static std::mutex mutex;
    static std::set<std::pair<int, int>> enabled;
    const std::lock_guard lock(mutex);
    WEFT_CUDA_CHECK(cudaSetDevice(device));
    if (enabled.contains({device, peer})) return;
    int can = 0;
    WEFT_CUDA_CHECK(cudaDeviceCanAccessPeer(&can, device, peer));
    if (can == 0)
        throw Error("multi-GPU: device " + std::to_string(device) + " cannot access the memory of device " +
                    std::to_string(peer) + " (no peer access between them)");
    WEFT_CUDA_CHECK(cudaDeviceEnablePeerAccess(peer, 0));
    enabled.insert({device, peer});
}

}  // namespace weft::cuda::multi
