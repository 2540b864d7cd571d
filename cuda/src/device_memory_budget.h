#pragma once
// How much device memory one backend may hold on each GPU (BackendOptions::device_memory_limit,
// `weft run --device-memory-limit`), and the message a failed allocation gives: which buffer, how
// many bytes it asked for, what Weft already holds on that GPU and what the device has free.
//
// Every device allocation goes through DeviceArray (device_array.h), which charges the budget of the
// backend whose call is running on this thread (BudgetScope) and gives it back when freed. A scene
// larger than the budget (or than the device) fails at build with those figures; a buffer that grows
// mid-run (contacts appearing) fails the substep the same way, and the backend puts the cloth back
// where the substep started (DeviceSolver::substep, docs/design.md "Device faults").

#include <array>
#include <atomic>
#include <cstddef>
#include <string>

namespace weft::cuda {

class DeviceMemoryBudget {
public:
    static constexpr int kMaxDevices = 64;
    /// `limit` bytes per GPU; 0 = no limit but the device's own memory.
    explicit DeviceMemoryBudget(std::size_t limit = 0) : limit_(limit) {}
    void set_limit(std::size_t limit) { limit_ = limit; }
    [[nodiscard]] std::size_t limit() const { return limit_; }
    /// Bytes held through this budget on `device`.
    [[nodiscard]] std::size_t held(int device) const;
    /// Counts `bytes` on `device` for `purpose`; throws weft::Error (out_of_device_memory's message)
    /// when that would pass the limit, counting nothing.
    void charge(int device, std::size_t bytes, const std::string& purpose);
    void refund(int device, std::size_t bytes);

private:
    std::size_t limit_ = 0;
    std::array<std::atomic<std::size_t>, kMaxDevices> held_{};
};

/// The budget DeviceArray charges on this thread (null: none, only the device's own memory).
[[nodiscard]] DeviceMemoryBudget* current_budget();

/// Makes `budget` the current one on this thread for the scope's life (nested scopes restore the
/// outer one). A backend opens one around build and substep; its worker threads open their own.
class BudgetScope {
public:
    explicit BudgetScope(DeviceMemoryBudget* budget);
    ~BudgetScope();
    BudgetScope(const BudgetScope&) = delete;
    BudgetScope& operator=(const BudgetScope&) = delete;

private:
    DeviceMemoryBudget* previous_;
};

/// Throws weft::Error: "out of device memory on GPU D: PURPOSE needs B more bytes; Weft holds H on
/// this GPU, the device has F free of T" (and the limit, where the budget set one).
[[noreturn]] void throw_out_of_device_memory(int device, std::size_t bytes, const std::string& purpose,
                                             const DeviceMemoryBudget* budget);

}  // namespace weft::cuda
