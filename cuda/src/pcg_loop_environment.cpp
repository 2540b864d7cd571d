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

}  // namespace weft::cuda
