#pragma once
// Owning device allocations. All of them are made in DeviceSolver::build (docs/design.md: nothing
// allocated inside the step) or when a collision buffer grows; an arena of named allocations reports
// how the device memory is spent, and the thread's memory budget (device_memory_budget.h) caps it.

#include <cuda_runtime_api.h>

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "cuda_check.h"
#include "device_memory_budget.h"

namespace weft::cuda {

/// Waits for what cudaMemcpy and cudaMemset left on the legacy default stream. The solver's streams
/// are non-blocking, so they are not ordered after it: a pageable host-to-device cudaMemcpy returns
/// once the bytes are staged, not landed, and cudaMemset returns at once. A kernel enqueued next on
/// a solver stream could read the old bytes (seen as rare run-to-run differences with several parts
/// on one GPU); every such blocking call is followed by this.
inline void wait_for_default_stream() { WEFT_CUDA_CHECK(cudaStreamSynchronize(cudaStreamLegacy)); }

/// Running total of device allocations by purpose.
class MemoryLedger {
public:
    void add(const std::string& purpose, std::size_t bytes) {
        for (auto& [name, total] : entries_)
            if (name == purpose) {
                total += bytes;
                return;
            }
        entries_.emplace_back(purpose, bytes);
    }
    /// Replaces the total of `purpose` (for buffers that are reallocated as they grow).
    void set(const std::string& purpose, std::size_t bytes) {
        for (auto& [name, total] : entries_)
            if (name == purpose) {
                total = bytes;
                return;
            }
        entries_.emplace_back(purpose, bytes);
    }
    void clear() { entries_.clear(); }
    [[nodiscard]] std::size_t total() const {
        std::size_t sum = 0;
        for (const auto& e : entries_) sum += e.second;
        return sum;
    }
    [[nodiscard]] const std::vector<std::pair<std::string, std::size_t>>& entries() const { return entries_; }

private:
    std::vector<std::pair<std::string, std::size_t>> entries_;
};

template <typename T>
class DeviceArray {
public:
    DeviceArray() = default;
    DeviceArray(const DeviceArray&) = delete;
    DeviceArray& operator=(const DeviceArray&) = delete;
    DeviceArray(DeviceArray&& o) noexcept
        : ptr_(std::exchange(o.ptr_, nullptr)), size_(std::exchange(o.size_, 0)), budget_(std::exchange(o.budget_, nullptr)),
          device_(o.device_) {}
    DeviceArray& operator=(DeviceArray&& o) noexcept {
        if (this != &o) {
            release();
            ptr_ = std::exchange(o.ptr_, nullptr);
            size_ = std::exchange(o.size_, 0);
            budget_ = std::exchange(o.budget_, nullptr);
            device_ = o.device_;
        }
        return *this;
    }
    ~DeviceArray() { release(); }

    /// Allocates `count` elements (contents undefined), charged to `purpose` in `ledger` and to the
    /// thread's memory budget. Out of memory (the budget's or the device's) throws weft::Error with
    /// the bytes asked for, held and free, and leaves the array empty.
    void allocate(std::size_t count, MemoryLedger& ledger, const std::string& purpose) {
        release();
        if (count == 0) return;
        const std::size_t bytes = count * sizeof(T);
        WEFT_CUDA_CHECK(cudaGetDevice(&device_));
        DeviceMemoryBudget* budget = current_budget();
        if (budget != nullptr) budget->charge(device_, bytes, purpose);
        const cudaError_t err = cudaMalloc(reinterpret_cast<void**>(&ptr_), bytes);
        if (err != cudaSuccess) {
            ptr_ = nullptr;
            if (budget != nullptr) budget->refund(device_, bytes);
            (void)cudaGetLastError();  // not sticky: the context stays usable
            if (err == cudaErrorMemoryAllocation) throw_out_of_device_memory(device_, bytes, purpose, budget);
            throw_cuda_error(err, "cudaMalloc", __FILE__, __LINE__);
        }
        size_ = count;
        budget_ = budget;
        ledger.add(purpose, bytes);
    }
    /// Allocates and copies `host` in (synchronously: build time only).
    void upload(const std::vector<T>& host, MemoryLedger& ledger, const std::string& purpose) {
        allocate(host.size(), ledger, purpose);
        if (!host.empty()) {
            WEFT_CUDA_CHECK(cudaMemcpy(ptr_, host.data(), host.size() * sizeof(T), cudaMemcpyHostToDevice));
            wait_for_default_stream();
        }
    }
    void zero(cudaStream_t stream) {
        if (size_ > 0) WEFT_CUDA_CHECK(cudaMemsetAsync(ptr_, 0, size_ * sizeof(T), stream));
    }
    [[nodiscard]] T* get() const { return ptr_; }
    [[nodiscard]] std::size_t size() const { return size_; }
    [[nodiscard]] std::size_t bytes() const { return size_ * sizeof(T); }

private:
    void release() noexcept {
        if (ptr_ != nullptr) {
            cudaFree(ptr_);
            if (budget_ != nullptr) budget_->refund(device_, size_ * sizeof(T));
        }
        ptr_ = nullptr;
        size_ = 0;
        budget_ = nullptr;
    }
    T* ptr_ = nullptr;
    std::size_t size_ = 0;
    DeviceMemoryBudget* budget_ = nullptr;  // charged at allocate; outlives the array (the backend owns both)
    int device_ = 0;
};

/// Page-locked host memory for asynchronous copies (parameters in, stats out).
template <typename T>
class PinnedArray {
public:
    PinnedArray() = default;
    PinnedArray(const PinnedArray&) = delete;
    PinnedArray& operator=(const PinnedArray&) = delete;
    ~PinnedArray() {
        if (ptr_ != nullptr) cudaFreeHost(ptr_);
    }
    void allocate(std::size_t count) {
        if (ptr_ != nullptr) cudaFreeHost(ptr_);
        ptr_ = nullptr;
        size_ = count;
        if (count > 0) WEFT_CUDA_CHECK(cudaMallocHost(reinterpret_cast<void**>(&ptr_), count * sizeof(T)));
    }
    [[nodiscard]] T* get() const { return ptr_; }
    [[nodiscard]] std::size_t size() const { return size_; }
    T& operator[](std::size_t i) { return ptr_[i]; }

private:
    T* ptr_ = nullptr;
    std::size_t size_ = 0;
};

}  // namespace weft::cuda
