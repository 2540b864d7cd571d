// WEFT_CUDA_PCG (pcg_loop_environment.h).
#include "pcg_loop_environment.h"

#include <cstdlib>
#include <string>
#include <string_view>

#include "weft/error.h"

namespace weft::cuda {

std::optional<PcgLoop> pcg_loop_from_environment() {
    const char* env = std::getenv("WEFT_CUDA_PCG");
    if (env == nullptr) return std::nullopt;
    const std::string_view v(env);
    if (v == "one") return PcgLoop::OneLaunch;
    if (v == "kernels") return PcgLoop::PerKernel;
    if (v == "auto") return PcgLoop::Auto;
    throw Error("WEFT_CUDA_PCG='" + std::string(v) + "': expected one, kernels or auto");
}

std::optional<int> pcg_blocks_from_environment() {
    const char* env = std::getenv("WEFT_CUDA_PCG_BLOCKS");
    if (env == nullptr) return std::nullopt;
    char* end = nullptr;
    const long blocks = std::strtol(env, &end, 10);
    if (end == env || *end != '\0' || blocks < 1 || blocks > (1L << 20))
        throw Error("WEFT_CUDA_PCG_BLOCKS='" + std::string(env) + "': expected a block count from 1 to 1048576");
    return static_cast<int>(blocks);
}

}  // namespace weft::cuda
