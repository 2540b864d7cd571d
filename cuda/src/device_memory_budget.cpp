// The device memory budget (device_memory_budget.h): per-GPU counters, the thread's current budget,
// and the out-of-memory message.
#include "device_memory_budget.h"

#include <cuda_runtime_api.h>

#include "weft/byte_size.h"
#include "weft/error.h"

namespace weft::cuda {
namespace {

thread_local DeviceMemoryBudget* g_current = nullptr;

int checked_device(int device) {
    if (device < 0 || device >= DeviceMemoryBudget::kMaxDevices)
        throw Error("CUDA backend: device " + std::to_string(device) + " is beyond the " +
                    std::to_string(DeviceMemoryBudget::kMaxDevices) + " a memory budget counts");
    return device;
}

std::string bytes_text(std::size_t bytes) { return format_bytes(static_cast<double>(bytes)); }

}  // namespace

std::size_t DeviceMemoryBudget::held(int device) const { return held_[checked_device(device)].load(); }

void DeviceMemoryBudget::charge(int device, std::size_t bytes, const std::string& purpose) {
    std::atomic<std::size_t>& held = held_[checked_device(device)];
    std::size_t now = held.load();
    do {
        if (limit_ > 0 && (bytes > limit_ || now > limit_ - bytes)) throw_out_of_device_memory(device, bytes, purpose, this);
    } while (!held.compare_exchange_weak(now, now + bytes));
}

void DeviceMemoryBudget::refund(int device, std::size_t bytes) { held_[checked_device(device)].fetch_sub(bytes); }

DeviceMemoryBudget* current_budget() { return g_current; }

BudgetScope::BudgetScope(DeviceMemoryBudget* budget) : previous_(g_current) { g_current = budget; }
BudgetScope::~BudgetScope() { g_current = previous_; }

void throw_out_of_device_memory(int device, std::size_t bytes, const std::string& purpose, const DeviceMemoryBudget* budget) {
    std::size_t free = 0, total = 0;
    const bool known = cudaMemGetInfo(&free, &total) == cudaSuccess;
    (void)cudaGetLastError();  // a failed query must not stay as the thread's last error
    std::string message = "out of device memory on GPU " + std::to_string(device) + ": '" + purpose + "' needs " +
                          bytes_text(bytes) + " more";
    if (budget != nullptr) message += "; Weft holds " + bytes_text(budget->held(device)) + " on this GPU";
    if (known) message += ", the device has " + bytes_text(free) + " free of " + bytes_text(total);
    if (budget != nullptr && budget->limit() > 0)
        message += ", and the backend may use " + bytes_text(budget->limit()) + " (device_memory_limit)";
    throw Error(message);
}

}  // namespace weft::cuda
