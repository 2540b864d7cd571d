#pragma once
// Factory of the built-in CPU backend.

#include <memory>

#include "weft/backend/backend.h"

namespace weft::cpu {

[[nodiscard]] std::unique_ptr<Backend> make_cpu_backend(const BackendOptions& options);

}  // namespace weft::cpu
